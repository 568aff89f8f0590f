"""How well a sweep locates a critical length, and the array setting that gives one.

A critical length is where the mean displacement fraction f of the runs that were
not trapped crosses 1/2. The report interpolates it linearly between the two
simulated lengths around the crossing (:func:`fibersweep.sorting.report.critical_table`);
that estimate has three errors, and the interval here holds all three:

* **the runs' scatter**: each mean f rests on the runs of its length (12 seeded
  starts, fewer where some were trapped);
* **the interpolation between simulated lengths**: lengths are 4 µm apart (one
  bead or more), and f between them is not a straight line. Near a sorter's
  critical length it is closer to a step: a fiber one bead shorter zigzags, one
  bead longer follows the tilt. Then the runs say only that the crossing lies
  between the two lengths, and a linear interpolation of two plateaus places it
  where the plateaus put it, not where it is;
* **the interpolation between simulated settings** (the inverse answer): the
  critical length is not a straight line in the row shift either.

**The model.** Around each crossing (the two lengths of its bracket and up to
:data:`WINDOW` simulated lengths on each side, never past a neighbouring crossing
that is a band's other edge) f is taken as a sigmoid in L between two plateaus,
f(L) = P0 + (P1 − P0) / (1 + exp(−(L − m)/w)), of any width w from a step (a
hundredth of the bracket) to wider than the window, and the critical length is
where it is 1/2. The runs of each length enter through their mean f, whose
variance is that of a share: n runs that each follow the tilt (the upper plateau)
or not with the sigmoid's probability S at that length, with half a run added at
each plateau (Jeffreys' prior of a share, so that a length whose few runs all did
the same keeps the uncertainty of a few runs), plus the runs' scatter within a
mode (the least spread of any length's runs). With flat priors on the midpoint
and the log width and a broad normal prior on the plateaus (centred on the lowest
and highest mean f between the neighbouring band edges, sd :data:`PLATEAU_SD`),
the plateaus integrate out exactly (the model is linear in them) and the midpoint
and width are summed on a grid. The result is a posterior of the critical length: a step
leaves it flat over the bracket (the runs cannot say where in the bracket the
step is), a transition that spans several lengths pins it near the
interpolation, and few runs widen it. The interval is the central
:data:`INTERVAL_LEVEL` of the posterior.

Why not a bootstrap of the runs alone: resampling the runs of each length and
re-interpolating linearly reproduces the scatter, not the interpolation error; on
the designs of ``tests/unit/test_design_coverage.py`` its 95 % interval held the
true critical length 88 % of the time (the statistical ± alone, less than 80 %:
the test measures it). Why not the whole bracket, uniform: where the lengths
around it show the transition (f between the plateaus at the bracket's ends) the
runs do locate the crossing inside it, and the bracket over-covers (99 % for a
promised 95 %). The model-free bracket is still printed beside the interval.

**The inverse answer.** :func:`inverse_draws` takes one draw of every setting's
critical length at a time, interpolates the target between the two settings
whose critical lengths bracket it (as :func:`fibersweep.sorting.design.answer`
does), and, with a third setting on either side, takes the truth to lie
anywhere between that chord and the parabola through the third setting (the next
term of the interpolation: uniform between the two, the parabola on a side drawn
at random). The interval is the central :data:`INTERVAL_LEVEL` of those answers.
With two settings only the curvature is not estimated (said where it is printed).

The coverage of both intervals on synthetic designs with a known truth is
measured in ``tests/unit/test_design_coverage.py``. Pure functions of the tables;
seeded, so the same tables give the same intervals.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pandas as pd

__all__ = [
    "DRAWS",
    "FEW_MOVING",
    "INTERVAL_LEVEL",
    "PLATEAU_SD",
    "WINDOW",
    "bracket_draws",
    "critical_draws",
    "crossing_draws",
    "interval",
    "inverse_draws",
    "level_text",
]

#: Probability the printed intervals hold (central interval of the posterior).
INTERVAL_LEVEL = 0.95

#: Draws of each critical length (and of the inverse answer).
DRAWS = 2000

#: Simulated lengths on each side of a crossing's bracket that inform its shape.
WINDOW = 2

#: Prior standard deviation of the plateaus of f around the lowest and highest mean.
PLATEAU_SD = 0.3

#: A length that decides a crossing with fewer moving (not trapped) runs is named.
FEW_MOVING = 5

#: Grid of the sigmoid: midpoints per bracket width, widths.
_PER_BRACKET = 20
_WIDTHS = 12
_SEED = 61803


def level_text(level: float = INTERVAL_LEVEL) -> str:
    """'95 %': the level as printed."""
    return f"{100 * level:g} %"


def _logit(p: np.ndarray) -> np.ndarray:
    return np.log(p) - np.log1p(-p)


def _expit(z: np.ndarray) -> np.ndarray:
    return 0.5 * (1.0 + np.tanh(0.5 * z))


def crossing_draws(
    lengths: np.ndarray,
    moving: np.ndarray,
    mean: np.ndarray,
    std: np.ndarray,
    lo: int,
    rising: bool,
    rng: np.random.Generator,
    draws: int = DRAWS,
    first: int = 0,
    last: int | None = None,
    window: int = WINDOW,
    at: float = 0.5,
) -> np.ndarray:
    """Draws of the critical length [µm] of one crossing from its posterior (module docstring).

    Parameters
    ----------
    lengths : ndarray
        Simulated lengths L [µm], increasing, each with at least one moving run.
    moving : ndarray
        Moving (not trapped) runs per length.
    mean, std : ndarray
        Mean f and its standard deviation over the moving runs (NaN for one run).
    lo : int
        Index of the bracket's lower length (the crossing is between ``lo`` and ``lo + 1``).
    rising : bool
        f rises through 1/2 there (False: falls).
    rng : Generator
    draws : int
    first, last : int
        The window never reaches below ``first`` or above ``last`` (the near lengths of
        the neighbouring crossings that are a band's other edge).
    window : int
        Lengths on each side of the bracket in the window.
    at : float
        The mean f that defines the critical length.

    Returns
    -------
    ndarray
        ``draws`` critical lengths [µm], inside the window.
    """
    n = len(lengths)
    last = n - 1 if last is None else last
    i0 = max(first, lo - window)
    i1 = min(last, lo + 1 + window)
    L = np.asarray(lengths[i0 : i1 + 1], float)
    N = np.asarray(moving[i0 : i1 + 1], float)
    fb = np.asarray(mean[i0 : i1 + 1], float)
    sd = np.nan_to_num(np.asarray(std[i0 : i1 + 1], float))
    # the plateaus: the lowest and highest mean f between the neighbouring crossings
    seg = np.asarray(mean[first : last + 1], float)
    fmin, fmax = float(min(seg.min(), fb.min())), float(max(seg.max(), fb.max()))
    top = max(fmax, fmin + 0.5)
    # the runs' spread within a mode: the least of any length with a few runs
    many = N >= 3
    tau2 = float(np.min(sd[many] ** 2)) if many.any() else 0.0
    tau2 = max(tau2, (0.01 * (top - fmin)) ** 2)
    h = float(lengths[lo + 1] - lengths[lo])
    span = float(L[-1] - L[0])
    s = 1.0 if rising else -1.0
    nm = int(_PER_BRACKET * span / h) + 1
    ms = np.linspace(L[0] - span, L[-1] + span, 3 * nm)
    dm = ms[1] - ms[0]
    ws = np.geomspace(0.01 * h, 3.0 * span, _WIDTHS)
    S = _expit(s * (L - ms[:, None, None]) / ws[None, :, None])  # (midpoints, widths, lengths)
    # the variance of a mean of n runs that each go one way or the other with the
    # sigmoid's share S, with half a run at each plateau (Jeffreys: a length whose few
    # runs all did the same keeps the uncertainty of a share of few runs), plus the
    # runs' scatter within a mode
    share = N * S * (1.0 - S) + 0.5 * (S**2 + (1.0 - S) ** 2)
    W = (N + 1.0) ** 2 / ((top - fmin) ** 2 * share + N * tau2)
    ip = 1.0 / PLATEAU_SD**2
    a00 = ((1 - S) ** 2 * W).sum(-1) + ip
    a11 = (S**2 * W).sum(-1) + ip
    a01 = ((1 - S) * S * W).sum(-1)
    r0 = ((1 - S) * W * fb).sum(-1) + ip * fmin
    r1 = (S * W * fb).sum(-1) + ip * fmax
    det = a00 * a11 - a01**2
    p0 = (a11 * r0 - a01 * r1) / det
    p1 = (a00 * r1 - a01 * r0) / det
    # log marginal likelihood of (m, w), the plateaus integrated out (normal prior)
    ll = 0.5 * (np.log(W) - W * fb**2).sum(-1) + 0.5 * (r0 * p0 + r1 * p1) - 0.5 * np.log(det)
    weight = np.exp(ll - ll.max()).ravel()
    weight /= weight.sum()
    out: list[np.ndarray] = []
    got = 0
    cdf = np.cumsum(weight)
    for _ in range(20):
        m_ = 2 * draws
        idx = np.minimum(np.searchsorted(cdf, rng.random(m_) * cdf[-1]), weight.size - 1)
        im, iw = np.unravel_index(idx, ll.shape)
        d = det[im, iw]
        c00, c11, c01 = a11[im, iw] / d, a00[im, iw] / d, -a01[im, iw] / d
        l00 = np.sqrt(c00)
        l10 = c01 / l00
        l11 = np.sqrt(np.maximum(c11 - l10**2, 0.0))
        z0, z1 = rng.standard_normal(m_), rng.standard_normal(m_)
        q0 = p0[im, iw] + l00 * z0
        q1 = p1[im, iw] + l10 * z0 + l11 * z1
        ok = (q0 < at) & (q1 > at)
        q = np.where(ok, (at - q0) / np.where(ok, q1 - q0, 1.0), 0.5)
        x = ms[im] + rng.uniform(-dm / 2, dm / 2, m_) + s * ws[iw] * _logit(q)
        ok &= (x >= L[0]) & (x <= L[-1])
        out.append(x[ok])
        got += int(ok.sum())
        if got >= draws:
            break
    x = np.concatenate(out) if out else np.empty(0)
    if x.size == 0:  # no sigmoid crosses 1/2 in the window: the bracket, uniform
        return rng.uniform(lengths[lo], lengths[lo + 1], draws)
    if x.size < draws:
        x = rng.choice(x, draws)
    return x[:draws]


def _rng(*key: float) -> np.random.Generator:
    """A generator seeded by ``key`` (a setting, a bracket): the same tables, the same draws."""
    return np.random.default_rng([_SEED, *(int(round(1000 * abs(k))) for k in key)])


def critical_draws(
    table: pd.DataFrame,
    setting: int,
    lo: float,
    hi: float,
    rising: bool,
    draws: int = DRAWS,
    at: float = 0.5,
) -> np.ndarray:
    """Draws of the critical length [µm] of one setting between ``lo`` and ``hi`` [µm].

    Parameters
    ----------
    table : DataFrame
        :func:`fibersweep.sorting.report.migration_table` (``moving``,
        ``fraction_mean``, ``fraction_std`` per setting and length).
    setting : int
    lo, hi : float
        The crossing's bracket of simulated lengths [µm].
    rising : bool
        f rises through 1/2 there.
    draws : int
    at : float
        The mean f that defines the critical length.
    """
    g = table[table["setting"] == setting].sort_values("length")
    g = g[np.isfinite(g["fraction_mean"].to_numpy(float))]
    L = g["length"].to_numpy(float)
    f = g["fraction_mean"].to_numpy(float)
    moving = g["moving"].to_numpy(float)
    std = g["fraction_std"].to_numpy(float)
    memo = (setting, lo, hi, rising, draws, at, L.tobytes(), f.tobytes(), moving.tobytes(),
            std.tobytes())  # fmt: skip
    if memo in _MEMO:  # the table and the curve ask for the same crossing
        return _MEMO[memo]
    k = int(np.flatnonzero(np.isclose(L, lo))[0])
    d = f - at
    cross = [j for j in range(len(L) - 1) if d[j] * d[j + 1] < 0]
    # the window stops at a neighbouring crossing only where f between the two is away
    # from the level by 2 standard errors (a band); a wiggle of the runs' scatter
    # around 1/2 is one transition, not two
    with np.errstate(invalid="ignore", divide="ignore"):
        se = np.where(moving > 1, std / np.sqrt(moving), np.nan)
        z = np.nan_to_num(np.abs(d) / np.where(np.isfinite(se) & (se > 0), se, np.inf))
    below = [j for j in cross if j < k and z[j + 1 : k + 1].max() >= 2.0]
    above = [j for j in cross if j > k and z[k + 1 : j + 1].max() >= 2.0]
    first = max(below, default=-1) + 1
    last = min(above, default=len(L) - 1)
    rng = _rng(setting, lo, hi, rising)
    x = crossing_draws(L, moving, f, std, k, rising, rng, draws, first, last, at=at)
    if len(_MEMO) > 512:
        _MEMO.clear()
    _MEMO[memo] = x
    return x


_MEMO: dict[tuple, np.ndarray] = {}


def bracket_draws(
    lo: float, hi: float, se: float, key: Sequence[float] = (), draws: int = DRAWS
) -> np.ndarray:
    """Draws of a critical length known only by its bracket [µm] and statistical error:
    uniform over the bracket, plus a normal of sd ``se`` (a curve read back from
    ``critical.csv``, without the runs)."""
    rng = _rng(lo, hi, *key)
    x = rng.uniform(lo, hi, draws)
    return x + (rng.standard_normal(draws) * se if math.isfinite(se) else 0.0)


def interval(x: np.ndarray, level: float = INTERVAL_LEVEL) -> tuple[float, float]:
    """Central ``level`` interval of draws (±inf kept: an end beyond the simulated range;
    NaN when there are no draws)."""
    x = np.asarray(x, float)
    x = x[~np.isnan(x)]
    if x.size == 0:
        return math.nan, math.nan
    a = 0.5 * (1.0 - level)
    lo, hi = np.quantile(x, [a, 1.0 - a], method="inverted_cdf")
    return float(lo), float(hi)


def inverse_draws(
    values: np.ndarray,
    crit: np.ndarray,
    target: float,
    rising: np.ndarray | None = None,
    curvature: bool = True,
    rng: np.random.Generator | None = None,
) -> np.ndarray:
    """Draws of the setting whose critical length is ``target`` (module docstring).

    Parameters
    ----------
    values : ndarray
        The simulated values of the setting, increasing (ns,).
    crit : ndarray
        Draws of their critical lengths [µm] (draws, ns).
    target : float
        Target critical length [µm].
    rising : ndarray of bool, optional
        Per value, whether its crossing is a lower edge; a pair of a lower and an upper
        edge is never interpolated.
    curvature : bool
        With three values or more, the truth between the chord and the parabola
        through a third value.

    Returns
    -------
    ndarray
        One answer per draw; +inf or −inf where every critical length of the draw is on
        one side of the target (the answer lies beyond the simulated values, on the side
        where the critical length moves towards the target).
    """
    rng = rng or _rng(target, *values)
    v = np.asarray(values, float)
    C = np.asarray(crit, float)
    D, ns = C.shape
    c0, c1 = C[:, :-1], C[:, 1:]
    cond = ((c0 - target) * (c1 - target) <= 0) & (c0 != c1)
    if rising is not None:
        rising = np.asarray(rising, bool)
        cond &= (rising[:-1] == rising[1:])[None, :]
    has = cond.any(1)
    k = cond.argmax(1)
    r = np.arange(D)
    k1 = np.minimum(k + 1, ns - 1)
    ck, ck1 = C[r, k], C[r, k1]
    h = v[k1] - v[k]
    with np.errstate(divide="ignore", invalid="ignore"):
        xl = (target - ck) / (ck1 - ck) * h
        x = xl
        if curvature and ns >= 3:
            alts = []
            for off in (-1, 0):
                a = k + off
                okt = (a >= 0) & (a + 2 <= ns - 1)
                ia, ib, ic = (np.clip(a + j, 0, ns - 1) for j in (0, 1, 2))
                dd = (
                    (C[r, ic] - C[r, ib]) / (v[ic] - v[ib])
                    - (C[r, ib] - C[r, ia]) / (v[ib] - v[ia])
                ) / (v[ic] - v[ia])
                b = (ck1 - ck) / h - dd * h
                disc = b * b - 4.0 * dd * (ck - target)
                sq = np.sqrt(np.maximum(disc, 0.0))
                x1, x2 = (-b + sq) / (2 * dd), (-b - sq) / (2 * dd)
                in1 = (x1 >= -1e-12 * h) & (x1 <= h * (1 + 1e-12))
                in2 = (x2 >= -1e-12 * h) & (x2 <= h * (1 + 1e-12))
                near1 = ~in2 | (np.abs(x1 - xl) <= np.abs(x2 - xl))
                xq = np.where(in1 & near1, x1, np.where(in2, x2, np.nan))
                flat = np.abs(dd * h * h) <= 1e-9 * np.abs(ck1 - ck)
                xq = np.where(flat, xl, xq)
                alts.append(np.where(okt & (disc >= 0), xq, np.nan))
            a0, a1 = alts
            pick = np.where(np.isfinite(a0) & (~np.isfinite(a1) | (rng.random(D) < 0.5)), a0, a1)
            x = np.where(np.isfinite(pick), xl + rng.random(D) * (pick - xl), xl)
    out = v[k] + x
    grows = C[:, -1] > C[:, 0]
    above = np.all(C < target, axis=1)
    below = np.all(C > target, axis=1)
    beyond = np.where(above == grows, np.inf, -np.inf)
    return np.where(has, out, np.where(above | below, beyond, np.nan))
