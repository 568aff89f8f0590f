"""Adaptive refinement as pure functions, against synthetic classifiers with known boundaries.

The classifiers stand in for the simulator: a point's class (and δ) is an exact function
of its start, so the true boundary is known and every located bracket can be checked
against it. The tolerance of each check is the refinement's own tolerance: a located
bracket has width <= tolerance and must contain the true boundary (no slack).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from fibersweep.analysis.boundaries import class_map
from fibersweep.config import Config, RefineSettings
from fibersweep.sweep.plan import make_tasks, sweep_settings
from fibersweep.sweep.refine import propose, stored_rounds

TOL_Y, TOL_T = 0.005, 0.5
EPS = 1e-9  # float rounding only: a boundary through a point is on either side of it
THETA = np.arange(-10.0, 10.001, 2.0)  # 11 columns
Y = np.round(np.arange(0.0, 1.0001, 0.1), 12)  # 11 rows


def tilted(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Above if y0 > 0.3 + 0.01 θ0, else Below (the boundary y_b(θ) = 0.3 + 0.01 θ)."""
    return np.where(y > 0.3 + 0.01 * t, "Above", "Below")


def _grid(length: float = 0.8) -> pd.DataFrame:
    t, y = np.meshgrid(THETA, Y, indexing="ij")
    return pd.DataFrame({"theta0": t.ravel(), "y0": y.ravel(), "length": length})


def _evaluate(p: pd.DataFrame, classify, delta=None, fails=None) -> pd.DataFrame:
    p = p.copy()
    t, y = p["theta0"].to_numpy(float), p["y0"].to_numpy(float)
    p["class"] = classify(t, y)
    p["delta"] = np.nan if delta is None else delta(t, y)
    p["status"] = "ok"
    if fails is not None:
        bad = fails(t, y)
        p.loc[bad, "status"] = "failed"
        p.loc[bad, "class"] = ""
    return p


def _refine(refine: RefineSettings, classify, delta=None, fails=None, cap: int = 60):
    """Run rounds until no proposal (at most ``cap``); (points, last proposal, rounds)."""
    pts = _evaluate(_grid(), classify, delta, fails)
    used = 0
    for rnd in range(1, cap + 1):
        prop = propose(pts, refine, refine.max_runs - used)
        if prop.new.empty:
            return pts, prop, rnd - 1
        used += len(prop.new)
        new = _evaluate(prop.new.drop(columns="group"), classify, delta, fails)
        pts = pd.concat([pts, new], ignore_index=True)
    raise AssertionError(f"refinement still proposing points after {cap} rounds")


def test_tilted_boundary_located_exactly_within_tolerance_with_few_runs():
    refine = RefineSettings(
        axes=["y0", "theta0"], tolerance={"y0": TOL_Y, "theta0": TOL_T}, max_runs=10_000
    )
    pts, prop, rounds = _refine(refine, tilted)
    b = prop.brackets
    assert (b["state"] == "located").all(), b
    by = b[b["axis"] == "y0"]
    # one located segment per θ column, each within tolerance of the truth
    assert sorted(by["theta0"]) == pytest.approx(THETA.tolist())
    truth = 0.3 + 0.01 * by["theta0"]
    assert ((by["hi"] - by["lo"]) <= TOL_Y + 1e-12).all()
    assert ((by["lo"] <= truth + EPS) & (truth <= by["hi"] + EPS)).all(), by
    assert (by["class_lo"] == "Below").all() and (by["class_hi"] == "Above").all()
    bt = b[b["axis"] == "theta0"]
    assert len(bt) > 0
    t_truth = (bt["y0"] - 0.3) / 0.01  # boundary crossing of each row
    assert ((bt["hi"] - bt["lo"]) <= TOL_T + 1e-12).all()
    assert ((bt["lo"] <= t_truth + EPS) & (t_truth <= bt["hi"] + EPS)).all(), bt
    # a uniform grid resolving the same: every θ column at step TOL_Y in y, every y row
    # at step TOL_T in θ
    uniform = len(THETA) * (round(1.0 / TOL_Y) + 1)
    assert len(pts) * 5 < uniform, (len(pts), uniform)
    assert rounds <= 6  # log2(0.1 / 0.005) = 4.3: 5 rounds on y, 2 on θ
    assert pts[["theta0", "y0"]].duplicated().sum() == 0


def test_thin_band_seen_by_the_grid_gets_both_boundaries():
    """Three classes: a band 0.38 < y0 < 0.41 holding the grid row 0.4."""

    def band(t, y):
        return np.where(y > 0.41, "Above", np.where(y > 0.38, "Pole-vaulting", "Below"))

    refine = RefineSettings(axes=["y0"], tolerance={"y0": TOL_Y}, max_runs=10_000)
    _, prop, _ = _refine(refine, band)
    b = prop.brackets
    assert (b["state"] == "located").all()
    for col, q in b.groupby("theta0"):
        assert len(q) == 2, (col, q)
        first, second = q.sort_values("lo").itertuples()
        assert first.lo <= 0.38 <= first.hi
        assert (first.class_lo, first.class_hi) == ("Below", "Pole-vaulting")
        assert second.lo <= 0.41 <= second.hi
        assert (second.class_lo, second.class_hi) == ("Pole-vaulting", "Above")


def test_failed_runs_stop_bisection_instead_of_spawning_points():
    """Every run within 0.002 of the boundary fails: brackets end stuck, the loop ends."""

    def fails(t, y):
        return np.abs(y - (0.3 + 0.01 * t)) < 0.002

    refine = RefineSettings(axes=["y0"], tolerance={"y0": 0.001}, max_runs=10_000)
    pts, prop, rounds = _refine(refine, tilted, fails=fails)
    b = prop.brackets
    assert rounds < 12
    assert (b["state"] == "stuck").any()
    assert set(b["state"]) <= {"stuck", "located"}
    # a stuck bracket's midpoint is a failed run
    failed = pts[pts["status"] == "failed"]
    for r in b[b["state"] == "stuck"].itertuples():
        at = np.isclose(failed["theta0"], r.theta0) & np.isclose(failed["y0"], r.y0)
        assert at.any(), r


def test_budget_caps_the_runs_and_spends_it_on_the_widest_brackets():
    refine = RefineSettings(axes=["y0"], tolerance={"y0": TOL_Y}, max_runs=15)
    pts, prop, _ = _refine(refine, tilted)
    assert len(pts) - len(_grid()) == 15
    assert (prop.brackets["state"] == "open").any()
    # one proposal at a time from a budget of 3: the widest brackets (grid spacing) first
    first = propose(_evaluate(_grid(), tilted), refine, 3)
    assert len(first.new) == 3


def test_delta_jump_is_bisected_only_when_asked():
    """One class everywhere, δ jumps from 0 to 1 at y0 = 0.62 (and varies smoothly)."""

    def one(t, y):
        return np.full(t.shape, "Above")

    def delta(t, y):
        return 0.05 * y + (y > 0.62)

    off = RefineSettings(axes=["y0"], tolerance={"y0": TOL_Y}, max_runs=1000)
    pts, prop, _ = _refine(off, one, delta)
    assert len(pts) == len(_grid()) and prop.brackets.empty
    on = off.model_copy(update={"delta_jump": 0.2})
    _, prop, _ = _refine(on, one, delta)
    b = prop.brackets
    assert len(b) == len(THETA) and (b["kind"] == "delta").all()
    assert ((b["lo"] <= 0.62) & (0.62 <= b["hi"]) & (b["hi"] - b["lo"] <= TOL_Y + 1e-12)).all()


def test_class_map_boundary_lies_in_the_located_brackets():
    """The figure's boundary (nearest-neighbour map) crosses each column inside its bracket."""
    refine = RefineSettings(axes=["y0"], tolerance={"y0": TOL_Y}, max_runs=10_000)
    pts, prop, _ = _refine(refine, tilted)
    pts = pts.assign(
        round=np.r_[np.zeros(len(_grid()), int), np.ones(len(pts) - len(_grid()), int)]
    )
    xs, ys, labels, names = class_map(pts, shape=(2001, 201))
    assert names == ["Above", "Below"]
    for r in prop.brackets.itertuples():
        i = int(np.argmin(np.abs(xs - r.theta0)))
        col = labels[:, i]
        k = int(np.flatnonzero(col[1:] != col[:-1])[0])  # the one change along this column
        y_edge = 0.5 * (ys[k] + ys[k + 1])
        pixel = ys[1] - ys[0]
        assert r.lo - pixel <= y_edge <= r.hi + pixel, (r, y_edge)
        assert np.sum(col[1:] != col[:-1]) == 1


def _cfg(refine: dict) -> Config:
    return Config.model_validate(
        {
            "sweep": {"theta0": [-4.0, 0.0, 4.0], "y0": [0.1, 0.3, 0.5, 0.7], "length": 0.8,
                      "refine": refine},
            "run": {"output": "unused"},
        }
    )  # fmt: skip


def test_stored_rounds_resume_a_partial_round_without_duplicates():
    """The rounds are a function of the stored runs: drop part of a round, get it back."""
    cfg = _cfg({"axes": ["y0"], "tolerance": {"y0": 0.01}, "max_runs": 200})
    settings = sweep_settings(cfg, "flowkey")
    grid = make_tasks(cfg, settings=settings)

    def row(t):
        return {"id": t.key, "status": "ok", "class": str(tilted(np.array(t.theta0),
                np.array(t.y0))), "delta": np.nan}  # fmt: skip

    stored = pd.DataFrame([row(t) for t in grid])
    history = []
    while True:  # what run_sweep does, with the synthetic classifier as the simulator
        extra, rnd, info = stored_rounds(cfg.sweep.refine, settings, grid, stored)
        todo = [t for t in extra if t.key not in set(stored["id"])]
        history.append(len(todo))
        if not todo:
            break
        stored = pd.concat([stored, pd.DataFrame([row(t) for t in todo])], ignore_index=True)
    assert info["stopped"] == "located" and info["open"] == 0
    assert stored["id"].is_unique and rnd == info["rounds"] >= 3
    # an interrupted last round: some of its runs never stored
    last = [t.key for t in extra if t.round == rnd]
    partial = stored[~stored["id"].isin(last[::2])]
    again, rnd2, _ = stored_rounds(cfg.sweep.refine, settings, grid, partial)
    assert rnd2 == rnd and [t.key for t in again] == [t.key for t in extra]
    assert {t.key for t in again} - set(partial["id"]) == set(last[::2])
    assert all(t.round >= 1 for t in again)
