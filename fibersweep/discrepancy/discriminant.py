"""The follow-up test of hypothesis A against B: its statistic, null draws and the fibers it needs.

Per follow-up fiber i and scored component c (:func:`.components.standardised_values`),
the discriminant

    λ_i = Σ_c [(x_ic - μB_ic)² - (x_ic - μA_ic)²] / (2 s_c²)

is the Gaussian log-likelihood ratio of A over B (μ: the mean of the *reference*
copies of each hypothesis at the fiber's start; s_c: the spread of both
hypotheses' reference copies around those means, pooled over all fibers; a
component undefined in x or μ adds nothing). It is only a statistic:
its distribution under each hypothesis is that of *null* copies of the
hypothesis (independent of the reference copies, measurement noise included)
scored the same way, so the test needs no Gaussian assumption. For the sum
Λ = Σ_i λ_i the null distribution is drawn by taking, per fiber, one value of
its pool (its null copies' λ and its own measured λ_i, as a permutation test
keeps the observed designation among its draws), ``n_draws`` times. A copy
whose run failed is left out of its fiber's pool (and of the reference means);
an outcome that is undefined by its observable's rule (no contact, a trapped
fiber) is scored the same way in the copies as in the measured fibers. Then

    p_A = P(Λ* <= Λ | A)   (fibers further from A than A's own copies are),
    p_B = P(Λ* >= Λ | B),

each one-sided at ``alpha``. When one of the two is true at its fitted value,
and the follow-up fibers' starts are spread as the copies assume (the measured
start within the start noise of the true one, not aimed at a point exactly),
the chance of rejecting it is at most alpha, and so is the chance of a wrong
pick. A hypothesis whose fitted value is off (a continuous effect fitted within
its interval) is rejected more often the more follow-up fibers there are. The
bound holds for one test of fresh fibers: testing again as more fibers are
added to the same follow-up (the copies are seeded the same) is a sequential
test, whose chance of a wrong pick grows with the number of looks.

Outcome: B rejected and A not: "A"; the reverse: "B"; both rejected:
"neither" (the fibers lie between the two, e.g. the truth is a value between
two fitted values); none rejected: "undecided" (too few or too weakly
discriminating fibers: :func:`fibers_to_settle` says how many such fibers would
do). The same statistic, read on copies at points of a window
(:func:`window_separation`), sizes what-to-measure-next (:mod:`.next_measure`).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.stats import norm

__all__ = [
    "N_DRAWS",
    "SettleTest",
    "discriminant",
    "fibers_to_settle",
    "noise_spread",
    "settle_test",
    "window_separation",
]


#: Null draws of the sum Λ per hypothesis (resolution of the p-values: 1/(n_draws + 1)).
N_DRAWS = 19999


def discriminant(x: np.ndarray, mu_a: np.ndarray, mu_b: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Per-fiber log-likelihood ratio of A over B under a Gaussian model.

    Parameters
    ----------
    x : ndarray, shape (..., n, c)
        Component values (scoring scale) of n fibers.
    mu_a, mu_b : ndarray, shape (n, c)
        The hypotheses' mean predictions at the same starts.
    s : ndarray, shape (c,)
        Noise of one fiber per component (> 0).

    Returns
    -------
    ndarray, shape (..., n)
        Σ_c [(x - μB)² - (x - μA)²] / (2 s²); a component undefined (NaN) in x,
        μA or μB adds 0, by the same rule for measured fibers and copies.
    """
    x = np.asarray(x, dtype=np.float64)
    if x.shape[-2:] != np.shape(mu_a) or np.shape(mu_a) != np.shape(mu_b):
        raise ValueError(
            f"shapes differ: x {x.shape}, mu_a {np.shape(mu_a)}, mu_b {np.shape(mu_b)}"
        )
    if np.shape(s) != x.shape[-1:]:
        raise ValueError(f"s must have shape {x.shape[-1:]}, got {np.shape(s)}")
    with np.errstate(invalid="ignore"):
        term = ((x - mu_b) ** 2 - (x - mu_a) ** 2) / (2.0 * np.asarray(s) ** 2)
    return np.where(np.isfinite(term), term, 0.0).sum(axis=-1)


def noise_spread(ref_a: np.ndarray, ref_b: np.ndarray) -> np.ndarray:
    """Noise of one fiber per component: the copies of each hypothesis around their means.

    Pooled over all starts: a noise per start, from its few copies, is itself so
    noisy that the log-likelihood ratio weighted by it has heavy tails (on the
    flow-grid case the fibers needed grew from hundreds to 10^5).

    Parameters
    ----------
    ref_a, ref_b : ndarray, shape (k, n, c)
        Copies of each hypothesis at n starts (scoring scale; NaN where undefined
        or the run failed); k >= 2.

    Returns
    -------
    ndarray, shape (c,)
        The residual rms pooled over both hypotheses and all starts (k/(k-1)
        corrected), floored at 5 % of the component's spread over all copies and
        starts so that no component counts as noiseless (1 where even that is 0
        or undefined).
    """
    k = ref_a.shape[0]
    with warnings.catch_warnings():  # a component undefined at a start: NaN, as meant
        warnings.simplefilter("ignore", RuntimeWarning)
        resid = np.concatenate([ref_a - np.nanmean(ref_a, 0), ref_b - np.nanmean(ref_b, 0)])
        s = np.sqrt(np.nanmean(resid**2, axis=(0, 1)) * k / max(k - 1, 1))
        floor = np.nanstd(np.concatenate([ref_a, ref_b]), axis=(0, 1)) * 0.05
    s = np.where(np.isfinite(s), s, 0.0)
    floor = np.where(np.isfinite(floor) & (floor > 0), floor, 1.0)
    return np.maximum(s, floor)


@dataclass(frozen=True)
class SettleTest:
    """The two one-sided tests on the follow-up fibers (:func:`settle_test`).

    Attributes
    ----------
    per_fiber : ndarray, shape (n,)
        λ_i of each measured follow-up fiber (> 0: closer to A).
    statistic : float
        Λ = Σ λ_i.
    expected : (float, float)
        Mean of Λ under A and under B (from the null copies: n times the mean per
        fiber).
    spread : (float, float)
        Its standard deviation under A and under B (√n times the sd within a
        fiber's pool).
    p_values : (float, float)
        p of "A is true" (Λ as low or lower under A) and of "B is true".
    outcome : {'A', 'B', 'neither', 'undecided'}
    fibers_to_settle : int or None
        Fibers of the same discrimination for which each test rejects the false
        hypothesis with power 0.8 (None when the copies do not separate them).
    failed : int
        Copies (reference and null) left out because their run failed.
    """

    per_fiber: np.ndarray
    statistic: float
    expected: tuple[float, float]
    spread: tuple[float, float]
    p_values: tuple[float, float]
    outcome: str
    fibers_to_settle: int | None
    failed: int = 0


def settle_test(
    x: np.ndarray,
    ref_a: np.ndarray,
    ref_b: np.ndarray,
    null_a: np.ndarray,
    null_b: np.ndarray,
    rng: np.random.Generator,
    alpha: float = 0.05,
    n_draws: int = N_DRAWS,
    ok: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None,
) -> SettleTest:
    """Test A against B on measured fibers, with copies of each.

    Parameters
    ----------
    x : ndarray, shape (n, c)
        The measured fibers' components (scoring scale; NaN where undefined); n >= 1.
    ref_a, ref_b : ndarray, shape (k_ref, n, c)
        Reference copies of each hypothesis at the fibers' starts (their means
        and spread define λ).
    null_a, null_b : ndarray, shape (k_null, n, c)
        Independent copies of each hypothesis: the null distributions.
    rng : Generator
        For the null draws of Λ.
    alpha : float
        Level of each one-sided test.
    n_draws : int
        Null draws of Λ per hypothesis.
    ok : (ndarray, ndarray, ndarray, ndarray) of bool, optional
        Which runs of ref_a, ref_b, null_a, null_b did not fail, shapes (k, n);
        default all. A failed run is left out; an undefined outcome is not.

    Returns
    -------
    SettleTest
    """
    x = np.asarray(x, dtype=np.float64)
    if x.ndim != 2 or x.shape[0] < 1:
        raise ValueError(f"x must have shape (n, c) with n >= 1, got {x.shape}")
    n, c = x.shape
    sets = [np.array(a, dtype=np.float64) for a in (ref_a, ref_b, null_a, null_b)]
    for name, arr in zip(("ref_a", "ref_b", "null_a", "null_b"), sets, strict=True):
        if arr.ndim != 3 or arr.shape[1:] != (n, c):
            raise ValueError(f"{name} must have shape (k, {n}, {c}), got {arr.shape}")
        if len(arr) < 2:
            raise ValueError(f"{name} needs at least 2 copies, got {len(arr)}")
    masks = _masks(sets, ok)
    mu_a, mu_b, s, pools = _null_pools(sets, masks)
    lam = discriminant(x, mu_a, mu_b, s)
    stat = float(lam.sum())
    draws = [_sum_draws(lam, p, rng, n_draws) for p in pools]
    p_a = float(np.mean(draws[0] <= stat))
    p_b = float(np.mean(draws[1] >= stat))
    rej_a, rej_b = p_a <= alpha, p_b <= alpha
    outcome = {(False, True): "A", (True, False): "B", (True, True): "neither"}.get(
        (bool(rej_a), bool(rej_b)), "undecided"
    )
    (ga, sa), (gb, sb) = (_per_fiber(p) for p in pools)
    k_null = int(min(masks[2].sum(axis=0).min(), masks[3].sum(axis=0).min()))
    need = fibers_to_settle(ga - gb, sa, sb, alpha, k_null=k_null)
    failed = int(sum((~m).sum() for m in masks))
    return SettleTest(lam, stat, (n * ga, n * gb), (math.sqrt(n) * sa, math.sqrt(n) * sb),
                      (p_a, p_b), outcome, need, failed)  # fmt: skip


def _masks(sets: list[np.ndarray], ok: Sequence[np.ndarray] | None) -> list[np.ndarray]:
    """The runs that did not fail, shape (k, n) per copy set; their rows set to NaN in place."""
    masks = [np.ones(a.shape[:2], bool) for a in sets] if ok is None else [
        np.asarray(m, bool) for m in ok]  # fmt: skip
    for arr, m in zip(sets, masks, strict=True):
        if m.shape != arr.shape[:2]:
            raise ValueError(f"an ok mask must have shape {arr.shape[:2]}, got {m.shape}")
        arr[~m] = np.nan  # a failed run: no outcome
    return masks


def _null_pools(
    sets: list[np.ndarray], masks: list[np.ndarray]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[list[np.ndarray]]]:
    """λ's definition from the reference copies, and each fiber's null λ under A and B.

    ``sets``: ref_a, ref_b, null_a, null_b (failed runs NaN), ``masks`` their runs that
    did not fail. Returns the reference means (n, c) of A and B, the noise (c,), and
    per hypothesis a list of n arrays: the λ of the fiber's valid null copies.
    """
    ra, rb, na, nb = sets
    with warnings.catch_warnings():  # all copies undefined at a start: NaN mean, adds 0
        warnings.simplefilter("ignore", RuntimeWarning)
        mu_a, mu_b = np.nanmean(ra, axis=0), np.nanmean(rb, axis=0)
    s = noise_spread(ra, rb)
    pools = []
    for null, m in ((na, masks[2]), (nb, masks[3])):
        lam_k = discriminant(null, mu_a, mu_b, s)
        pools.append([lam_k[m[:, i], i] for i in range(lam_k.shape[1])])
    return mu_a, mu_b, s, pools


def _per_fiber(pools: list[np.ndarray]) -> tuple[float, float]:
    """λ's mean and sd within a fiber's pool, averaged over the fibers with two or more
    values (mean of the means; root of the mean variance); NaN when none has."""
    used = [q for q in pools if len(q) > 1]
    if not used:
        return np.nan, np.nan
    return float(np.mean([q.mean() for q in used])), math.sqrt(
        float(np.mean([q.var(ddof=1) for q in used]))
    )


def _sum_draws(
    lam: np.ndarray, pools: list[np.ndarray], rng: np.random.Generator, n_draws: int
) -> np.ndarray:
    """Null draws of Λ: per fiber one value of its pool, the measured λ_i among them.

    With the measured value in each pool (as a permutation test keeps the observed
    designation among its draws) the test is exact under exchangeability, however
    few the copies; drawing from the k copies alone gives a null whose variance is
    (k - 1)/k of the copies' (an anti-conservative test). A fiber with no valid
    copy contributes its own λ_i to every draw.

    Returns
    -------
    ndarray, shape (n_draws + 1,)
        The draws and Λ itself.
    """
    total = np.zeros(n_draws)
    for i, q in enumerate(pools):
        pool = np.concatenate([[lam[i]], q])
        total += pool[rng.integers(0, len(pool), size=n_draws)]
    return np.concatenate([total, [lam.sum()]])


def fibers_to_settle(
    gap: float,
    sd_a: float,
    sd_b: float,
    alpha: float,
    power: float = 0.8,
    k_null: int | None = None,
) -> int | None:
    """Fibers for which each one-sided test rejects the false hypothesis with ``power``.

    Per fiber λ has mean g_H and sd σ_H under hypothesis H (``gap`` = g_A - g_B).
    Rejecting B when A is true needs N gap >= √N (z_{1-alpha} σ_B + z_power σ_A),
    and the reverse with A and B swapped; the larger N of the two. With
    ``k_null`` null copies per fiber, the measured λ_i in each pool pulls the
    null towards it by 1/(k_null + 1) of the gap: N grows by ((k+1)/k)².

    Returns
    -------
    int or None
        None when nothing separates them (gap <= 0), or the inputs are not finite.
    """
    if not all(np.isfinite(v) for v in (gap, sd_a, sd_b)) or gap <= 0.0:
        return None
    za, zp = norm.ppf(1 - alpha), norm.ppf(power)
    worst = max(za * sd_b + zp * sd_a, za * sd_a + zp * sd_b)
    pull = 1.0 if not k_null else ((k_null + 1) / k_null) ** 2
    return max(1, int(math.ceil(pull * (worst / gap) ** 2)))


def window_separation(
    ref_a: np.ndarray,
    ref_b: np.ndarray,
    null_a: np.ndarray,
    null_b: np.ndarray,
    ok: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None,
) -> tuple[float, float, float, float]:
    """λ of one fiber measured anywhere in a window, under A and under B.

    Parameters
    ----------
    ref_a, ref_b : ndarray, shape (k_ref, m, c)
        Reference copies at m points of the window (means and spread, as the test).
    null_a, null_b : ndarray, shape (k_null, m, c)
        Independent copies there.
    ok : as :func:`settle_test`
        Runs that did not fail (default all).

    Returns
    -------
    (g_A, g_B, sd_A, sd_B)
        λ's mean and its sd within a point, averaged over the points, under each
        hypothesis, exactly as :func:`settle_test` reads them per fiber: a fiber at
        a random point of the window.
        :func:`fibers_to_settle` of them is what the test would need there. NaN for a
        hypothesis with fewer than two valid copies at every point.
    """
    sets = [np.array(a, dtype=np.float64) for a in (ref_a, ref_b, null_a, null_b)]
    *_, pools = _null_pools(sets, _masks(sets, ok))
    (ga, sa), (gb, sb) = (_per_fiber(p) for p in pools)
    return ga, gb, sa, sb
