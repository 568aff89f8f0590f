"""The band-pass study's planning and reading (scripts/studies/flexible/bandpass_map.py and
bandpass_tables.py).

The driver's runs are studies; what is tested here is the arithmetic that decides how
many more starts a point gets and which array scale a pair of edges follows.
"""

from __future__ import annotations

import argparse
import importlib
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

STUDY = Path(__file__).parents[2] / "scripts" / "studies" / "flexible"


@pytest.fixture(scope="module")
def bm():
    """The driver, imported as its command line runs it: beside bandpass_tables."""
    sys.path.insert(0, str(STUDY))
    try:
        yield importlib.import_module("bandpass_map")
    finally:
        sys.path.remove(str(STUDY))


@pytest.fixture(scope="module")
def bt(bm):
    return sys.modules["bandpass_tables"]


def _args(**kw) -> argparse.Namespace:
    base = {"moduli": None, "target_se": 0.05, "trap_se": 0.1, "max_count": 40,
            "refine_tol": 6.0, "refine_count": 12}  # fmt: skip
    return argparse.Namespace(**{**base, **kw})


def _point(E, L, runs, moving, se):
    trapped = (runs - moving) / runs
    return {"E": E, "length": L, "runs": runs, "moving": moving, "fraction_se": se,
            "trapped": trapped}  # fmt: skip


@pytest.mark.parametrize("moving,se", [(6, 0.1), (6, 0.2), (12, 0.07), (5, 0.06), (20, 0.051)])
def test_more_starts_reach_the_target_standard_error(bm, moving, se):
    """The starts a point gets bring the standard error of its mean f to the target.

    The spread of f is taken as measured (sd = se √moving); with the planned count
    and no trapping the new standard error sd / √(moving + count) is at most the
    target (0.05), unless the cap of 40 runs binds, when the count is the cap's rest.
    """
    table = pd.DataFrame([_point(1e4, 40.0, moving, moving, se)])
    runs = pd.DataFrame({"E": [1e4] * moving, "length": [40.0] * moving, "status": "ok",
                         "mode": "zigzag", "fraction": 0.5})  # fmt: skip
    plan = bm.more_plan(table, runs, _args())
    assert len(plan) == 1
    count = int(plan["count"].iloc[0])
    sd = se * math.sqrt(moving)
    if moving + count < 40:
        assert sd / math.sqrt(moving + count) <= 0.05
    else:
        assert moving + count == 40


def test_more_starts_skip_points_within_the_target_and_correct_for_trapping(bm):
    """se ≤ target: nothing; half the runs trapped: about twice the starts; too few
    moving runs for a standard error: ``refine_count`` starts (no cap binds: 100 runs)."""
    table = pd.DataFrame([
        _point(1e4, 20.0, 6, 6, 0.04),
        _point(1e4, 40.0, 12, 6, 0.1),
        _point(1e4, 60.0, 6, 6, 0.1),
        _point(1e4, 80.0, 6, 1, math.nan),
    ])  # fmt: skip
    runs = pd.DataFrame({"E": 1e4, "length": [20.0, 40.0, 60.0, 80.0], "status": "ok",
                         "mode": "zigzag", "fraction": 0.0})  # fmt: skip
    plan = bm.more_plan(table, runs, _args(max_count=100)).set_index("length")["count"]
    assert 20.0 not in plan.index
    assert plan[40.0] == 48  # 21 moving starts needed, half of them trap: 42, to a bucket
    assert plan[60.0] == 24  # 21 needed, rounded up to a bucket
    assert plan[80.0] == 12


def test_more_refines_a_located_crossing_and_only_a_located_one(bm):
    """A bracket of f = 1/2 whose two lengths meet the target gets its midpoint; one
    whose lengths do not, or that is narrower than the tolerance, does not."""
    rng = np.random.default_rng(0)
    rows, pts = [], []
    for E, lengths, se in ((1e4, (30.0, 50.0), 0.03), (2e4, (30.0, 50.0), 0.2),
                           (3e4, (30.0, 34.0), 0.03)):  # fmt: skip
        for L, f in zip(lengths, (0.2, 0.8), strict=True):
            pts.append(_point(E, L, 30, 30, se))
            for _ in range(30):
                rows.append({"E": E, "length": L, "status": "ok", "mode": "displacement",
                             "fraction": f + 0.01 * rng.standard_normal()})  # fmt: skip
    plan = bm.more_plan(pd.DataFrame(pts), pd.DataFrame(rows), _args(max_count=30))
    assert plan[["E", "length", "count"]].values.tolist() == [[1e4, 40.0, 12]]


def test_pairs_name_the_scale_an_edge_follows(bt):
    """G1 and G5 differ in period_x only (80 → 120 µm). An edge 1.5 × longer in G5
    follows the period: z for period_x is 0 and for the gap (unchanged) and the
    bending length (unchanged) (1.5 − 1) / se = 10 with se 0.05."""
    edges = pd.DataFrame([
        {"geometry": "G1", "E": 3e4, "edge": "lower", "critical": 50.0, "se": 0.0,
         "per_bending_length": 5.0},
        {"geometry": "G5", "E": 3e4, "edge": "lower", "critical": 75.0, "se": 75.0 * 0.05 / 1.5,
         "per_bending_length": 7.5},
        {"geometry": "G0", "E": 3e4, "edge": "other", "critical": 10.0, "se": 1.0,
         "per_bending_length": 1.0},
    ])  # fmt: skip
    p = bt.pairs_table(edges)
    assert len(p) == 1
    r = p.iloc[0]
    assert (r["a"], r["b"], r["changed"]) == ("G1", "G5", "period_x")
    assert r["ratio"] == pytest.approx(1.5) and r["ratio_se"] == pytest.approx(0.05)
    assert r["z_period_x"] == pytest.approx(0.0, abs=1e-12)
    assert r["z_gap"] == pytest.approx(10.0) and r["z_bending_length"] == pytest.approx(10.0)


def test_more_configs_are_valid_sweeps_of_new_draws(bm, tmp_path):
    """Each (E, count) of a plan becomes one valid config (the schema accepts it) with a
    single stiffness, the plan's lengths, a seed after the last used one, its own folder
    ``<geometry>+s<seed>``, and starts that differ from the map's (seed 0) at the same
    length: independent draws, never the map's runs again."""
    from fibersweep.config.loading import parse_config
    from fibersweep.sweep.draws import start_points

    args = argparse.Namespace(fractions=[0.5, 1.0], moduli=[1e4, 3e4], count=4, seed=0,
                              rows=20, spacing=0.5, contact="rough", time_scale=1.0,
                              refine_runs=0, refine_tol=4.0, cache="c", out=str(tmp_path),
                              tag="")  # fmt: skip
    base = bm.config_of("G1", args, 1)
    plan = pd.DataFrame({"E": [1e4, 1e4, 3e4], "length": [40.0, 80.0, 60.0],
                         "count": [8, 8, 12]})  # fmt: skip
    todo = bm._more_configs(tmp_path, "G1", plan, base, last_seed=3)
    seeds = sorted(t[2] for t in todo)
    assert seeds == [4, 5]
    for _, _geom, seed, cfg in todo:
        cfg_ok = parse_config(cfg)
        assert cfg["run"]["output"] == str(tmp_path / f"G1+s{seed}")
        assert len(cfg["sweep"]["fiber.young_modulus"]) == 1
        ts, ys, Ls = start_points(cfg_ok)
        assert len(ts) == cfg["sweep"]["random"]["count"] * len(cfg["sweep"]["length"])
        same_lengths = {**base["sweep"], "length": cfg["sweep"]["length"]}
        old = start_points(parse_config({**base, "sweep": same_lengths}))
        new_starts = set(zip(ts.round(9), ys.round(9), strict=True))
        assert not new_starts & set(zip(old[0].round(9), old[1].round(9), strict=True))


def test_fits_recover_a_power_law_and_keep_band_edges_apart(bt):
    """Edges exactly ∝ E^(1/4) with 2 % errors give β = 0.25 (to 1e-9), z_quarter = 0,
    χ² = 0; a cut-off without an upper edge (E = 1e5) is in ``power_law`` only."""
    moduli = [1e4, 2e4, 4e4, 8e4]
    rows = []
    for e in moduli:
        for edge, c0 in (("lower", 50.0), ("upper", 90.0)):
            c = c0 * (e / 1e4) ** 0.25
            rows.append({"geometry": "G1", "E": e, "edge": edge, "critical": c, "se": 0.02 * c})
    rows.append({"geometry": "G1", "E": 1e5, "edge": "lower", "critical": 30.0, "se": 1.0})
    fits = bt.fits_table(pd.DataFrame(rows)).set_index(["kind", "edge"])
    band = fits.loc[("power_law_band", "lower")]
    assert band["beta"] == pytest.approx(0.25, abs=1e-9)
    assert band["z_quarter"] == pytest.approx(0.0, abs=1e-6) and band["points"] == 4
    assert band["chi2_dof"] == pytest.approx(0.0, abs=1e-12)
    assert fits.loc[("power_law", "lower")]["points"] == 5
    assert fits.loc[("power_law_band", "upper")]["beta"] == pytest.approx(0.25, abs=1e-9)


def test_more_starts_measure_a_trapped_share(bm):
    """Four of six trapped, f known (se 0.01): runs to bring the trapped share's binomial
    error to 0.1, p(1 − p)/0.1² = 23 in all (17 more, bucket 24)."""
    table = pd.DataFrame([_point(1e4, 40.0, 6, 2, 0.01)])
    runs = pd.DataFrame({"E": [1e4] * 6, "length": 40.0, "status": "ok", "mode": "trapped",
                         "fraction": math.nan})  # fmt: skip
    plan = bm.more_plan(table, runs, _args(max_count=100))
    assert plan["count"].tolist() == [24]
    assert bm.more_plan(table, runs, _args(max_count=100, trap_se=0.0)).empty
