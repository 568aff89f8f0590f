"""Settling the verdict's two-way question on fibers measured for it.

When the verdict leaves two hypotheses (ambiguous between A and B, or the other
cases of :func:`.followup.next_hypotheses`), what-to-measure-next proposes the
starts where they differ most. Fibers measured afterwards (``--followup``), used
by no fit, test the two hypotheses against each other directly; the analysis of
the first fibers is left as it was.

The test
--------
Per follow-up fiber i and scored component c (:func:`.power.standardised_values`),
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
discriminating fibers: the report says how many such fibers would do). The test looks along the
difference of the two predictions only, so the winner is then checked on the
follow-up fibers as every fitted effect is on the first ones
(:func:`.gap.assess_gap` against its copies): a significant gap left, and it
is not named.

Why not paired comparisons on the first fibers: there each hypothesis was
fitted to the same fibers, and common random numbers favour whichever copies
happen to look like them (:mod:`.decide`); here the hypotheses are fixed
before the follow-up fibers are seen.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.stats import norm

from fibersweep.discrepancy.copies import CopyMaker, NoiseModel
from fibersweep.discrepancy.decide import Verdict
from fibersweep.discrepancy.gap import GapResult, assess_gap, value_matrices
from fibersweep.discrepancy.power import standardised_values
from fibersweep.discrepancy.simulate import Simulator

__all__ = [
    "Settlement",
    "SettleTest",
    "copy_values",
    "discriminant",
    "fibers_needed",
    "hypothesis_copies",
    "noise_spread",
    "settle",
    "settle_test",
    "settled_verdict",
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


def copy_values(
    cps: Sequence[pd.DataFrame], observables: Sequence[str]
) -> tuple[np.ndarray, np.ndarray]:
    """Copies on the scoring scale, with the runs that failed marked.

    Parameters
    ----------
    cps : sequence of DataFrame
        k copies of n fibers (:meth:`.copies.CopyMaker.copies`).

    Returns
    -------
    values : ndarray, shape (k, n, c)
        :func:`.power.standardised_values`; a failed run's row is NaN.
    ok : ndarray of bool, shape (k, n)
        The run did not fail (``status == 'ok'``). A failed run is no outcome; an
        outcome undefined by its observable's rule (no contact) is one.
    """
    vals = np.stack(standardised_values(list(cps), observables))
    ok = np.stack([(c["status"] == "ok").to_numpy() if "status" in c
                   else np.ones(len(c), bool) for c in cps])  # fmt: skip
    vals[~ok] = np.nan
    return vals, ok


def hypothesis_copies(
    maker: CopyMaker,
    hypotheses: tuple[Mapping[str, float], Mapping[str, float]],
    copies: int,
    observables: Sequence[str],
    tag: str,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Both hypotheses' copies at the maker's starts (common random numbers).

    Returns
    -------
    values_a, values_b : ndarray, shape (copies, n, c)
    ok_a, ok_b : ndarray of bool, shape (copies, n)
        As :func:`copy_values`.
    """
    (va, oka), (vb, okb) = (
        copy_values(maker.copies(range(copies), dict(h), desc=f"{tag}: {t}"), observables)
        for h, t in zip(hypotheses, "AB", strict=True)
    )
    return va, vb, oka, okb


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
    fibers_needed : int or None
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
    fibers_needed: int | None
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
    need = fibers_needed(ga - gb, sa, sb, alpha, k_null=k_null)
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


def fibers_needed(
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
        :func:`fibers_needed` of them is what the test would need there. NaN for a
        hypothesis with fewer than two valid copies at every point.
    """
    sets = [np.array(a, dtype=np.float64) for a in (ref_a, ref_b, null_a, null_b)]
    *_, pools = _null_pools(sets, _masks(sets, ok))
    (ga, sa), (gb, sb) = (_per_fiber(p) for p in pools)
    return ga, gb, sa, sb


@dataclass(frozen=True)
class Settlement:
    """The follow-up fibers' answer to the verdict's two-way question.

    Attributes
    ----------
    labels : (str, str)
        The hypotheses, e.g. ('flow.dx = 5 µm', 'off_midplane = 0.068').
    hypotheses : (dict, dict)
        Their effects (name -> value in the fit's scale).
    reason : str
        Why these two (as what-to-measure-next says).
    n : int
        Follow-up fibers.
    observables : tuple of str
        Observables scored (those the follow-up table has).
    test : SettleTest
    simulations : int
    adequacy : GapResult or None
        The winner (outcome A or B) checked on the follow-up fibers against
        all its copies (:func:`.gap.assess_gap`); None otherwise.
    """

    labels: tuple[str, str]
    hypotheses: tuple[dict[str, float], dict[str, float]]
    reason: str
    n: int
    observables: tuple[str, ...]
    test: SettleTest
    simulations: int
    adequacy: GapResult | None = None

    @property
    def outcome(self) -> str:
        return self.test.outcome

    @property
    def settled(self) -> bool:
        """One hypothesis rejected, the other not, and no significant gap left by it."""
        return self.outcome in ("A", "B") and self.adequacy is not None and not self.adequacy.any

    def text(self) -> str:
        """One sentence: what the follow-up fibers say."""
        a, b = self.labels
        pa, pb = self.test.p_values
        tail = f"(p {pa:.2g} for {a}, p {pb:.2g} for {b})"
        if self.outcome in ("A", "B"):
            win, lose = (a, b) if self.outcome == "A" else (b, a)
            if self.settled:
                return (
                    f"the {self.n} follow-up fibers reject {lose} and are consistent with "
                    f"{win} {tail}"
                )
            left = ", ".join(self.adequacy.flagged) if self.adequacy is not None else "?"
            return (
                f"the {self.n} follow-up fibers reject {lose}; {win} is closer to them but "
                f"leaves a significant gap in {left} {tail}"
            )
        if self.outcome == "neither":
            return f"the {self.n} follow-up fibers lie between {a} and {b}, rejecting both {tail}"
        need = self.test.fibers_needed
        more = f"; about {need} such fibers would separate them" if need else ""
        return f"the {self.n} follow-up fibers do not separate {a} from {b} {tail}{more}"


def settle(
    sim: Simulator,
    noise: NoiseModel,
    hypotheses: tuple[Mapping[str, float], Mapping[str, float]],
    labels: tuple[str, str],
    reason: str,
    table: pd.DataFrame,
    starts: np.ndarray,
    observables: Sequence[str],
    rng: np.random.Generator,
    seed: int = 0,
    copies: int = 24,
    alpha: float = 0.05,
    n_perm: int = 4999,
) -> Settlement:
    """Simulate both hypotheses at the follow-up fibers' starts and test them.

    Parameters
    ----------
    sim : Simulator
    noise : NoiseModel
        Measurement model of the copies (start and outcome noise).
    hypotheses : (mapping, mapping)
        The two sets of effects (fixed: fitted on the first fibers).
    labels, reason : as :class:`Settlement`
    table : DataFrame
        The follow-up fibers (observed columns by observable name).
    starts : ndarray, shape (n, 3)
        Their starts: theta0 [deg], y0 [/h_obs], length [/l_obs].
    observables : sequence of str
        Observables to score (present in ``table``).
    copies : int
        Copies per hypothesis and fiber: a third for the reference means, the
        rest for the null distributions (>= 6).
    rng : Generator
        For the test's null draws and the winner's permutations.
    seed : int
        Seeds the copies (the same seed gives the same copies).
    alpha : float
        Level of each one-sided test and of the winner's gap test.
    n_perm : int
        Permutations of the winner's gap test.

    Returns
    -------
    Settlement
    """
    if copies < 6:
        raise ValueError(f"copies must be >= 6, got {copies}")
    k_ref = copies // 3
    used0 = sim.used
    # common random numbers between A and B; reference and null copies are independent
    maker = CopyMaker(starts, noise, seed + 15485863, sim)
    cps = [
        maker.copies(range(copies), dict(h), desc=f"follow-up: {tag}")
        for h, tag in zip(hypotheses, "AB", strict=True)
    ]
    (va, oka), (vb, okb) = (copy_values(c, observables) for c in cps)
    x = standardised_values([table], observables)[0]
    test = settle_test(x, va[:k_ref], vb[:k_ref], va[k_ref:], vb[k_ref:], rng, alpha,
                       ok=(oka[:k_ref], okb[:k_ref], oka[k_ref:], okb[k_ref:]))  # fmt: skip
    adequacy = None
    if test.outcome in ("A", "B"):
        win = cps[0 if test.outcome == "A" else 1]
        adequacy = assess_gap(value_matrices(table, win, observables), rng, alpha=alpha,
                              n_perm=n_perm)  # fmt: skip
    return Settlement(
        labels=labels,
        hypotheses=(dict(hypotheses[0]), dict(hypotheses[1])),
        reason=reason,
        n=len(starts),
        observables=tuple(observables),
        test=test,
        simulations=sim.used - used0,
        adequacy=adequacy,
    )


def settled_verdict(verdict: Verdict, st: Settlement) -> Verdict:
    """The verdict after the follow-up fibers.

    An ambiguous verdict between exactly these two alternatives becomes "named"
    when the follow-up fibers reject one and the other leaves no significant gap
    on them (:attr:`Settlement.settled`); any other verdict
    (and any other outcome) stands, and the report gives the settlement beside it.
    """
    alts = [dict(a) for a in verdict.alternatives]
    if verdict.kind != "ambiguous" or not st.settled or alts != list(st.hypotheses):
        return verdict
    win = st.hypotheses[0 if st.outcome == "A" else 1]
    label = st.labels[0 if st.outcome == "A" else 1]
    text = f"{label}: {st.text()}. On the first fibers alone: {verdict.text}"
    return Verdict("named", dict(win), verdict.observable, verdict.region, text, (dict(win),))
