"""The value a fit quotes and its 95 % interval, read from its per-fiber loss profile.

A :class:`Fit` keeps, at every value it evaluated, each fiber's loss (and, for
an effect that draws random numbers, each fiber's dispersion score). From
these, without any new simulation:

- :func:`slope_estimate`: the value the score test is most compatible with,
  the deepest zero of the t statistic of the fibers' loss slopes;
- :func:`score_interval`: the values where that t statistic is not
  significant, a confidence interval by inverting a score test over the fibers;
- :func:`dispersion_root`, :func:`dispersion_interval`: the same two for a
  random effect, read from where the data are as spread as its copies.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.stats import t as student_t

__all__ = [
    "CRIT_SCALE",
    "Fit",
    "dispersion_interval",
    "dispersion_root",
    "merged_profile",
    "score_interval",
    "slope_estimate",
]

#: Factor on Student's quantile of the score test's 95 % interval (:func:`score_interval`),
#: calibrated on simulated data sets with hidden single effects (N = 20, used at every N):
#: the split-conformal quantile (:func:`.scores.conformal_quantile`) of the factor each
#: data set needed. Per-fiber slopes are step-like and T between evaluated values is an
#: interpolation, so |T| at the truth exceeds Student's quantile more often than it states.
CRIT_SCALE = 1.36


@dataclass(frozen=True)
class Fit:
    """Fitted value of one effect on the fit fibers.

    Attributes
    ----------
    name : str
    value : float
    loss, loss0 : float
        Combined score at the fitted value and at the baseline (same copies).
    evaluations : tuple of (value, loss)
    profile : tuple of (value, ndarray (n_fit,))
        Per-fiber loss at every evaluated value
        (:func:`fibersweep.discrepancy.fit.per_fiber_loss`; its mean is the
        loss), for :func:`score_interval`.
    dispersion : tuple of (value, ndarray (n_fit,))
        For a random effect: each fiber's dispersion score of its observation
        among its copies at every evaluated value
        (:func:`~fibersweep.discrepancy.dispersion.dispersion_matrix`, column 0;
        mean 1 where the copies are as spread as the data), for
        :func:`dispersion_root` and the interval. Empty otherwise.
    """

    name: str
    value: float
    loss: float
    loss0: float
    evaluations: tuple[tuple[float, float], ...]
    profile: tuple[tuple[float, np.ndarray], ...] = field(default=(), repr=False, compare=False)
    dispersion: tuple[tuple[float, np.ndarray], ...] = field(default=(), repr=False, compare=False)


def score_interval(
    fit: Fit, level: float = 0.95, grid: int = 400, scale: float | None = None
) -> tuple[float, float, bool, bool]:
    """Confidence interval of a fitted value by inverting a score test over the fibers.

    The fitted value minimises the mean over fibers of the per-fiber loss
    ℓ_i(v) (the fit's ``profile``). At the true value the mean slope of the
    ℓ_i is zero, so the interval is the set of values where the mean slope is
    not significantly different from zero: between neighbouring evaluated
    values v_j < v_{j+1} the per-fiber slope g_i = (ℓ_i(v_{j+1}) - ℓ_i(v_j)) /
    (v_{j+1} - v_j) is its loss's derivative at the midpoint; at any v each
    fiber's slope is interpolated between its midpoint slopes, and T(v) =
    mean(g) / (sd(g) / sqrt(n)) (:func:`_fiber_t`). The interval is the stretch
    where |T| <= c t_{n-1}(1 - (1 - level)/2) nearest the fitted value, widened to
    the fitted value where that lies outside it; c = ``scale``, by default
    :data:`CRIT_SCALE` for the 95 % interval (calibrated on simulated data) and 1
    at any other level. Evaluated
    values closer than a twentieth of their range count as one (a slope over a
    tiny step is set by the few fibers whose class flips there).

    Each fiber's loss is scored against its own model copies, so the spread of
    g over fibers holds both the fibers' variation and the copies' Monte Carlo
    noise (common random numbers make the slopes themselves precise). A slope,
    not a loss difference, is tested because the loss is not a log-likelihood:
    for a quadratic per-fiber loss (v - mu_i)^2 this interval is exactly
    mean(mu) ± c t SE(mu), while a test on loss differences would be twice as wide.

    Parameters
    ----------
    fit : Fit
        With at least two evaluated values in ``profile``.
    level : float
        Coverage.
    grid : int
        Points at which T is read.
    scale : float or None
        Factor on Student's quantile (None: :data:`CRIT_SCALE` at level 0.95, else 1).

    Returns
    -------
    (lo, hi, open_lo, open_hi)
        The interval; ``open_lo`` / ``open_hi`` are True when the test did not
        reject up to the lowest / highest evaluated value, so the interval is
        cut there (the value may lie further out). ``(value, value, True, True)``
        with fewer than two evaluated values.
    """
    if len(fit.dispersion) >= 2:
        return dispersion_interval(fit, level, grid)
    if len(fit.profile) < 2:
        return (fit.value, fit.value, True, True)
    if scale is None:
        scale = CRIT_SCALE if level == 0.95 else 1.0
    lo, hi, open_lo, open_hi = _accepted(fit, level, grid, scale=scale)
    # never excludes the value it is reported with (see slope_estimate: a fit's value
    # lies inside by construction; a hand-made Fit may not)
    return min(lo, fit.value), max(hi, fit.value), open_lo, open_hi


def merged_profile(fit: Fit) -> tuple[np.ndarray, np.ndarray]:
    """Evaluated values (sorted) and per-fiber losses (k, n), near-duplicates merged.

    Values closer than a twentieth of their range count as one (the lower mean loss
    kept): a slope over a tiny step is set by the one or two fibers whose class
    flips there.
    """
    pts = sorted(fit.profile, key=lambda p: p[0])
    x = np.array([p[0] for p in pts])
    L = np.stack([p[1] for p in pts])  # (k, n)
    keep = [0]
    for j in range(1, len(x)):
        if x[j] - x[keep[-1]] < (x[-1] - x[0]) / 20.0:
            if L[j].mean() < L[keep[-1]].mean():
                keep[-1] = j
        else:
            keep.append(j)
    return x[keep], L[keep]


def _slope_t(x: np.ndarray, L: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Midpoints, mean per-fiber slope and its t statistic between neighbouring values."""
    n = L.shape[1]
    g = np.diff(L, axis=0) / np.diff(x)[:, None]  # (k-1, n) per-fiber slopes
    mid = 0.5 * (x[1:] + x[:-1])
    sd = g.std(axis=1, ddof=1) if n > 1 else np.zeros(len(mid))
    mean = g.mean(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        # no spread: a slope of exactly 0 (no fiber's loss changes there) rejects nothing
        flat = np.where(mean == 0, 0.0, np.sign(mean) * np.inf)
        T = np.where(sd > 0, mean / (sd / np.sqrt(n)), flat)
    return mid, mean, T


def _fiber_t(x: np.ndarray, L: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The score test's t statistic at values ``v``, each fiber's slope interpolated.

    Each fiber's slope between neighbouring evaluated values is its loss's derivative
    at their midpoint; at v, the fiber's slope is the linear interpolation of its two
    neighbouring midpoint slopes (constant beyond the outer midpoints), the derivative
    of a piecewise-quadratic interpolant of its loss, and T(v) = mean / (sd / sqrt(n))
    over the fibers: a t statistic of one per-fiber number at every v, so a valid test
    at v wherever the interpolant is. Interpolating T itself between the midpoints
    (:func:`_slope_t`, the estimate's T) would misread it where neighbouring slopes
    differ in spread.

    Parameters
    ----------
    x : ndarray, shape (k,)
        Evaluated values, sorted, k >= 2.
    L : ndarray, shape (k, n)
        Per-fiber losses at them.
    v : ndarray, shape (m,)

    Returns
    -------
    ndarray, shape (m,)
        T, clipped to +-1e6; where no fiber's slope varies, 0 for a zero mean (no
        fiber's loss changes: rejects nothing) and +-1e6 otherwise.
    """
    n = L.shape[1]
    g = np.diff(L, axis=0) / np.diff(x)[:, None]  # (k-1, n)
    mid = 0.5 * (x[1:] + x[:-1])
    if len(mid) == 1:
        G = np.broadcast_to(g[0], (len(v), n))
    else:
        j = np.clip(np.searchsorted(mid, v) - 1, 0, len(mid) - 2)
        w = np.clip((v - mid[j]) / (mid[j + 1] - mid[j]), 0.0, 1.0)[:, None]
        G = (1.0 - w) * g[j] + w * g[j + 1]  # (m, n)
    mean = G.mean(axis=1)
    sd = G.std(axis=1, ddof=1) if n > 1 else np.zeros(len(v))
    # round-off of the interpolation: a spread far below the slopes' size is none
    sd = np.where(sd > 1e-12 * np.abs(G).max(initial=0.0), sd, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        T = np.where(sd > 0, mean / (sd / np.sqrt(n)), np.sign(mean) * 1e6)
    return np.clip(T, -1e6, 1e6)


def _accepted(
    fit: Fit, level: float, grid: int, centre: float | None = None, scale: float = 1.0
) -> tuple[float, float, bool, bool]:
    """The stretch where |T| stays below ``scale`` x the t quantile nearest ``centre``
    (default: the fitted value); ``(centre, centre, open_lo, open_hi)`` when every value
    is rejected, open at an end the centre sits on while the loss still falls toward it."""
    centre = fit.value if centre is None else centre
    x, L = merged_profile(fit)
    if len(x) < 2:
        return (centre, centre, True, True)
    n = L.shape[1]
    crit = float(student_t.ppf(0.5 + level / 2.0, max(n - 1, 1)))
    v = np.linspace(x[0], x[-1], grid)
    Tv = _fiber_t(x, L, v)
    inside = np.abs(Tv) <= scale * crit
    if not inside.any():
        # every value rejected: at an end where the loss still falls outward the truth
        # lies beyond the evaluated values (open there), otherwise the test is sharp
        step = (x[-1] - x[0]) / (grid - 1)
        return (centre, centre, bool(Tv[0] > 0 and centre <= x[0] + step),
                bool(Tv[-1] < 0 and centre >= x[-1] - step))  # fmt: skip
    # the accepted stretch nearest the centre (with a noisy loss, the slope's zero
    # crossing need not be at the best evaluated value)
    return _stretch(v, inside, centre)


def _stretch(v: np.ndarray, inside: np.ndarray, centre: float) -> tuple[float, float, bool, bool]:
    """The run of accepted read-out points (``inside``, at least one) nearest ``centre``:
    its ends, and whether it reaches the first / last read-out point (open there)."""
    ok = np.flatnonzero(inside)
    i0 = i1 = int(ok[np.argmin(np.abs(v[ok] - centre))])
    while i0 > 0 and inside[i0 - 1]:
        i0 -= 1
    while i1 < len(v) - 1 and inside[i1 + 1]:
        i1 += 1
    return float(v[i0]), float(v[i1]), i0 == 0, i1 == len(v) - 1


def slope_estimate(fit: Fit, level: float = 0.95, grid: int = 400) -> float:
    """The value the score test is most compatible with: the deepest zero of its T.

    The argmin of the evaluated mean losses (the search's best point) is the best
    of a few noisy, step-like points. With 2 copies per fiber a single fiber
    whose copies switch between two outcome branches (contact or not, a long
    dwell or none) changes its loss by tens of times the typical fiber's, so the
    best point is wherever that fiber's copies happened to match its
    observation, often at the edge of its own interval.

    Here the slope between neighbouring evaluated values is read through its t
    statistic T (mean per-fiber slope over its standard error, as in
    :func:`score_interval`), which down-weights a step set by one fiber. The
    estimate minimises the pseudo-loss Λ(v) = ∫ T, the interpolated T
    integrated from the lowest evaluated value: a zero of T where it turns
    from negative to positive, the deepest if there are several. For a
    quadratic per-fiber loss with equal spread of the slopes it is the exact
    minimiser. It lies in the accepted stretch of the score test, so the
    interval :func:`score_interval` reports around it holds it. A fit that kept
    the baseline (value 0) stays at 0.

    Returns
    -------
    float
        The estimate, in the units of the fitted value.
    """
    if fit.value == 0.0 or len(fit.profile) < 3:
        return fit.value
    x, L = merged_profile(fit)
    if len(x) < 3:
        return fit.value
    mid, _, T = _slope_t(x, L)
    v = np.linspace(x[0], x[-1], grid)
    Tv = np.interp(v, mid, np.clip(T, -1e6, 1e6))
    lam = np.concatenate([[0.0], np.cumsum(0.5 * (Tv[1:] + Tv[:-1]) * np.diff(v))])
    return float(v[int(np.argmin(lam))])


def _dispersion_t(fit: Fit) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Evaluated values, mean dispersion score and its t statistic against 1."""
    pts = sorted(fit.dispersion, key=lambda p: p[0])
    x = np.array([p[0] for p in pts])
    D = np.stack([p[1] for p in pts])  # (k, n)
    n = np.isfinite(D).sum(axis=1)
    mean = np.nanmean(D, axis=1)
    sd = np.nanstd(D, axis=1, ddof=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        T = np.where(sd > 0, (mean - 1.0) / (sd / np.sqrt(np.maximum(n, 1))), 0.0)
    return x, mean, T


def dispersion_root(fit: Fit) -> float:
    """The value of a random effect at which the data are as spread as its copies.

    A random effect (start noise, Brownian motion) widens the outcomes. Its fair
    scores against a few copies move little with the value and carry the effect's
    own Monte Carlo noise, so no slope between evaluated values need be
    significant and a half of the fibers can fit 0. The dispersion score of each
    observation among its copies (1 on average exactly when the observation is
    one more copy, whatever the number of copies) falls steadily with the value.
    This is its crossing of 1, read by linear interpolation between the evaluated values,
    the first one going up from the lowest; 0 when the data are not more spread
    than the baseline's copies (a mean of at most 1 at the lowest value), the
    highest evaluated value when they are more spread than every copy set.
    """
    x, mean, _ = _dispersion_t(fit)
    if mean[0] <= 1.0:
        return float(x[0])
    for j in range(len(x) - 1):
        if mean[j] > 1.0 >= mean[j + 1]:
            return float(x[j] + (mean[j] - 1.0) / (mean[j] - mean[j + 1]) * (x[j + 1] - x[j]))
    return float(x[-1])


def dispersion_interval(
    fit: Fit, level: float = 0.95, grid: int = 400
) -> tuple[float, float, bool, bool]:
    """Interval of a random effect's value: where the mean dispersion score is not
    significantly different from 1 (a t test over the fibers at each evaluated
    value, T interpolated between them), the stretch around the fitted value
    (widened to hold it). Same return as :func:`score_interval`."""
    x, _, T = _dispersion_t(fit)
    n = len(fit.dispersion[0][1])
    crit = float(student_t.ppf(0.5 + level / 2.0, max(n - 1, 1)))
    v = np.linspace(x[0], x[-1], grid)
    inside = np.abs(np.interp(v, x, T)) <= crit
    if not inside.any():
        return (fit.value, fit.value, False, False)
    lo, hi, open_lo, open_hi = _stretch(v, inside, fit.value)
    return min(lo, fit.value), max(hi, fit.value), open_lo, open_hi
