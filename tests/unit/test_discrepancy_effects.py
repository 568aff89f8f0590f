"""Nuisance effects of the discrepancy library (inlet_speed, start_noise, pillar_scale)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.config.flow import FlowSettings
from fibersweep.errors import InputError
from fibersweep.fiber.effects import build_effects
from fibersweep.fiber.result import FiberStart, RunResult


def test_start_noise_has_the_stated_spread():
    eff = build_effects({"start_noise": 2.0}).effects[0]
    rng = np.random.default_rng(0)
    s0 = FiberStart(1.0, 0.4, 1.0)
    draws = (eff.transform_start(s0, rng) for _ in range(4000))
    out = np.array([[s.theta0, s.y0, s.length] for s in draws])
    sd = out.std(axis=0)
    # k = 2 times (1 deg, 0.01, 0.01); 4000 draws: sd within 5 %
    np.testing.assert_allclose(sd, [2.0, 0.02, 0.02], rtol=0.05)
    # unbiased: means within 4 standard errors
    assert np.all(np.abs(out.mean(axis=0) - [1.0, 0.4, 1.0]) < 4 * sd / math.sqrt(4000))


def test_pillar_scale_is_a_change_of_units_about_the_centroid():
    eps = 0.1
    eff = build_effects({"pillar_scale": eps}).effects[0]
    rng = np.random.default_rng(0)
    # the centroid (y/h = 1/3) is the same point in both unit systems
    assert eff.transform_start(FiberStart(0.0, 1 / 3, 1.0), rng).y0 == pytest.approx(1 / 3)
    s = eff.transform_start(FiberStart(0.0, 0.8, 1.1), rng)
    assert s.length == pytest.approx(1.1 / 1.1)
    # a lateral position maps back: nominal y -> real y' -> nominal via the result hook,
    # which also reports the start that was asked for
    asked = FiberStart(0.0, 0.8, 1.1)
    res = RunResult(start=s, status="ok", cls="Above", delta=0.2, contact=True, y_c=s.y0)
    geometry = FlowSettings().geometry.to_geometry()
    back = eff.transform_result(res, asked, geometry)
    assert back.y_c == pytest.approx(0.8)
    assert back.delta == pytest.approx(0.2 * (1 + eps))
    assert back.start == asked


def test_simulate_reports_pillar_scale_runs_in_nominal_units(small_field):
    # a run with pillar_scale = ε is the nominal run at the transformed start, its δ
    # rescaled by 1 + ε and its positions [µm] stretched by 1 + ε about the pillar
    # centroid (the effect owns every unit change); simulate() returns the nominal start
    from fibersweep.config.fiber import FiberSettings, RecordSettings
    from fibersweep.fiber.run import simulate

    eps, asked = 0.1, FiberStart(2.0, 0.9, 0.8)
    rec = RecordSettings(trajectories=True, samples=50)
    scaled = simulate(small_field, FiberSettings(effects={"pillar_scale": eps}, record=rec), asked)
    moved = build_effects({"pillar_scale": eps}).effects[0].transform_start(asked, None)
    plain = simulate(small_field, FiberSettings(record=rec), moved)
    assert scaled.start == asked and plain.start == moved
    assert scaled.delta == pytest.approx(plain.delta * (1 + eps), rel=1e-12)
    cx, cy = small_field.geometry.centroid
    # same arithmetic on the same numbers: exact
    assert scaled.x_f == cx + (1 + eps) * (plain.x_f - cx)
    assert scaled.y_f == cy + (1 + eps) * (plain.y_f - cy)
    np.testing.assert_array_equal(scaled.trajectory.y, cy + (1 + eps) * (plain.trajectory.y - cy))
    np.testing.assert_array_equal(scaled.trajectory.t, plain.trajectory.t)
    np.testing.assert_array_equal(scaled.trajectory.theta, plain.trajectory.theta)


def test_out_of_range_values_name_the_effect():
    with pytest.raises(InputError, match="effects.inlet_speed"):
        build_effects({"inlet_speed": -1.5})
    with pytest.raises(InputError, match="effects.pillar_scale"):
        build_effects({"pillar_scale": 0.7})
    with pytest.raises(InputError, match="effects.start_noise"):
        build_effects({"start_noise": -1.0})


def test_inlet_speed_scales_time_and_keeps_the_path(coarse_field):
    """Stokes flow: speed x (1 + eps) leaves the path and divides every time by 1 + eps."""
    from fibersweep.config.fiber import FiberSettings
    from fibersweep.fiber.run import simulate

    start = FiberStart(-3.0, 0.45, 0.9)  # touches the pillar
    base = simulate(coarse_field, FiberSettings(), start)
    fast = simulate(coarse_field, FiberSettings(effects={"inlet_speed": 0.25}), start)
    assert base.status == fast.status == "ok" and base.cls == fast.cls
    # adaptive steps differ slightly between the runs: path to 1e-3 h, time to 1 %
    assert fast.delta == pytest.approx(base.delta, abs=1e-3)
    assert fast.t_pass * 1.25 == pytest.approx(base.t_pass, rel=0.01)
