"""Per-fiber scores of an observation against an ensemble of model copies.

Everything here works on a value matrix ``V`` of shape (n, m): row i is fiber
i, column 0 its observed value and columns 1..m-1 the model's jittered copies
(NaN / -1 where undefined, e.g. δ of a trapped fiber). For each entry the
*leave-one-out* score of ``V[i, j]`` against the other members of row i is
computed, giving a score matrix ``S`` of the same shape. Under the null
hypothesis "the observation is one more draw of the model's copies", the
columns of a row are exchangeable, so column 0 is a uniformly random pick among
them; this is what :mod:`fibersweep.discrepancy.stats` permutes.

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
spread. The log-loss of a smoothed frequency, used before, is not: with 8
copies, an observation that is one class with probability 0.9 scored better
against copies that always give that class than against copies drawn from the
true distribution, so effects that spread outcomes (start noise) were fitted
too small.
"""

from __future__ import annotations

import numpy as np

from fibersweep.discrepancy.observables import OBSERVABLES, Observable

__all__ = [
    "crps_fair_loo",
    "brier_fair_loo",
    "score_matrix",
    "residual_matrix",
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
