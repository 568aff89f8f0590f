"""Localisation of a gap: the shallow tree finds a planted region."""

from __future__ import annotations

import numpy as np

from fibersweep.discrepancy.localise import binned_map, find_region


def test_tree_finds_planted_band():
    rng = np.random.default_rng(0)
    n = 200
    X = np.column_stack(
        [
            rng.uniform(-10, 10, n),
            rng.uniform(0, 1, n),
            rng.uniform(0.5, 1.4, n),
            rng.random(n) < 0.5,
        ]
    ).astype(float)
    inside = (X[:, 1] >= 0.3) & (X[:, 1] < 0.5)
    excess = rng.normal(0, 0.1, n) + 1.0 * inside
    r = find_region(X, excess, depth=2)
    lo, hi = r.bounds["y0"]
    # split thresholds fall between samples: within 0.05 of the planted edges
    assert abs(lo - 0.3) < 0.05 and abs(hi - 0.5) < 0.05
    assert r.mean_excess > 0.8 and r.share > 0.8
    assert "y0" in r.describe()


def test_binned_map_means_and_counts():
    x = np.array([0.1, 0.2, 0.9, np.nan])
    y = np.array([0.1, 0.1, 0.9, 0.5])
    v = np.array([1.0, 3.0, 5.0, 7.0])
    m, c = binned_map(x, y, v, np.array([0, 0.5, 1]), np.array([0, 0.5, 1]))
    assert m[0, 0] == 2.0 and c[0, 0] == 2 and m[1, 1] == 5.0 and np.isnan(m[0, 1])
