"""Refinement of a pillar array's critical length (random starts): which lengths run next."""

from __future__ import annotations

import numpy as np
import pandas as pd

from fibersweep.sorting.lengths import LEVEL, length_brackets, propose_lengths


def _points(fractions: dict[float, list[float]], modes=None, group="s1") -> pd.DataFrame:
    rows = []
    for L, fs in fractions.items():
        for k, f in enumerate(fs):
            mode = (modes or {}).get((L, k), "displacement" if f > 0.5 else "zigzag")
            rows.append({"settings": group, "length": L, "status": "ok", "mode": mode,
                         "fraction": f})  # fmt: skip
    return pd.DataFrame(rows)


def _draw(count=3):
    def draw(group, length):
        rng = np.random.default_rng(int(length * 1000))
        return rng.uniform(-10, 10, count), rng.uniform(0, 1, count)

    return draw


def test_the_bracket_is_where_the_mean_fraction_crosses_one_half():
    pts = _points({4.0: [0.0, 0.1], 20.0: [0.2, 0.4], 40.0: [0.9, 0.8], 80.0: [0.95, 0.9]})
    b = length_brackets(pts)
    assert LEVEL == 0.5
    assert b[["lo", "hi", "length"]].values.tolist() == [[20.0, 40.0, 30.0]]
    assert b["class_lo"].item() == "0.300" and b["class_hi"].item() == "0.850"


def test_trapped_and_failed_runs_do_not_count_in_the_means():
    pts = _points({20.0: [0.2, 0.9], 40.0: [0.9, 0.8]}, modes={(20.0, 1): "trapped"})
    pts.loc[len(pts)] = {"settings": "s1", "length": 40.0, "status": "failed", "mode": None,
                         "fraction": np.nan}  # fmt: skip
    b = length_brackets(pts)  # 20 µm: 0.2 (the trapped 0.9 left out), 40 µm: 0.85
    assert b[["lo", "hi"]].values.tolist() == [[20.0, 40.0]]


def test_wide_brackets_get_the_midpoint_with_all_its_starts_within_the_budget():
    pts = pd.concat([
        _points({20.0: [0.2], 40.0: [0.9]}, group="a"),
        _points({10.0: [0.1], 60.0: [0.9]}, group="b"),
    ])  # fmt: skip
    prop = propose_lengths(pts, tolerance=5.0, budget=4, draw=_draw(3))
    # the widest bracket relative to the tolerance first (b: 50 µm), then a does not fit
    assert set(prop.new["group"]) == {"b"} and len(prop.new) == 3
    assert prop.new["length"].unique().tolist() == [35.0]
    assert sorted(prop.brackets["state"]) == ["open", "open"]
    more = propose_lengths(pts, tolerance=5.0, budget=6, draw=_draw(3))
    assert sorted(more.new["length"].unique().tolist()) == [30.0, 35.0]


def test_a_located_bracket_stops_and_a_run_midpoint_without_a_mean_is_stuck():
    located = _points({20.0: [0.2], 24.0: [0.9]})
    prop = propose_lengths(located, tolerance=5.0, budget=100, draw=_draw())
    assert prop.new.empty and prop.brackets["state"].tolist() == ["located"]
    stuck = _points({20.0: [0.2], 40.0: [0.9], 30.0: [0.7]}, modes={(30.0, 0): "trapped"})
    prop = propose_lengths(stuck, tolerance=5.0, budget=100, draw=_draw())
    assert prop.new.empty and prop.brackets["state"].tolist() == ["stuck"]


def test_no_crossing_proposes_nothing():
    prop = propose_lengths(_points({20.0: [0.8], 40.0: [0.9]}), 5.0, 100, _draw())
    assert prop.new.empty and prop.brackets.empty
