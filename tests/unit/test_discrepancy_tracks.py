"""Track observables: station crossings against analytic tracks, the measured-side rules,
the simulated side derived by the same function, and the noise law of a derived value."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from fibersweep.analysis.observables import station_crossings, station_positions, track_values
from fibersweep.analysis.trajectory import Trajectory
from fibersweep.discrepancy.copies import NoiseModel
from fibersweep.discrepancy.measured import (
    measured_track_values,
    validate_trajectories,
    with_tracks,
)
from fibersweep.discrepancy.observables import OBSERVABLES, noise_draws, scored, track_observables
from fibersweep.discrepancy.schema import validate_measured
from fibersweep.discrepancy.simulate import frames, outcome_row
from fibersweep.errors import InputError
from fibersweep.fiber.effects.pillar_scale import scaled_track as nominal_track
from fibersweep.fiber.result import FiberStart, RunResult
from fibersweep.units import Geometry

GEO = Geometry()  # pillar x 1156.70 .. 1243.30 µm, base line y = 375 µm, h_obs 75 µm


def _straight(t: np.ndarray, u: float = 500.0, v: float = -20.0, w: float = 30.0):
    """x = 600 + u t, y = 420 + v t [µm], theta = 5 + w t [deg]: analytic crossings."""
    return 600.0 + u * t, 420.0 + v * t, 5.0 + w * t


def test_crossings_of_a_straight_track_are_exact():
    # irregular samples: linear interpolation of a linear track is exact (to rounding, 1e-9)
    t = np.sort(np.random.default_rng(0).uniform(0.0, 2.0, 300))
    x, y, th = _straight(t)
    s = np.array([1156.7, 1243.3, 1330.0])
    ts, ys, ths = station_crossings(t, x, y, th, s)
    t_exact = (s - 600.0) / 500.0
    np.testing.assert_allclose(ts, t_exact, rtol=0, atol=1e-9)
    np.testing.assert_allclose(ys, 420.0 - 20.0 * t_exact, rtol=0, atol=1e-9)
    np.testing.assert_allclose(ths, 5.0 + 30.0 * t_exact, rtol=0, atol=1e-9)


def test_crossing_of_a_curved_track_within_the_interpolation_bound():
    # y = A sin(k x) sampled every dx in x: linear interpolation errs by at most A k² dx² / 8
    amp, k, dx = 20.0, 2 * np.pi / 200.0, 5.0
    x = np.arange(600.0, 1500.0, dx)
    t = (x - 600.0) / 500.0
    y = 400.0 + amp * np.sin(k * x)
    s = np.array([1161.3, 1247.9, 1333.3])
    _, ys, _ = station_crossings(t, x, y, np.zeros_like(x), s)
    err = np.abs(ys - (400.0 + amp * np.sin(k * s)))
    assert (err <= amp * k**2 * dx**2 / 8.0 + 1e-12).all()


def test_a_station_not_reached_or_started_past_is_nan():
    t = np.linspace(0.0, 1.0, 50)
    x, y, th = _straight(t)  # x from 600 to 1100 µm: short of the pillar
    ts, ys, ths = station_crossings(t, x, y, th, np.array([700.0, 1156.7, 500.0]))
    assert np.isfinite([ts[0], ys[0], ths[0]]).all()
    assert np.isnan([ts[1], ys[1], ths[1], ts[2], ys[2], ths[2]]).all()
    assert all(math.isnan(v) for v in station_crossings(t[:1], x[:1], y[:1], th[:1], [700.0])[0])


def test_the_first_crossing_counts_and_angles_are_undirected():
    # the centre goes past 1000 µm, back, and past again: the first crossing is taken
    x = np.array([900.0, 1010.0, 990.0, 1100.0])
    t = np.arange(4.0)
    th = np.array([80.0, 100.0, 100.0, 100.0])  # directed angle through the vertical
    ts, _, ths = station_crossings(t, x, np.zeros(4), th, np.array([1000.0]))
    assert ts[0] == pytest.approx(100.0 / 110.0, abs=1e-12)
    assert ths[0] == pytest.approx(-(180.0 - (80.0 + 20.0 * 100.0 / 110.0)), abs=1e-9)
    # the same fiber tracked without a direction (angles in (-90, 90]) gives the same value
    _, _, und = station_crossings(t, x, np.zeros(4), np.array([80.0, -80.0, -80, -80]), [1000.0])
    assert und[0] == pytest.approx(ths[0], abs=1e-9)


def test_track_values_in_units_of_the_pillar():
    t = np.linspace(0.0, 2.0, 2001)
    x, y, th = _straight(t, v=0.0)  # y = 420 µm: (420 - 375) / 75 = 0.6 h_obs
    v = track_values(t, x, y, th, GEO, 1.0)
    xs = station_positions(GEO, GEO.pillar_base_length)
    assert xs[2] - xs[1] == pytest.approx(GEO.pillar_base_length)
    assert v["y_out"] == pytest.approx(0.6, abs=1e-12)
    assert v["t_transit"] == pytest.approx((xs[2] - xs[0]) / 500.0, abs=1e-9)
    assert v["theta_out"] == pytest.approx(5.0 + 30.0 * (xs[1] - 600.0) / 500.0, abs=1e-9)


def _run(cls: str, t: np.ndarray, length: float = 1.0) -> RunResult:
    x, y, th = _straight(t)
    n = len(t)
    traj = Trajectory(t, x, y, th, np.zeros((n, 2)), np.zeros((n, 2)), np.zeros(n), np.zeros(n),
                      np.zeros(n, dtype=bool))  # fmt: skip
    return RunResult(start=FiberStart(0.0, 0.6, length), status="ok", cls=cls, delta=0.0,
                     t_pass=1.0, trajectory=traj)  # fmt: skip


def _fibers(ids, classes, lengths) -> pd.DataFrame:
    return pd.DataFrame({"fiber_id": ids, "class": classes, "length": lengths})


def _track_table(ids, t) -> pd.DataFrame:
    x, y, th = _straight(t)
    return pd.concat(
        [pd.DataFrame({"fiber_id": i, "t": t, "x": x, "y": y, "theta": th}) for i in ids],
        ignore_index=True,
    )


def test_measured_and_simulated_sides_derive_identically():
    t = np.linspace(0.0, 2.0, 400)
    row = outcome_row(_run("Above", t, 1.2), GEO)
    measured = measured_track_values(_track_table(["a"], t), _fibers(["a"], ["Above"], [1.2]),
                                     GEO, "test")  # fmt: skip
    for name in track_observables():
        assert np.isfinite(row[name]) and row[name] == measured[name][0]
    # no geometry or a Trapping fiber: NaN (the NaN rule), as on the measured side
    assert all(math.isnan(outcome_row(_run("Above", t))[n]) for n in track_observables())
    assert all(math.isnan(outcome_row(_run("Trapping", t), GEO)[n]) for n in track_observables())


def test_trapping_tracks_may_stop_anywhere_others_must_cross_every_station():
    t_short = np.linspace(0.0, 1.0, 100)  # ends at x = 1100 µm, before the pillar
    t_full = np.linspace(0.0, 2.0, 200)
    traj = pd.concat([_track_table(["a"], t_full), _track_table(["b"], t_short)])
    out = measured_track_values(traj, _fibers(["a", "b"], ["Below", "Trapping"], [1.0, 1.0]),
                                GEO, "tracks.csv")  # fmt: skip
    assert np.isfinite(out.loc[0]).all() and out.loc[1].isna().all()
    with pytest.raises(InputError, match=r"tracks.csv: trajectories: the track of 1 fiber.*"
                       r"fiber_id b\).*channel frame"):  # fmt: skip
        measured_track_values(traj, _fibers(["a", "b"], ["Below", "Above"], [1.0, 1.0]), GEO,
                              "tracks.csv")  # fmt: skip


def test_tracks_for_only_some_fibers_is_an_error_naming_the_field():
    t = np.linspace(0.0, 2.0, 200)
    fibers = _fibers(["a", "b", "c"], ["Below"] * 3, [1.0] * 3)
    with pytest.raises(InputError, match=r"trajectories.fiber_id: no track for 2 of 3 fibers "
                       r"\(fiber_id b, c\)"):  # fmt: skip
        measured_track_values(_track_table(["a"], t), fibers, GEO, "t.csv")


def test_tracks_in_another_frame_are_caught():
    t = np.linspace(0.0, 2.0, 200)
    traj = _track_table(["a"], t)
    traj["x"] -= 1200.0  # pillar at the origin instead of the channel frame
    with pytest.raises(InputError, match="channel frame"):
        measured_track_values(traj, _fibers(["a"], ["Below"], [1.0]), GEO, "t.csv")


def test_with_tracks_adds_the_scored_track_observables():
    n = 4
    table = pd.DataFrame(
        {"fiber_id": list("abcd"), "theta0": [1.0, -2.0, 3.0, 4.0], "y0": [0.6] * n,
         "length": [1.0] * n, "class": ["Below"] * n}
    )  # fmt: skip
    data = validate_measured(table)
    t = np.linspace(0.0, 2.0, 200)
    traj = validate_trajectories(_track_table(list("abcd"), t), data.table, "t")
    got = with_tracks(data, traj, GEO)
    assert got.observed == ("class", *track_observables())
    assert set(scored()) & set(track_observables()) == set()  # not compared without tracks
    assert got.trajectories is traj and len(got.table) == n


def test_pillar_scale_tracks_follow_the_nominal_units_of_y_c():
    # the effect maps y/h in real-pillar units y' to nominal y' (1 + ε) - ε/3 (as y_c)
    eps = 0.1
    t = np.linspace(0.0, 2.0, 2001)
    run = _run("Below", t)
    scaled = nominal_track(run.trajectory, GEO.centroid, 1.0 + eps)
    y_sim = track_values(t, *[getattr(run.trajectory, c) for c in ("x", "y", "theta")], GEO, 1.0)
    y_real = track_values(t, scaled.x, scaled.y, scaled.theta, GEO, 1.0)
    # the stations are fixed in the channel, the track stretched: compare at one x instead
    xs = GEO.shape.bounds[2]
    x_sim = GEO.centroid[0] + (xs - GEO.centroid[0]) / (1.0 + eps)  # where it maps to xs
    _, y_at, _ = station_crossings(t, run.trajectory.x, run.trajectory.y, t, [x_sim])
    expect = float(GEO.y_over_h(y_at[0])) * (1.0 + eps) - eps / 3.0
    assert y_real["y_out"] == pytest.approx(expect, abs=1e-9)
    assert y_real["y_out"] != pytest.approx(y_sim["y_out"], abs=1e-3)


def test_noise_law_of_a_derived_position_matches_frame_noise():
    """Linear interpolation between two frames, each with error σ, at a uniform fraction f:
    sd = σ sqrt(E[(1-f)² + f²]) = σ sqrt(2/3) on a level track. Monte Carlo with 4000 tracks,
    within 4 %; the registry's y_out law (0.012 h_obs) is this for σ = 1 µm (0.0109 h_obs)
    plus the slope term of tilted tracks (measured 0.0115,
    scripts/studies/discrepancy/track_signatures.py)."""
    rng = np.random.default_rng(1)
    sigma, errs = 1.0, []
    for _ in range(4000):
        t0 = rng.uniform(0, 0.01)
        t = t0 + np.arange(0.0, 2.0, 0.01)  # 100 frames/s, random phase
        x, y, th = _straight(t, v=0.0)
        y = y + sigma * rng.standard_normal(t.size)
        _, ys, _ = station_crossings(t, x, y, th, [1243.3])
        errs.append(ys[0] - 420.0)
    assert np.std(errs) == pytest.approx(sigma * math.sqrt(2.0 / 3.0), rel=0.04)
    assert OBSERVABLES["y_out"].noise.sd * GEO.pillar_height == pytest.approx(0.9, abs=0.1)


def test_frames_and_track_noise_draws():
    t = np.linspace(0.0, 1.005, 300)
    run = _run("Below", t)
    f = frames(run.trajectory, 100.0)
    np.testing.assert_allclose(np.diff(f["t"]), 0.01, atol=1e-12)
    assert f["t"][-1] <= t[-1] and len(f["t"]) == 101
    np.testing.assert_allclose(f["x"], 600.0 + 500.0 * f["t"], atol=1e-9)
    assert frames(None, 100.0) is None
    # the track observables get their registry noise law in the copies, default sd unlisted
    nm = NoiseModel()
    assert "y_out" not in nm.as_dict() and nm.sd("y_out") == OBSERVABLES["y_out"].noise.sd
    out = pd.DataFrame([outcome_row(_run("Below", np.linspace(0, 2, 400)), GEO)] * 3)
    z = noise_draws([0], 3)
    noisy = nm.observe(out, z)
    np.testing.assert_allclose(noisy["y_out"], out["y_out"] + 0.012 * z["y_out"])
