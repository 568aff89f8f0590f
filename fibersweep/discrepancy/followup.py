"""After the verdict: the question it leaves, and the follow-ups that run when they apply.

- verdict "no significant gap" or "unexplained": :func:`.power.analyse_power` on
  the measured starts (which effects could be present below which magnitudes),
  and the fibers it says would do (:class:`PowerFibers`: to detect each effect
  at a realistic magnitude, to detect and to name the leading candidate);
- verdict ambiguous, two significant candidates left unexplained, or a fit
  whose halves disagree by more than a factor 2 (:func:`next_hypotheses`):
  :func:`.next_measure.discriminate` between the two hypotheses (what to
  measure next).

Both are sized before the analysis starts (:func:`followup_costs`, the plan
the command prints) and run within what the budget leaves (:func:`followup`);
one that does not fit is skipped, and the report says so and why. A stage
whose size depends on what it finds (the power analysis's re-reads) stops
reading again where the budget ends; a batch refused by the budget inside a
stage ends that stage only (:class:`.simulate.BudgetExhausted` is caught at
the stage's boundary), so the verdict and the report are always written. The
follow-up fibers (``--followup``) then test the hypotheses
(:func:`settle_followup`, :mod:`.settle`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.stats import norm

from fibersweep.discrepancy.candidates import LIBRARY, Candidate
from fibersweep.discrepancy.copies import CopyMaker
from fibersweep.discrepancy.decide import HeldOut, Verdict
from fibersweep.discrepancy.detection import PowerResult
from fibersweep.discrepancy.next_measure import (
    CONFIRM_POINTS,
    CONFIRM_STARTS,
    discriminate,
    hypothesis_label,
    start_grid,
)
from fibersweep.discrepancy.power import analyse_power, planned_runs
from fibersweep.discrepancy.schema import MeasuredData
from fibersweep.discrepancy.settings import DiscrepancySettings, Plan
from fibersweep.discrepancy.settle import settle, settled_verdict
from fibersweep.discrepancy.simulate import BudgetExhausted, Simulator

__all__ = [
    "POWER_BOOT",
    "POWER_COPIES",
    "FollowupCosts",
    "LeadingFibers",
    "PowerFibers",
    "fibers_to_name",
    "followup",
    "followup_costs",
    "next_hypotheses",
    "power_fibers",
    "settle_followup",
]


#: Bootstrap resamples of the simulated starts behind each detection limit's interval
#: (no new runs; about a minute of scoring with all seven effects on 40 starts).
POWER_BOOT = 30

#: Copies per magnitude of the workflow's power analysis (:func:`.power.analyse_power`).
POWER_COPIES = 3


@dataclass(frozen=True)
class FollowupCosts:
    """Runs of the stages after the verdict, known before the analysis starts.

    Attributes
    ----------
    power : int
        Runs the power analysis always asks for (0: off), the workflow's
        baseline copies it reuses not counted.
    power_more : int
        Most runs of its re-reads at the limits (they run only where a limit lies
        far from its probes, and only while the budget leaves room).
    next : int
        Most runs of what-to-measure-next (0: off): grid and measured starts
        under both hypotheses, and the best starts measured again.
    """

    power: int
    power_more: int
    next: int


def followup_costs(
    starts: np.ndarray, s: DiscrepancySettings, plan: Plan, candidates: Sequence[Candidate]
) -> FollowupCosts:
    """What each follow-up stage costs at most (see :class:`FollowupCosts`).

    Parameters
    ----------
    starts : ndarray, shape (n, 3)
        Measured starts (the power analysis simulates the first ``power_fibers``;
        what-to-measure-next's grid spans them).
    s : DiscrepancySettings
        ``power_fibers``, ``next_copies``, ``settle_copies``.
    plan : Plan
        Its ``copies``: the baseline copies the power analysis reuses.
    """
    n = len(starts)
    power = more = 0
    if s.power_fibers:
        n_sim = min(s.power_fibers, n)
        certain, more = planned_runs(candidates, n_sim, POWER_COPIES)
        power = certain - min(plan.copies, POWER_COPIES) * n_sim  # its baseline is held
    nxt = 0
    if s.next_copies:
        ng = len(start_grid(starts))
        again = 2 * s.settle_copies * CONFIRM_POINTS * min(CONFIRM_STARTS, ng)
        nxt = 2 * s.next_copies * (ng + n) + again
    return FollowupCosts(power, more, nxt)


def fibers_to_name(per_fiber: np.ndarray, k: int, alpha: float, power: float = 0.8) -> int | None:
    """Fibers whose held-out improvement would be significant with the target power.

    From the measured per-fiber improvement (mean mu, sd sigma): the one-sided test
    at alpha / k (Holm's first step over k candidates) reaches the power when
    ``sqrt(n) mu / sigma >= z_{1-alpha/k} + z_power``. None when mu <= 0.

    Parameters
    ----------
    per_fiber : ndarray, shape (n,)
        Held-out improvement of each fiber [copy-spread units]; NaN left out.
    k : int
        Candidates in the Holm family.
    """
    d = np.asarray(per_fiber, dtype=np.float64)
    d = d[np.isfinite(d)]
    if len(d) < 2 or d.mean() <= 0:
        return None
    z = norm.ppf(1 - alpha / max(k, 1)) + norm.ppf(power)
    return int(math.ceil((z * d.std(ddof=1) / d.mean()) ** 2))


@dataclass(frozen=True)
class LeadingFibers:
    """Fibers the leading candidate (the best held-out improvement) would need.

    Attributes
    ----------
    name : str
    value : float
        Its value (nonzero).
    fibers_to_detect : int or None
        Fibers whose gap tests detect it at ``value`` with the target power
        (:meth:`.detection.PowerResult.fibers_to_detect`; None: more than 100 000).
    fibers_to_detect_ci : (int or None, int or None) or None
        Their 95 % interval over the simulated starts
        (:meth:`.detection.PowerResult.fibers_to_detect_ci`).
    fibers_to_name : int or None
        Fibers whose held-out improvement would be significant (:func:`fibers_to_name`).
    """

    name: str
    value: float
    fibers_to_detect: int | None
    fibers_to_detect_ci: tuple[int | None, int | None] | None
    fibers_to_name: int | None


@dataclass(frozen=True)
class PowerFibers:
    """The fibers a power analysis says would do (the report's numbers, computed here).

    Attributes
    ----------
    realistic : tuple of (float or None, int or None)
        Per entry of ``PowerResult.effects``, in its order: a library effect's
        realistic magnitude in the probe's direction (None for a declared
        candidate) and the fibers that detect it with the target power (None:
        more than 100 000, or no realistic magnitude).
    leading : LeadingFibers or None
        The candidate that helped most out of sample, at a nonzero value; None
        when there is none.
    realistic_ci : tuple of ((int or None, int or None) or None)
        Per entry, the 95 % interval over the simulated starts of its fibers to
        detect the realistic magnitude (:meth:`.detection.PowerResult.fibers_to_detect_ci`;
        None: not computed; an end None: more than 100 000).
    """

    realistic: tuple[tuple[float | None, int | None], ...]
    leading: LeadingFibers | None
    realistic_ci: tuple[tuple[int | None, int | None] | None, ...] = ()


def power_fibers(pw: PowerResult, heldout: Sequence[HeldOut], alpha: float) -> PowerFibers:
    """The fibers to detect each effect at a realistic magnitude, and the leading candidate's.

    Parameters
    ----------
    pw : PowerResult
    heldout : sequence of HeldOut
        The held-out evaluation of every fitted candidate (its Holm family).
    alpha : float
        Family-wise level of the held-out decision.
    """
    realistic, real_ci = [], []
    for e in pw.effects:
        real = math.copysign(LIBRARY[e.name].realistic, e.probe) if e.name in LIBRARY else None
        realistic.append((real, pw.fibers_to_detect(e.name, real) if real else None))
        real_ci.append(pw.fibers_to_detect_ci(e.name, real) if real else None)
    lead = None
    if heldout:
        h = max(heldout, key=lambda h: h.improvement[0])
        if h.value != 0.0:
            lead = LeadingFibers(
                name=h.name,
                value=h.value,
                fibers_to_detect=pw.fibers_to_detect(h.name, h.value),
                fibers_to_detect_ci=pw.fibers_to_detect_ci(h.name, h.value),
                fibers_to_name=fibers_to_name(h.per_fiber, len(heldout), alpha, pw.power),
            )
    return PowerFibers(tuple(realistic), lead, tuple(real_ci))


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
    show = show or hypothesis_label
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
        ``power`` (:class:`.detection.PowerResult`) and ``power_fibers``
        (:class:`PowerFibers`), ``next`` (:class:`.result.Discrimination`)
        and ``next_reason``, or ``power_skipped`` / ``next_skipped`` with the reason
        (``"skipped: budget (...)"`` when the budget left too few runs);
        ``power_unread``: the limits not read again at the limit for the budget.
    """
    out: dict[str, Any] = {}
    costs = followup_costs(maker.starts, s, plan, candidates)
    if s.power_fibers and verdict.kind in ("no significant gap", "unexplained"):
        if costs.power <= sim.remaining:
            unread: list[str] = []
            try:
                out["power"] = analyse_power(
                    maker, candidates, maker.n, obs, rng, n_sim=min(s.power_fibers, maker.n),
                    copies=POWER_COPIES, workflow_copies=plan.copies, alpha=s.alpha,
                    n_boot=POWER_BOOT, unread=unread,
                )  # fmt: skip
                out["power_fibers"] = power_fibers(out["power"], heldout, s.alpha)
                if unread:
                    out["power_unread"] = unread
            except BudgetExhausted as err:  # a batch its plan did not foresee
                out["power_skipped"] = f"skipped: budget ({err})"
        else:
            out["power_skipped"] = _no_room(costs.power, sim.remaining)
    hyp = next_hypotheses(verdict, heldout, fold_values, show) if s.next_copies else None
    if hyp is not None:
        a, b, why = hyp
        if costs.next <= sim.remaining:
            try:
                out["next"] = discriminate(
                    sim, s.noise, (a, b), maker.starts, obs, seed=s.seed,
                    copies=s.next_copies, grid=start_grid(maker.starts), alpha=s.alpha,
                    show=show, confirm_copies=s.settle_copies,
                )  # fmt: skip
                out["next_reason"] = why
            except BudgetExhausted as err:
                out["next_skipped"] = f"skipped: budget ({err})"
        else:
            out["next_skipped"] = _no_room(costs.next, sim.remaining)
    return out


def _no_room(cost: int, left: float) -> str:
    """Why a stage did not run: the budget left too few runs."""
    return f"skipped: budget (it needs up to {cost} runs, the budget leaves {left:.0f})"


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
    label = show or hypothesis_label
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
        return verdict, {"settle_skipped": _no_room(cost, sim.remaining)}
    a, b, why = hyp
    try:
        st = settle(
            sim, s.noise, (a, b), (label(a) or "baseline", label(b) or "baseline"), why,
            followup.table.reset_index(drop=True), followup.starts, obs,
            np.random.default_rng([s.seed, 23]), seed=s.seed, copies=s.settle_copies,
            alpha=s.alpha, n_perm=s.n_perm,
        )  # fmt: skip
    except BudgetExhausted as err:  # the first verdict stands
        return verdict, {"settle_skipped": f"skipped: budget ({err})"}
    return settled_verdict(verdict, st), {"settle": st}
