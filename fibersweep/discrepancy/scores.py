"""Per-fiber scores of an observation against model copies, and the tests on them.

Scores
------
Everything here works on a value matrix ``V`` of shape (n, m): row i is fiber
i, column 0 its observed value and columns 1..m-1 the model's jittered copies
(NaN / -1 where undefined, e.g. δ of a trapped fiber). For each entry the
*leave-one-out* score of ``V[i, j]`` against the other members of row i is
computed, giving a score matrix ``S`` of the same shape.

Scores (lower is better, all proper):

- continuous observables, on their scoring scale (``Observable.transform``, e.g.
  log t_pass): the *fair* CRPS of an m-member ensemble (Ferro 2014),
  ``mean_k |x_k - y| - sum_{k != l} |x_k - x_l| / (2 m (m - 1))``, unbiased for
  the CRPS of the distribution the members come from;
- categorical observables (kinds class and binary: class, contact): the *fair*
  Brier score of an m-member ensemble (Ferro 2014), ``sum_c (f_c - o_c)^2 -
  f_c (1 - f_c) / (m - 1)`` with f_c the members' frequency of category c and
  o_c the one-hot observation, unbiased for the Brier score of the
  distribution the members come from.

Both are unbiased at every ensemble size, so comparing two models on a few
copies each favours the one whose outcome distribution is right, whatever its
spread (a biased score, such as the log-loss of a smoothed frequency, favours
copies sharper than the truth, and fits effects that spread outcomes too small).

Tests
-----
The null hypothesis of every gap test is exchangeability within each fiber:
the observation is one more draw of what the model's jittered copies are
(same start noise, same measurement noise). Then column 0 of a score matrix
is a uniformly random pick among the row's columns, independently per fiber,
and the exact conditional null distribution of any statistic of column 0 is
obtained by drawing, for every fiber, a random column instead
(:func:`permutation_test`). This is the noise floor: it comes from the model's
own copies, not from a tuned threshold. Holm's correction and bootstrap
intervals and p-values complete the toolbox.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fibersweep.discrepancy.observables import OBSERVABLES, Observable

__all__ = [
    "PermTest",
    "boot_p",
    "bootstrap_mean_ci",
    "brier_fair_loo",
    "crps_fair_loo",
    "excess",
    "holm",
    "permutation_test",
    "residual_matrix",
    "score_matrix",
    "transform",
]


def _observable(name: str) -> Observable:
    try:
        return OBSERVABLES[name]
    except KeyError:
        raise ValueError(f"unknown observable {name!r}; valid: {', '.join(OBSERVABLES)}") from None


def transform(name: str, values: np.ndarray) -> np.ndarray:
    """Values on the scale observable ``name`` is scored on (e.g. log time to pass)."""
    return _observable(name).transform(np.asarray(values, dtype=np.float64))


def crps_fair_loo(V: np.ndarray) -> np.ndarray:
    """Leave-one-out fair CRPS of every member against the rest of its row.

    Parameters
    ----------
    V : ndarray, shape (n, m), float
        NaN marks an undefined value (excluded from the ensemble).

    Returns
    -------
    ndarray, shape (n, m)
        NaN where ``V`` is NaN or fewer than two other members are defined.
    """
    V = np.asarray(V, dtype=np.float64)
    if V.ndim != 2:
        raise ValueError(f"V must be 2D (fibers, members), got shape {V.shape}")
    fin = np.isfinite(V)
    D = np.abs(V[:, :, None] - V[:, None, :])
    both = fin[:, :, None] & fin[:, None, :]
    D = np.where(both, D, 0.0)
    cnt = fin.sum(axis=1, keepdims=True).astype(np.float64)  # (n, 1)
    row_j = D.sum(axis=2)  # sum_l |V_j - V_l| over defined l
    pairs = D.sum(axis=(1, 2))[:, None]  # ordered-pair sum over defined members
    m_other = cnt - 1.0  # members left when j (defined) is held out
    with np.errstate(divide="ignore", invalid="ignore"):
        term1 = row_j / m_other
        pairs_other = pairs - 2.0 * row_j
        term2 = pairs_other / (2.0 * m_other * (m_other - 1.0))
        S = term1 - term2
    S[~fin | (m_other < 2.0)] = np.nan
    return S


def brier_fair_loo(codes: np.ndarray, n_categories: int) -> np.ndarray:
    """Leave-one-out fair Brier score of every member's category against the rest of its row.

    Parameters
    ----------
    codes : ndarray, shape (n, m), int
        Category 0..n_categories-1, or -1 where undefined (failed run).
    n_categories : int

    Returns
    -------
    ndarray, shape (n, m)
        ``sum_c (f_c - o_c)^2 - f_c (1 - f_c) / (k - 1)`` over the k defined
        other members (f_c their frequency of c, o_c the member's one-hot
        category), in [-1/(k-1), 2]; NaN where the code is -1 or fewer than two
        other members are defined.
    """
    c = np.asarray(codes)
    if c.ndim != 2:
        raise ValueError(f"codes must be 2D (fibers, members), got shape {c.shape}")
    fin = c >= 0
    onehot = np.stack([(c == q) & fin for q in range(n_categories)], axis=2).astype(np.float64)
    others = fin.sum(axis=1)[:, None, None].astype(np.float64) - 1.0  # k per member of a row
    with np.errstate(divide="ignore", invalid="ignore"):
        f = (onehot.sum(axis=1, keepdims=True) - onehot) / others  # (n, m, K)
        S = ((f - onehot) ** 2 - f * (1.0 - f) / (others - 1.0)).sum(axis=2)
    S[~fin | (others[:, :, 0] < 2.0)] = np.nan
    return S


def _codes(V: np.ndarray) -> np.ndarray:
    v = np.asarray(V, dtype=np.float64)
    return np.where(np.isfinite(v), v, -1).astype(np.int64)


def score_matrix(name: str, V: np.ndarray) -> np.ndarray:
    """Leave-one-out score matrix of one observable (see module docstring).

    Parameters
    ----------
    name : str
        An observable of the registry. Categorical ones hold category indices
        as floats (:meth:`Observable.values`) with NaN where undefined.
    V : ndarray, shape (n, m)
        Column 0 observed, the rest model copies.
    """
    o = _observable(name)
    if o.categorical:
        return brier_fair_loo(_codes(V), o.width)
    return crps_fair_loo(transform(name, V))


def residual_matrix(name: str, V: np.ndarray) -> np.ndarray:
    """Signed leave-one-out residuals: member minus the mean of the others.

    Returns
    -------
    ndarray, shape (n, m, c)
        c = number of categories for categorical observables (one-hot minus
        leave-one-out frequency), 1 otherwise. NaN where undefined.
    """
    o = _observable(name)
    if o.categorical:
        k = o.width
        c = _codes(V)
        fin = c >= 0
        onehot = np.stack([(c == q) for q in range(k)], axis=2).astype(np.float64)
        tot = onehot.sum(axis=1, keepdims=True)
        n_def = fin.sum(axis=1)[:, None, None].astype(np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            loo = (tot - onehot) / (n_def - 1.0)
        R = onehot - loo
        R[~fin] = np.nan
        R[np.broadcast_to(n_def < 2, R.shape)] = np.nan
        return R
    X = transform(name, V)
    fin = np.isfinite(X)
    s = np.where(fin, X, 0.0).sum(axis=1, keepdims=True)
    n_def = fin.sum(axis=1, keepdims=True).astype(np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        loo = (s - np.where(fin, X, 0.0)) / (n_def - 1.0)
    R = X - loo
    R[~fin | (n_def < 2)] = np.nan
    return R[:, :, None]


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
