"""After the verdict: the power analysis and what to measure next, when they apply.

- verdict "no significant gap" or "unexplained": :func:`.power.analyse_power` on
  the measured starts (which effects could be present below which magnitudes,
  how many fibers would name the leading candidate);
- verdict ambiguous, two significant candidates left unexplained, or a fit
  whose halves disagree by more than a factor 2 (:func:`next_hypotheses`):
  :func:`discriminate` between the two hypotheses.

Both run within what the budget leaves (:func:`followup`); otherwise the
report says why not.

What to measure next
--------------------
Two hypotheses (e.g. the two effects of an ambiguous verdict at their fitted
values, or one effect at its two fold values when the halves disagree) are
simulated at a grid of candidate starts (θ0, y0, L spanning the measured
range) with the same copies (common random numbers, measurement noise
included). Per start and observable component the *discrimination* is

    D = |mean_k (x_A,k - x_B,k)| / s

(its square debiased by the variance of that mean over the k copies, averaged
before it is clipped at 0), with s the component's spread among the copies of
both hypotheses (noise of one measured fiber); a start's D is the root sum of
squares over its components. Two copies per start are enough to rank the grid,
not to size the measurement: the best of many noisy estimates overstates itself
(the winner's curse; on the flow-grid case 2.5 per fiber at the best start
against 0.2-0.3 from 16 new copies there).

So the ``CONFIRM_STARTS`` best starts are measured again: at ``CONFIRM_POINTS``
points each, uniform within ``WINDOW`` start-noise sd of the start (where a
fiber measured "at" it lands), with as many new copies per point as the
follow-up test uses, scored by that test's own statistic (the log-likelihood
ratio λ of :mod:`.settle`). A start's separation per fiber is
(g_A - g_B) / sd, λ's mean under each hypothesis over its sd, and the fibers
needed, shared over these starts, are those for which each of the follow-up
test's one-sided tests rejects the false hypothesis with the target power
(:func:`.settle.fibers_needed`). The count at the measured starts
(``fibers_needed_measured``) is of another kind, for comparison only: the
grid's two-copy D averaged over the measured starts, for a two-sided test with
known predictions, ``ceil(((z_{1 - alpha/2} + z_power) / D)²)``.

The follow-up fibers (``--followup``) then test the hypotheses
(:func:`settle_followup`, :mod:`.settle`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.stats import norm

from fibersweep.discrepancy.candidates import Candidate
from fibersweep.discrepancy.copies import CopyMaker, NoiseModel
from fibersweep.discrepancy.decide import HeldOut, Verdict
from fibersweep.discrepancy.observables import OBSERVABLES
from fibersweep.discrepancy.power import analyse_power
from fibersweep.discrepancy.schema import MeasuredData
from fibersweep.discrepancy.settings import DiscrepancySettings, Plan
from fibersweep.discrepancy.settle import (
    fibers_needed,
    hypothesis_copies,
    noise_spread,
    settle,
    settled_verdict,
    window_separation,
)
from fibersweep.discrepancy.simulate import Simulator

__all__ = [
    "POWER_BOOT",
    "Discrimination",
    "Suggestion",
    "component_names",
    "discriminate",
    "followup",
    "next_hypotheses",
    "settle_followup",
    "start_grid",
    "window_points",
]


#: Half-width of the window around a proposed start, in start-noise sd: the fibers
#: measured "at" a start are those whose measured start falls within it.
WINDOW = 3.0
#: Points per best start, and best starts, where what-to-measure-next measures the
#: separation again with the follow-up test's statistic.
CONFIRM_POINTS = 8
CONFIRM_STARTS = 5


def component_names(observables: Sequence[str]) -> list[str]:
    """Names of the columns of :func:`power.standardised_values` (e.g. 'class=Above')."""
    out = []
    for name in (o for o in OBSERVABLES if o in observables and OBSERVABLES[o].scored):
        o = OBSERVABLES[name]
        out += [f"{name}={c}" for c in o.categories] if o.categorical else [name]
    return out


@dataclass(frozen=True)
class Suggestion:
    """One start worth measuring.

    Attributes
    ----------
    theta0, y0, length : float
        Start [deg], [/h_obs], [/l_obs].
    d : float
        Discrimination (standardised prediction difference) of one fiber there.
    observable : str
        The component that discriminates most there.
    a, b : float
        The two hypotheses' mean predictions of that component (its scoring scale).
    """

    theta0: float
    y0: float
    length: float
    d: float
    observable: str
    a: float
    b: float


@dataclass(frozen=True)
class Discrimination:
    """Where two hypotheses differ most.

    Attributes
    ----------
    labels : (str, str)
        The hypotheses, e.g. ('inlet_speed = -0.06', 'off_midplane = 0.1').
    grid : ndarray, shape (g, 3)
        Candidate starts.
    d : ndarray, shape (g,)
        Discrimination of one fiber at each start (``copies`` copies).
    best : list of Suggestion
        The best starts, most discriminating first (by the window's estimate).
    fibers_needed : int or None
        Fibers within the window of the best starts that settle it (None when
        nothing discriminates).
    fibers_needed_measured : int or None
        The same at the measured starts (their mean D²).
    simulations : int
    window : ndarray, shape (3,), or None
        Half-width (θ0 [deg], y0 [/h_obs], L [/l_obs]) of the window around each
        best start within which its ``d`` and ``fibers_needed`` hold; None: at the
        start itself, from the grid's copies.
    """

    labels: tuple[str, str]
    grid: np.ndarray
    d: np.ndarray
    best: list[Suggestion]
    fibers_needed: int | None
    fibers_needed_measured: int | None
    simulations: int
    window: np.ndarray | None = None


def start_grid(starts: np.ndarray, n_theta: int = 5, n_y: int = 8, n_len: int = 3) -> np.ndarray:
    """A regular grid spanning the measured starts; an axis that does not vary keeps its value.

    Returns
    -------
    ndarray, shape (g, 3)
        theta0 [deg], y0 [/h_obs], length [/l_obs].
    """
    s = np.asarray(starts, dtype=np.float64)
    axes = []
    for j, k in enumerate((n_theta, n_y, n_len)):
        lo, hi = float(np.nanmin(s[:, j])), float(np.nanmax(s[:, j]))
        axes.append(np.linspace(lo, hi, k) if hi - lo > 1e-9 else np.array([lo]))
    g = np.meshgrid(*axes, indexing="ij")
    return np.column_stack([a.ravel() for a in g])


def _needed(d: float, alpha: float, power: float) -> int | None:
    if not np.isfinite(d) or d <= 1e-9:
        return None
    z = norm.ppf(1 - alpha / 2) + norm.ppf(power)
    return int(math.ceil((z / d) ** 2))


def _label(effects: Mapping[str, float]) -> str:
    return " + ".join(f"{k} = {v:.3g}" for k, v in effects.items()) or "baseline"


def _shift2(xa: np.ndarray, xb: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Unbiased squared standardised shift per point and component, shape (points, c).

    Paired (common random numbers) per-copy differences; their mean squared, less the
    noise of that mean (its variance). Unclipped: negative where noise exceeds the
    shift. Average before clipping at 0; clipping each point first biases the average
    up (four-fold for a shift of 0.5 noise sd with two copies).
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        delta = (xa - xb) / s
        cnt = np.isfinite(delta).sum(axis=0)
        mean = np.where(cnt > 0, np.nansum(delta, axis=0) / np.maximum(cnt, 1), np.nan)
        ss = np.nansum((delta - mean) ** 2, axis=0)
        var = np.where(cnt > 1, ss / np.maximum(cnt - 1, 1) / np.maximum(cnt, 1), 0.0)
    diff = np.where(np.isfinite(mean), mean, 0.0)
    return diff**2 - np.where(np.isfinite(var), var, 0.0)


def window_points(
    centres: np.ndarray, noise: NoiseModel, m: int, rng: np.random.Generator, width: float = WINDOW
) -> np.ndarray:
    """``m`` starts uniform within ``width`` start-noise sd of each centre.

    Returns
    -------
    ndarray, shape (len(centres) * m, 3)
        Centre j's points are rows j*m .. j*m + m - 1.
    """
    c = np.repeat(np.asarray(centres, dtype=np.float64), m, axis=0)
    half = width * np.array([noise.theta0, noise.y0, noise.length])
    return c + rng.uniform(-1.0, 1.0, size=c.shape) * half


def discriminate(
    sim: Simulator,
    noise: NoiseModel,
    hypotheses: tuple[Mapping[str, float], Mapping[str, float]],
    starts: np.ndarray,
    observables: Sequence[str],
    seed: int = 0,
    copies: int = 2,
    grid: np.ndarray | None = None,
    top: int = 8,
    alpha: float = 0.05,
    power: float = 0.8,
    show: Callable[[Mapping[str, float]], str] | None = None,
    confirm: int = CONFIRM_POINTS,
    confirm_starts: int = CONFIRM_STARTS,
    confirm_copies: int = 24,
) -> Discrimination:
    """Rank candidate starts by how well one fiber there separates the hypotheses.

    Parameters
    ----------
    sim : Simulator
    noise : NoiseModel
        Measurement model (start and outcome noise) of the copies.
    hypotheses : (mapping, mapping)
        The two sets of effects to separate.
    starts : ndarray, shape (n, 3)
        Measured starts (the grid spans them; also scored for the comparison).
    observables : sequence of str
        Observables that would be measured.
    copies : int
        Copies per hypothesis and grid start (>= 2): enough to rank them.
    show : callable, optional
        ``{name: value} -> text`` for the two labels (each value in its
        candidate's unit); default ``name = value``.
    confirm, confirm_starts, confirm_copies : int
        The ``confirm_starts`` best grid starts are measured again at ``confirm``
        points each, uniform within ``WINDOW`` start-noise sd (where a fiber
        measured "at" the start lands), with ``confirm_copies`` new copies per
        point and hypothesis, scored by the follow-up test's own statistic
        (:func:`.settle.window_separation`): their separation per fiber and the
        fibers needed are those of :func:`.settle.settle_test` (``confirm`` 0:
        the grid's estimates, optimistic by the winner's curse).
    """
    label = show or _label
    if copies < 2:
        raise ValueError(f"copies must be >= 2, got {copies}")
    g = start_grid(starts) if grid is None else np.asarray(grid, dtype=np.float64)
    pts = np.vstack([g, np.asarray(starts, dtype=np.float64)])
    used0 = sim.used
    xa, xb, _, _ = hypothesis_copies(CopyMaker(pts, noise, seed + 104729, sim), hypotheses,
                                     copies, observables, "next")  # fmt: skip
    raw = _shift2(xa, xb, noise_spread(xa, xb))  # (points, components), unclipped
    ng = len(g)
    d = np.sqrt(np.clip(raw[:ng], 0.0, None).sum(axis=1))  # ranks the grid
    order = np.argsort(-d)[:top]
    d_best = d[order]
    need = _needed(float(np.sqrt(max(raw[order].sum(axis=1).mean(), 0.0))), alpha, power)
    window = None
    if confirm and len(order):
        order = order[:confirm_starts]
        k_ref = max(confirm_copies, 6) // 3
        w = window_points(g[order], noise, confirm, np.random.default_rng([seed, 104743]))
        wa, wb, oka, okb = hypothesis_copies(CopyMaker(w, noise, seed + 104759, sim), hypotheses,
                                             max(confirm_copies, 6), observables,
                                             "next: confirm")  # fmt: skip
        sep = []  # per start: g_A, g_B, sd_A, sd_B
        for j in range(len(order)):
            sl = slice(j * confirm, (j + 1) * confirm)
            ok = (oka[:k_ref, sl], okb[:k_ref, sl], oka[k_ref:, sl], okb[k_ref:, sl])
            sep.append(window_separation(wa[:k_ref, sl], wb[:k_ref, sl], wa[k_ref:, sl],
                                         wb[k_ref:, sl], ok=ok))  # fmt: skip
        sep = np.nan_to_num(np.array(sep))  # a side without two valid copies: no separation
        gap = sep[:, 0] - sep[:, 1]
        sd = np.sqrt((sep[:, 2] ** 2 + sep[:, 3] ** 2) / 2)
        d_best = np.where(sd > 0, np.clip(gap, 0.0, None) / np.where(sd > 0, sd, 1.0), 0.0)
        resort = np.argsort(-d_best, kind="stable")
        order, d_best = order[resort], d_best[resort]
        # fibers shared equally over these starts: all their points at once, as the
        # follow-up test scores them (its noise floor is over all its fibers)
        ok = (oka[:k_ref], okb[:k_ref], oka[k_ref:], okb[k_ref:])
        g_a, g_b, sd_a, sd_b = window_separation(wa[:k_ref], wb[:k_ref], wa[k_ref:],
                                                 wb[k_ref:], ok=ok)  # fmt: skip
        need = fibers_needed(g_a - g_b, sd_a, sd_b, alpha, power,
                             k_null=max(confirm_copies, 6) - k_ref)  # fmt: skip
        window = WINDOW * np.array([noise.theta0, noise.y0, noise.length])
    names = component_names(observables)
    best = []
    for i, di in zip(order, d_best, strict=True):
        j = int(np.argmax(raw[i]))  # the component that separates most there, on the grid
        best.append(
            Suggestion(
                float(g[i, 0]),
                float(g[i, 1]),
                float(g[i, 2]),
                float(di),
                names[j],
                float(np.nanmean(xa[:, i, j])),
                float(np.nanmean(xb[:, i, j])),
            )  # fmt: skip
        )
    meas2 = raw[ng:].sum(axis=1)
    d_m = float(np.sqrt(max(np.mean(meas2), 0.0))) if len(meas2) else 0.0
    return Discrimination(
        labels=(label(hypotheses[0]) or "baseline", label(hypotheses[1]) or "baseline"),
        grid=g,
        d=d,
        best=best,
        fibers_needed=need,
        fibers_needed_measured=_needed(d_m, alpha, power),
        simulations=sim.used - used0,
        window=window,
    )


#: Bootstrap resamples of the simulated starts behind each detection limit's interval
#: (no new runs; about a minute of scoring with all seven effects on 40 starts).
POWER_BOOT = 30


def _weak(values: list[float]) -> bool:
    """The two folds' fits disagree by more than a factor 2 (or in sign)."""
    a, b = values
    if a == b:
        return False
    if a * b <= 0:
        return True
    return max(abs(a), abs(b)) > 2 * min(abs(a), abs(b))


def next_hypotheses(
    verdict: Verdict,
    heldout: list[HeldOut],
    fold_values: dict[str, list[float]],
    show: Callable[[Mapping[str, float]], str] | None = None,
) -> tuple[dict[str, float], dict[str, float], str] | None:
    """The two hypotheses what-to-measure-next should separate, and why (None: nothing).

    Ambiguous: its first two alternatives. Unexplained with two significant
    candidates: those two. Otherwise a weakly identified fit (the named or the
    best candidate's two fold values differ by more than a factor 2): the
    effect at each fold value. Otherwise, unexplained: the model as it is
    against the candidate that helped most out of sample (at its value, or the
    mean of its nonzero fold values), so the report says at which starts, and
    with how many fibers, that candidate would be confirmed or ruled out.
    ``show``: ``{name: value} -> text`` for the reason (each value in its
    candidate's unit, :func:`.candidates.show_values`); default ``name = value``.
    """
    show = show or _label
    if verdict.kind == "ambiguous" and len(verdict.alternatives) >= 2:
        a, b = verdict.alternatives[:2]
        return dict(a), dict(b), "the verdict is ambiguous"
    sig = sorted((h for h in heldout if h.significant), key=lambda h: -h.improvement[0])
    if verdict.kind == "unexplained" and len(sig) >= 2:
        return (
            {sig[0].name: sig[0].value},
            {sig[1].name: sig[1].value},
            ("two candidates each improve the fit significantly"),
        )
    name = next(iter(verdict.effects), None) if verdict.kind == "named" else None
    if name is None and heldout:
        name = max(heldout, key=lambda h: h.improvement[0]).name
    if name is not None and name in fold_values and _weak(fold_values[name]):
        v0, v1 = fold_values[name]
        return (
            {name: v0},
            {name: v1},
            f"the two halves fit {show({name: v0})} and {show({name: v1})}",
        )
    if verdict.kind == "unexplained" and heldout:
        # the doubt of an unexplained gap: is the candidate that helped most there or
        # not? The starts where its prediction departs most from the model as it is
        # test it fastest
        best = max(heldout, key=lambda h: h.improvement[0])
        v = best.value if best.value != 0.0 else _mean_nonzero(fold_values.get(best.name, []))
        if v != 0.0:
            return (
                {},
                {best.name: v},
                (
                    f"the gap is unexplained; {show({best.name: v})} helped most out of sample "
                    f"(p Holm {best.p_holm:.2g}): these starts test it against the model as it is"
                ),
            )
    return None


def _mean_nonzero(values: list[float]) -> float:
    """Mean of the nonzero fold values (0 when there are none)."""
    nz = [v for v in values if v != 0.0]
    return float(np.mean(nz)) if nz else 0.0


def followup(
    verdict: Verdict,
    heldout: list[HeldOut],
    fold_values: dict[str, list[float]],
    candidates: Sequence[Candidate],
    maker: CopyMaker,
    sim: Simulator,
    plan: Plan,
    s: DiscrepancySettings,
    obs: tuple[str, ...],
    rng: np.random.Generator,
    show: Callable[[Mapping[str, float]], str] | None = None,
) -> dict[str, Any]:
    """Power analysis and what-to-measure-next, when they apply and the budget allows.

    Parameters
    ----------
    plan : Plan
        Its ``copies`` (the ensemble the power analysis scales to).
    s : DiscrepancySettings
        ``power_fibers``, ``next_copies``, ``noise``, ``seed``, ``alpha``.
    show : callable, optional
        ``{name: value} -> text`` (each value in its candidate's unit) for the
        reason and the hypotheses' labels.

    Returns
    -------
    dict
        ``power`` (PowerResult), ``next`` (Discrimination) and ``next_reason``,
        or ``power_skipped`` / ``next_skipped`` with the reason.
    """
    out: dict[str, Any] = {}
    if s.power_fibers and verdict.kind in ("no significant gap", "unexplained"):
        n_sim = min(s.power_fibers, maker.n)
        cost = 3 * n_sim * 2 * sum(len(c.probes) for c in candidates)
        if cost <= sim.remaining:
            out["power"] = analyse_power(
                maker, candidates, maker.n, obs, rng, n_sim=n_sim,
                workflow_copies=plan.copies, alpha=s.alpha, n_boot=POWER_BOOT,
            )  # fmt: skip
        else:
            out["power_skipped"] = f"the budget leaves {sim.remaining} runs, it needs {cost}"
    hyp = next_hypotheses(verdict, heldout, fold_values, show) if s.next_copies else None
    if hyp is not None:
        a, b, why = hyp
        grid = start_grid(maker.starts)
        # + the best starts measured again in their windows
        again = 2 * s.settle_copies * CONFIRM_POINTS * min(CONFIRM_STARTS, len(grid))
        cost = 2 * s.next_copies * (len(grid) + maker.n) + again
        if cost <= sim.remaining:
            out["next"] = discriminate(
                sim, s.noise, (a, b), maker.starts, obs, seed=s.seed,
                copies=s.next_copies, grid=grid, alpha=s.alpha, show=show,
                confirm_copies=s.settle_copies,
            )  # fmt: skip
            out["next_reason"] = why
        else:
            out["next_skipped"] = f"the budget leaves {sim.remaining} runs, it needs {cost}"
    return out


def settle_followup(
    verdict: Verdict,
    heldout: Sequence[HeldOut],
    fold_values: Mapping[str, list[float]],
    followup: MeasuredData,
    sim: Simulator,
    s: DiscrepancySettings,
    observables: Sequence[str],
    show: Callable[[Mapping[str, float]], str] | None = None,
) -> tuple[Verdict, dict[str, Any]]:
    """The verdict's two-way question (:func:`.followup.next_hypotheses`) put to follow-up fibers.

    Parameters
    ----------
    verdict, heldout, fold_values
        The analysis of the first fibers.
    followup : MeasuredData
        Fibers measured after it (typically at the starts what-to-measure-next gave).
    s : DiscrepancySettings
        ``settle_copies``, ``noise``, ``seed``, ``alpha``.
    observables : sequence of str
        The first fibers' observables; those the follow-up table also has are scored.
    show : callable, optional
        ``{name: value} -> text`` for the labels (each value in its candidate's unit).

    Returns
    -------
    verdict : Verdict
        :func:`settled_verdict`.
    extra : dict
        ``settle`` (Settlement), or ``settle_skipped`` with the reason.
    """
    label = show or _label
    hyp = next_hypotheses(verdict, list(heldout), dict(fold_values), show)
    if hyp is None:
        why = f"the verdict ({verdict.kind}) leaves no two hypotheses to separate"
        return verdict, {"settle_skipped": why}
    obs = tuple(o for o in observables if o in followup.observed)
    if not obs:
        why = f"the follow-up fibers measure none of {', '.join(observables)}"
        return verdict, {"settle_skipped": why}
    cost = 2 * s.settle_copies * len(followup)
    if cost > sim.remaining:
        why = f"the budget leaves {sim.remaining} runs, it needs {cost}"
        return verdict, {"settle_skipped": why}
    a, b, why = hyp
    st = settle(
        sim, s.noise, (a, b), (label(a) or "baseline", label(b) or "baseline"), why,
        followup.table.reset_index(drop=True), followup.starts, obs,
        np.random.default_rng([s.seed, 23]), seed=s.seed, copies=s.settle_copies, alpha=s.alpha,
        n_perm=s.n_perm,
    )  # fmt: skip
    return settled_verdict(verdict, st), {"settle": st}
