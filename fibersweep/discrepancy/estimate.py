"""The value a fit quotes and its 95 % interval, read from its per-fiber loss profile.

A :class:`Fit` keeps, at every value it evaluated, each fiber's loss (and, for
an effect that draws random numbers, each fiber's dispersion score). From
these, without any new simulation:

- :func:`slope_estimate`: the value the score test is most compatible with,
  the deepest minimum of the pseudo-loss Λ = ∫ T, T the t statistic of the
  fibers' loss slopes;
- :func:`score_interval`: a bootstrap over the fibers of the mean loss's
  minimiser, read with the same interpolation (:func:`minimiser_ends`), as an
  expanded percentile interval;
- :func:`dispersion_root`, :func:`dispersion_interval`: the same two for a
  random effect, read from where the data are as spread as its copies.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, field

import numpy as np
from scipy.stats import norm
from scipy.stats import t as student_t

__all__ = [
    "N_BOOT",
    "Fit",
    "bootstrap_minimisers",
    "dispersion_interval",
    "dispersion_root",
    "expanded_tail",
    "merged_profile",
    "minimiser_ends",
    "score_interval",
    "slope_estimate",
]

#: Bootstrap resamples of the fibers behind :func:`score_interval`. The interval's ends
#: are its 1.6 % / 98.4 % quantiles at N = 20 (:func:`expanded_tail`): about 64
#: resamples beyond each end, a Monte Carlo error of the ends near 0.05 standard errors.
N_BOOT = 4000


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


def expanded_tail(n: int, level: float = 0.95) -> float:
    """Tail probability of each end of the expanded percentile interval of ``n`` units.

    The percentile interval of a bootstrapped mean is too narrow at small n: the
    bootstrap's spread has divisor n, not n - 1, and its quantiles are the normal's,
    not Student's. Reading it at Φ(-sqrt(n / (n - 1)) t_{n-1}(1 - (1 - level) / 2))
    instead of (1 - level) / 2 makes it Student's interval mean ± t SE for a
    symmetric sample (Hesterberg 2015, "What teachers should know about the
    bootstrap", The American Statistician 69: 371, section 4.3). Nothing is fitted:
    the expansion follows from n and the level, and vanishes as n grows (0.016 at
    n = 20, 0.022 at 60, 0.024 at 200, for 0.025 at level 0.95).

    Parameters
    ----------
    n : int
        Resampled units (fibers), at least 2.
    level : float
        Coverage in (0, 1).

    Returns
    -------
    float
        The probability left out at each end.
    """
    if n < 2:
        raise ValueError(f"the expanded percentile needs at least 2 fibers, got {n}")
    t = float(student_t.ppf(0.5 + level / 2.0, n - 1))
    return float(norm.sf(np.sqrt(n / (n - 1.0)) * t))


def _data_seed(x: np.ndarray, L: np.ndarray) -> int:
    """A seed from the profile itself: the same fit always gets the same interval."""
    return zlib.crc32(np.ascontiguousarray(L, dtype=np.float64).tobytes(),
                      zlib.crc32(np.ascontiguousarray(x, dtype=np.float64).tobytes()))  # fmt: skip


def score_interval(
    fit: Fit, level: float = 0.95, grid: int = 400, n_boot: int = N_BOOT
) -> tuple[float, float, bool, bool]:
    """Confidence interval of a fitted value: a bootstrap over the fibers of its minimiser.

    The fibers are independent, and each fiber's loss ℓ_i(v) (the fit's
    ``profile``) is scored against its own model copies, so resampling fibers
    resamples the copies' Monte Carlo noise with them. ``n_boot`` resamples of the
    n fibers with replacement; for each, the minimiser of the resampled mean loss,
    read with the interpolation of :func:`slope_estimate`: each fiber's slope
    between neighbouring evaluated values is its loss's derivative at their
    midpoint, the mean slope is interpolated linearly between the midpoints (a
    piecewise-quadratic mean loss) and the minimiser is its zero where it turns
    from negative to positive, the deepest if there are several, read exactly
    (:func:`minimiser_ends`). Where the mean loss is
    flat at its minimum (no fiber's loss changes there) a resample's minimiser is
    the whole flat stretch: the interval runs from the lower quantile of the
    stretches' lower ends to the upper quantile of their upper ends.

    The mean slope is not divided by its standard error per stretch, as the quoted
    value's T is: between closely spaced evaluated values (where a search zoomed
    in) few fibers change, T is small whatever the mean slope, and the resampled
    zeros of T stay trapped between those values. On a stand-in whose losses are
    only class flips (halves and pooled refits, 60 data sets each) the T read-out
    covered 0.85 and 0.73 at N = 20 and 60, the mean slope 0.90 and 0.82
    (scripts/studies/discrepancy/diagnose_interval.py; on smooth losses both
    0.93-0.98 at N = 20, 60, 200).

    The quantiles are those of the expanded percentile interval
    (:func:`expanded_tail`): for a quadratic per-fiber loss (v - mu_i)^2 the
    minimiser is mean(mu) and the interval is Student's mean(mu) ± t SE(mu), up to
    the skewness of the mu and the bootstrap's Monte Carlo error. Nothing in it is
    calibrated on simulated data.

    A resample whose minimiser is the highest (lowest) evaluated value shows only
    that the mean loss still falls over the last stretch toward it; its minimum
    may lie anywhere beyond the stretch's other end, which is the lower (upper)
    end it contributes. ``open_lo`` / ``open_hi``: the resampled minimisers pile up
    at the lowest / highest evaluated value (at least the tail probability of the
    resamples sit there), so the interval is cut there and the value may lie
    further out. The resamples are drawn from a seed made of the profile itself
    (the same fit always gets the same interval). Evaluated values closer than a
    twentieth of their range count as one (:func:`merged_profile`). The interval is
    widened to hold the fit's value (the zero of T) where that lies outside it.

    Parameters
    ----------
    fit : Fit
        With at least two evaluated values in ``profile`` (or ``dispersion``: a
        random effect, :func:`dispersion_interval`).
    level : float
        Coverage.
    grid : int
        Points at which a random effect's t statistic is read
        (:func:`dispersion_interval`).
    n_boot : int
        Bootstrap resamples.

    Returns
    -------
    (lo, hi, open_lo, open_hi)
        The interval in the units of the value, and whether each end is cut at the
        evaluated range. ``(value, value, True, True)`` with fewer than two evaluated
        values; the evaluated range, open at both ends, with one fiber.
    """
    if len(fit.dispersion) >= 2:
        return dispersion_interval(fit, level, grid)
    if len(fit.profile) < 2:
        return (fit.value, fit.value, True, True)
    x, L = merged_profile(fit)
    if len(x) < 2:
        return (fit.value, fit.value, True, True)
    n = L.shape[1]
    if n < 2:
        return (min(float(x[0]), fit.value), max(float(x[-1]), fit.value), True, True)
    rng = np.random.default_rng(_data_seed(x, L))
    counts = rng.multinomial(n, np.full(n, 1.0 / n), size=n_boot)  # (n_boot, n)
    ends_lo, ends_hi = minimiser_ends(x, L, counts)
    a = expanded_tail(n, level)
    # open: at least the tail's share of the minimisers sit at the evaluated range's end
    open_lo = bool(np.quantile(ends_lo, a) <= x[0])
    open_hi = bool(np.quantile(ends_hi, 1.0 - a) >= x[-1])
    # a minimum at an end of the evaluated values says only that the loss still falls
    # over the last stretch toward it: the value lies beyond that stretch's other end
    lo = float(np.quantile(np.where(ends_lo >= x[-1], x[-2], ends_lo), a))
    hi = float(np.quantile(np.where(ends_hi <= x[0], x[1], ends_hi), 1.0 - a))
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


def _slope_stat(
    x: np.ndarray, L: np.ndarray, counts: np.ndarray, studentise: bool
) -> tuple[np.ndarray, np.ndarray]:
    """Midpoints of neighbouring evaluated values, shape (k-1,), and per resample the
    weighted fibers' mean slope there (its t statistic with ``studentise``), (b, k-1)."""
    C = np.asarray(counts, dtype=np.float64)
    n = C.sum(axis=1, keepdims=True)  # (b, 1) fibers per resample
    g = np.diff(L, axis=0) / np.diff(x)[:, None]  # (k-1, n) per-fiber slopes
    gbar = g.mean(axis=1)
    gc = g - gbar[:, None]  # centred: the weighted variance without cancellation
    W = C / n
    m = W @ gc.T  # (b, k-1)
    mean = m + gbar
    mid = 0.5 * (x[1:] + x[:-1])
    if not studentise:
        return mid, mean
    var = np.maximum(W @ (gc**2).T - m**2, 0.0) * n / np.maximum(n - 1.0, 1.0)
    sd = np.sqrt(var)
    # round-off: a spread far below the slopes' size is none; then a slope of exactly
    # 0 (no fiber's loss changes there) is 0 and any other is decisive
    tiny = 1e-12 * np.abs(g).max(initial=0.0)
    sd = np.where(sd > tiny, sd, 0.0)
    flat = np.where(np.abs(mean) <= tiny, 0.0, np.sign(mean) * 1e6)
    with np.errstate(divide="ignore", invalid="ignore"):
        T = np.clip(np.where(sd > 0, mean / (sd / np.sqrt(n)), flat), -1e6, 1e6)
    return mid, T


def bootstrap_minimisers(
    x: np.ndarray, L: np.ndarray, counts: np.ndarray, v: np.ndarray, studentise: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """The minimiser of the pseudo-loss Λ for fibers weighted by ``counts``, on a grid.

    Between neighbouring evaluated values each fiber's slope is its loss's
    derivative at their midpoint; T there is the weighted fibers' mean slope (a
    resample with fiber i drawn ``counts[i]`` times), divided by its standard
    error with ``studentise`` (:func:`slope_estimate`) or not (the mean loss).
    T is interpolated linearly between the midpoints (constant beyond the outer
    ones) and Λ(v) = ∫ T from the lowest evaluated value. Its minimum is where T
    turns from negative to positive, the deepest if there are several; where no
    fiber's slope changes over a stretch (T exactly 0) the minimum is that whole
    stretch. :func:`minimiser_ends` reads the same minimum exactly, off the grid.

    Parameters
    ----------
    x : ndarray, shape (k,)
        Evaluated values, sorted, k >= 2.
    L : ndarray, shape (k, n)
        Per-fiber losses at them.
    counts : ndarray, shape (b, n)
        Times each fiber is drawn, per resample (a row of ones: the data themselves).
    v : ndarray, shape (m,)
        Sorted points at which Λ is read.
    studentise : bool
        T the t statistic of the mean slope (True) or the mean slope itself.

    Returns
    -------
    (i_lo, i_hi) : ndarray of int, shape (b,) each
        Indices into ``v`` of the lowest and highest point of each resample's minimum.
    """
    mid, T = _slope_stat(x, L, counts, studentise)
    if len(mid) == 1:
        Tv = np.repeat(T, len(v), axis=1)
    else:
        j = np.clip(np.searchsorted(mid, v, side="right") - 1, 0, len(mid) - 2)
        w = np.clip((v - mid[j]) / (mid[j + 1] - mid[j]), 0.0, 1.0)
        Tv = (1.0 - w) * T[:, j] + w * T[:, j + 1]  # (b, m)
    lam = np.concatenate(
        [np.zeros((len(T), 1)), np.cumsum(0.5 * (Tv[:, 1:] + Tv[:, :-1]) * np.diff(v), axis=1)],
        axis=1,
    )
    at_min = _at_min(lam)
    i_lo = np.argmax(at_min, axis=1)
    i_hi = lam.shape[1] - 1 - np.argmax(at_min[:, ::-1], axis=1)
    return i_lo, i_hi


def _at_min(lam: np.ndarray) -> np.ndarray:
    """Where each row of Λ (inf: no candidate) is at its minimum; a flat minimum (T
    exactly 0 over a stretch) holds the same Λ up to round-off."""
    fin = np.isfinite(lam)
    low = np.where(fin, lam, np.inf).min(axis=1, keepdims=True)
    size = np.where(fin, np.abs(lam), 0.0).max(axis=1, keepdims=True)
    return fin & (lam <= low + 1e-12 * np.maximum(size, 1e-300))


def minimiser_ends(
    x: np.ndarray, L: np.ndarray, counts: np.ndarray, studentise: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """The minimum of Λ of :func:`bootstrap_minimisers`, read exactly (no grid).

    T is piecewise linear between the midpoints and constant beyond them, so Λ is
    piecewise quadratic and its minimum lies at an end of the evaluated range, at a
    midpoint, or where T crosses zero from negative to positive between two
    midpoints (linear interpolation); Λ is evaluated at all of these.

    Parameters
    ----------
    x, L, counts, studentise
        As for :func:`bootstrap_minimisers`.

    Returns
    -------
    (lo, hi) : ndarray, shape (b,) each
        The lowest and highest point of each resample's minimum, in the units of x
        (equal unless Λ is flat there).
    """
    mid, T = _slope_stat(x, L, counts, studentise)
    b = len(T)
    dm = np.diff(mid)
    lam_mid = T[:, :1] * (mid[0] - x[0]) + np.concatenate(
        [np.zeros((b, 1)), np.cumsum(0.5 * (T[:, 1:] + T[:, :-1]) * dm, axis=1)], axis=1
    )  # (b, k-1): Λ at the midpoints
    lam_end = lam_mid[:, -1:] + T[:, -1:] * (x[-1] - mid[-1])
    T0, T1 = T[:, :-1], T[:, 1:]
    cross = (T0 < 0.0) & (T1 > 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(cross, mid[:-1] + T0 / (T0 - T1) * dm, mid[:-1])
    lam_z = np.where(cross, lam_mid[:, :-1] + 0.5 * T0 * (z - mid[:-1]), np.inf)
    pos = np.concatenate([np.full((b, 1), x[0]), np.broadcast_to(mid, (b, len(mid))), z,
                          np.full((b, 1), x[-1])], axis=1)  # fmt: skip
    lam = np.concatenate([np.zeros((b, 1)), lam_mid, lam_z, lam_end], axis=1)
    at_min = _at_min(lam)
    lo = np.where(at_min, pos, np.inf).min(axis=1)
    hi = np.where(at_min, pos, -np.inf).max(axis=1)
    return lo, hi


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
    statistic T (mean per-fiber slope over its standard error), which
    down-weights a step set by one fiber. The estimate minimises the
    pseudo-loss Λ(v) = ∫ T, the interpolated T integrated from the lowest
    evaluated value (:func:`bootstrap_minimisers` with every fiber once): a zero
    of T where it turns from negative to positive, the deepest if there are
    several, the lowest point of a flat minimum. For a quadratic per-fiber loss
    with equal spread of the slopes it is the exact minimiser. The interval
    :func:`score_interval` bootstraps the mean loss's minimiser read the same way.
    A fit that kept the baseline (value 0) stays at 0.

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
    v = np.linspace(x[0], x[-1], grid)
    i_lo, _ = bootstrap_minimisers(x, L, np.ones((1, L.shape[1])), v)
    return float(v[i_lo[0]])


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
