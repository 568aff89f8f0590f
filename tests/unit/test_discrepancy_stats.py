"""Scores and calibrated tests of the discrepancy workflow, checked against analytic results."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import norm

from fibersweep.discrepancy.scores import (
    bootstrap_mean_ci,
    brier_fair_loo,
    crps_fair_loo,
    excess,
    holm,
    permutation_test,
    residual_matrix,
)


def _crps_normal(y: float) -> float:
    """Closed-form CRPS of N(0, 1) at y (Gneiting & Raftery 2007)."""
    return y * (2 * norm.cdf(y) - 1) + 2 * norm.pdf(y) - 1 / math.sqrt(math.pi)


def test_fair_crps_is_unbiased_for_small_ensembles():
    # 3-member ensembles of N(0,1): the mean fair CRPS at y = 0.7 equals the
    # closed form; tolerance 4 standard errors of the Monte Carlo mean.
    rng = np.random.default_rng(1)
    n = 40_000
    V = np.column_stack([np.full(n, 0.7), rng.standard_normal((n, 3))])
    s = crps_fair_loo(V)[:, 0]
    se = s.std() / math.sqrt(n)
    assert abs(s.mean() - _crps_normal(0.7)) < 4 * se


def test_fair_crps_large_ensemble_and_nan_members():
    rng = np.random.default_rng(2)
    members = rng.standard_normal(3000)
    V = np.concatenate([[1.3], members, [np.nan, np.nan]])[None, :]
    s = crps_fair_loo(V)
    # one 3000-member ensemble: sampling error of the CRPS ~ 0.02
    assert abs(s[0, 0] - _crps_normal(1.3)) < 0.03
    assert np.isnan(s[0, -1]) and np.isnan(s[0, -2])
    # fewer than two other members: undefined
    assert np.isnan(crps_fair_loo(np.array([[0.0, 1.0, np.nan]]))[0, 0])


def test_fair_brier_by_hand():
    # row: observed class 2, copies 0, 0, 2 -> others have f = (2/3, 0, 1/3, 0), k = 3
    codes = np.array([[2, 0, 0, 2, -1]])
    s = brier_fair_loo(codes, 4)
    f, o = np.array([2 / 3, 0, 1 / 3, 0]), np.array([0, 0, 1, 0])
    assert s[0, 0] == pytest.approx(np.sum((f - o) ** 2 - f * (1 - f) / 2))
    # copy 0 (class 0): others 2, 0, 2 -> f = (1/3, 0, 2/3, 0)
    f, o = np.array([1 / 3, 0, 2 / 3, 0]), np.array([1, 0, 0, 0])
    assert s[0, 1] == pytest.approx(np.sum((f - o) ** 2 - f * (1 - f) / 2))
    assert np.isnan(s[0, 4])
    # fewer than two other members: undefined
    assert np.isnan(brier_fair_loo(np.array([[1, 0, -1]]), 2)[0, 0])


@pytest.mark.parametrize("k", [2, 3, 8])
@pytest.mark.parametrize("p", [0.6, 0.9, 0.97])
def test_fair_brier_is_unbiased_and_proper_for_small_ensembles(k, p):
    # Exact expectation over k other members ~ Bernoulli(q) and an observation ~
    # Bernoulli(p): the fair score's mean equals the Brier score of q,
    # 2 (p - q)^2 + 2 p (1 - p) (to 1e-12), so it is least at q = p for every k.
    # The smoothed log-loss it replaces preferred q = 1 at p = 0.9, k = 8.
    def expected(q: float) -> float:
        total = 0.0
        for n1 in range(k + 1):  # others in category 1
            w = math.comb(k, n1) * q**n1 * (1 - q) ** (k - n1)
            row = np.array([[1] + [1] * n1 + [0] * (k - n1), [0] + [1] * n1 + [0] * (k - n1)])
            s = brier_fair_loo(row, 2)[:, 0]
            total += w * (p * s[0] + (1 - p) * s[1])
        return total

    qs = np.linspace(0.0, 1.0, 101)
    e = np.array([expected(q) for q in qs])
    assert np.allclose(e, 2 * (p - qs) ** 2 + 2 * p * (1 - p), atol=1e-12)
    assert qs[np.argmin(e)] == pytest.approx(p, abs=0.006)


def test_residuals_sum_to_zero_per_row():
    rng = np.random.default_rng(3)
    V = rng.standard_normal((5, 4))
    R = residual_matrix("delta", V)[:, :, 0]
    # member minus mean of the others: sum_j R_j = m/(m-1) * sum_j (V_j - mean) = 0
    assert np.allclose(R.sum(axis=1), 0.0, atol=1e-12)


def test_permutation_test_is_calibrated_under_the_null():
    # Exchangeable rows: the false-alarm rate at 5 % must lie in the 99.9 %
    # binomial band for 300 replicates, [0.015, 0.10].
    rng = np.random.default_rng(4)
    hits = 0
    reps = 300
    for _ in range(reps):
        V = rng.standard_normal((30, 5)) + rng.standard_normal((30, 1)) * 3
        p = permutation_test(crps_fair_loo(V), rng, n_perm=999).p_value
        hits += p <= 0.05
    assert 0.015 <= hits / reps <= 0.10


def test_permutation_test_detects_a_shift():
    rng = np.random.default_rng(5)
    V = rng.standard_normal((40, 5))
    V[:, 0] += 1.5  # observation biased by 1.5 sd
    t = permutation_test(crps_fair_loo(V), rng)
    assert t.p_value < 1e-3 and t.z > 3
    assert np.nanmean(excess(crps_fair_loo(V))) > 0


def test_holm_by_hand():
    adj = holm([0.01, 0.04, 0.03, 0.005])
    assert np.allclose(adj, [0.03, 0.06, 0.06, 0.02])


def test_bootstrap_interval_covers_the_mean():
    rng = np.random.default_rng(6)
    x = rng.normal(2.0, 1.0, 400)
    m, lo, hi = bootstrap_mean_ci(x, rng)
    # 95 % interval half-width ~ 1.96 / sqrt(400) ~ 0.1
    assert lo < m < hi
    assert abs(m - 2.0) < 0.2  # 4 standard errors
    assert 0.07 < (hi - lo) / 2 < 0.13
