"""Calibrated tests on leave-one-out score matrices, multiple-testing correction, bootstrap.

The null hypothesis of every gap test is exchangeability within each fiber:
the observation is one more draw of what the model's jittered copies are
(same start noise, same measurement noise). Then column 0 of a score matrix
is a uniformly random pick among the row's columns, independently per fiber,
and the exact conditional null distribution of any statistic of column 0 is
obtained by drawing, for every fiber, a random column instead. This is the
noise floor: it comes from the model's own copies, not from a tuned threshold.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "PermTest",
    "boot_p",
    "bootstrap_mean_ci",
    "conformal_quantile",
    "excess",
    "holm",
    "permutation_test",
]


@dataclass(frozen=True)
class PermTest:
    """One-sided permutation test of ``nanmean_i S[i, 0]`` being too large.

    Attributes
    ----------
    statistic : float
        Observed mean score (column 0), NaN if no fiber is defined.
    null_mean, null_sd : float
        Mean and standard deviation of the permutation distribution.
    p_value : float
        (1 + #{null >= observed}) / (1 + B); 1.0 when undefined.
    z : float
        (statistic - null_mean) / null_sd (0 when the null has no spread).
    n : int
        Fibers with a defined observed score.
    """

    statistic: float
    null_mean: float
    null_sd: float
    p_value: float
    z: float
    n: int


def permutation_test(
    S: np.ndarray, rng: np.random.Generator, n_perm: int = 4999, two_sided: bool = False
) -> PermTest:
    """Test whether column 0 of ``S`` scores worse than a random column per row.

    Parameters
    ----------
    S : ndarray, shape (n, m)
        Leave-one-out scores (or signed residuals with ``two_sided``), NaN where undefined.
    rng : numpy.random.Generator
    n_perm : int
        Random designations drawn.
    two_sided : bool
        Test |statistic - null_mean| instead of the upper tail.
    """
    S = np.asarray(S, dtype=np.float64)
    n, m = S.shape
    defined = np.isfinite(S[:, 0])
    if n == 0 or not defined.any() or m < 2:
        return PermTest(np.nan, np.nan, np.nan, 1.0, 0.0, 0)
    obs = float(np.nanmean(S[:, 0]))
    pick = rng.integers(0, m, size=(n_perm, n))
    draws = S[np.arange(n)[None, :], pick]
    with np.errstate(invalid="ignore"):
        cnt = np.isfinite(draws).sum(axis=1)
        null = np.where(cnt > 0, np.nansum(draws, axis=1) / np.maximum(cnt, 1), np.nan)
    null = null[np.isfinite(null)]
    mu = float(null.mean())
    sd = float(null.std(ddof=1)) if len(null) > 1 else 0.0
    if two_sided:
        hits = np.abs(null - mu) >= abs(obs - mu) - 1e-12 * max(1.0, abs(obs))
    else:
        hits = null >= obs - 1e-12 * max(1.0, abs(obs))
    p = (1.0 + hits.sum()) / (1.0 + len(null))
    z = (obs - mu) / sd if sd > 0 else 0.0
    return PermTest(obs, mu, sd, float(p), float(z), int(defined.sum()))


def holm(p_values: np.ndarray | list[float]) -> np.ndarray:
    """Holm-Bonferroni adjusted p-values (controls the family-wise error rate).

    Parameters
    ----------
    p_values : array_like, shape (k,)

    Returns
    -------
    ndarray, shape (k,)
        Adjusted p-values in the input order; reject where adjusted <= alpha.
    """
    p = np.asarray(p_values, dtype=np.float64)
    k = len(p)
    order = np.argsort(p)
    adj_sorted = np.maximum.accumulate((k - np.arange(k)) * p[order])
    out = np.empty(k)
    out[order] = np.minimum(adj_sorted, 1.0)
    return out


def bootstrap_mean_ci(
    x: np.ndarray, rng: np.random.Generator, n_boot: int = 2000, level: float = 0.95
) -> tuple[float, float, float]:
    """Mean of the finite entries of ``x`` and its percentile bootstrap interval.

    Returns
    -------
    (mean, lo, hi) : tuple of float
        NaNs when ``x`` has no finite entry.
    """
    v = np.asarray(x, dtype=np.float64)
    v = v[np.isfinite(v)]
    if len(v) == 0:
        return (np.nan, np.nan, np.nan)
    idx = rng.integers(0, len(v), size=(n_boot, len(v)))
    means = v[idx].mean(axis=1)
    a = (1.0 - level) / 2.0
    return float(v.mean()), float(np.quantile(means, a)), float(np.quantile(means, 1.0 - a))


def excess(S: np.ndarray) -> np.ndarray:
    """Per-fiber excess score: observed minus the row's mean over all members.

    Its expectation is zero under the null; positive means the observation
    sits worse than the model's own copies. Shape (n,), NaN where undefined.
    """
    S = np.asarray(S, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        cnt = np.isfinite(S).sum(axis=1)
        mean = np.where(cnt > 0, np.nansum(S, axis=1) / np.maximum(cnt, 1), np.nan)
    return S[:, 0] - mean


def boot_p(d: np.ndarray, rng: np.random.Generator, n_boot: int = 4000) -> float:
    """One-sided bootstrap p-value of mean(d) <= 0 over the finite entries of d."""
    d = np.asarray(d, dtype=np.float64)
    d = d[np.isfinite(d)]
    if len(d) == 0:
        return 1.0
    means = d[rng.integers(0, len(d), size=(n_boot, len(d)))].mean(axis=1)
    return float((1 + np.sum(means <= 0.0)) / (1 + n_boot))


def conformal_quantile(scores: np.ndarray, level: float = 0.95) -> float:
    """Split-conformal quantile: the k-th smallest of n scores, k = ceil((n + 1) level).

    If a new score is exchangeable with the n calibration scores, it is at most
    this value with probability at least ``level`` (and below (k + 1) / (n + 1)
    when the scores have no ties). Used to calibrate the score test's critical
    value on simulated data sets (:data:`fit.CRIT_SCALE`).

    Parameters
    ----------
    scores : ndarray, shape (n,)
    level : float

    Returns
    -------
    float
        inf when k > n (too few scores for the level).
    """
    s = np.sort(np.asarray(scores, dtype=float))
    k = int(np.ceil((len(s) + 1) * level))
    return float(s[k - 1]) if k <= len(s) else float("inf")
