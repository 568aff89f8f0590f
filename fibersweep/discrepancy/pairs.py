"""Two effects together: fitting a pair, and forward selection out of sample.

When the best single effect leaves a gap, other candidates B are added to the
significant effects A that leave one (the ``settings.PAIR_FIRSTS`` that improved
the held-out fibers most; each A must be significant alone, since from a
non-significant start a wrong A and a B that undoes A's side effect can look
like a pair; the set also needs each member's own contribution significant):

0. partners are ranked by their signature against the gap A leaves
   (:func:`.signatures.rank_partners`), not against the whole gap, which A
   dominates; and the loss also scores the observables A leaves with a gap
   (:func:`pair_weights`): B's part of the gap often shows only once A's is
   removed, and a loss blind to it can neither fit B nor see its contribution.
   The plan's pairs are taken in turn from each A's ranking (A1's best partner,
   A2's best, A1's second, ...; :func:`pair_trials`), a set of two effects
   tried once;
1. joint fit, on the same two folds as the single fits, by coordinate descent
   (:func:`joint_fit`): B is fitted with A at its single value, then A is
   refitted with B at that value, both on the training fold only;
2. cross-fitted copies with both effects on score the held-out fold;
3. each member's own contribution is the per-fiber improvement of the pair
   over the pair without it (over B alone for A, over A alone for B), tested
   by a one-sided bootstrap; the p-values of every member of every pair form
   one Holm family;
4. a pair whose members both contribute significantly is refitted on all
   fibers (:func:`pair_refits`: each member with the other held fixed, the
   same refit and interval a single effect's quoted value gets)
   and checked for adequacy there.

Pairs are tried in that order, and the step stops after the round in which a
pair explains the gap (significant contributions, no gap left): the other
first member's pair of that round is still tried, so that two look-alike first
members give two explaining sets and an ambiguous verdict, not whichever came
first. The Holm family is every member of every pair that may be tried, the
untried ones counted with p = 1: Holm is monotone in the p-values, so stopping
early never rejects more than trying every pair would.

The rule of :func:`.decide.decide` then names the pair when it leaves no
significant gap and no single effect explains the gap. Two effects are the
most this step adds: a third would need far more fibers.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from fibersweep.discrepancy.candidates import Candidate
from fibersweep.discrepancy.copies import CopyMaker, crossfit_copies
from fibersweep.discrepancy.decide import SetHeldOut
from fibersweep.discrepancy.estimate import Fit, score_interval
from fibersweep.discrepancy.fit import fit_effect, pooled_refit
from fibersweep.discrepancy.gap import (
    GapResult,
    assess_gap,
    paired_improvement,
    value_matrices,
    weighted_loss,
)
from fibersweep.discrepancy.scores import boot_p, bootstrap_mean_ci, holm

__all__ = [
    "PairTrial",
    "SelectionInput",
    "forward_pairs",
    "joint_fit",
    "pair_refits",
    "pair_trials",
    "pair_weights",
]

log = logging.getLogger(__name__)


def pair_weights(
    weights: Mapping[str, float], base_gap: GapResult, left: GapResult, alpha: float
) -> dict[str, float]:
    """Loss weights of the forward step.

    The single-effect step scores only the observables with a significant gap at
    baseline. A second effect often lives where the first one's gap hid it (a
    friction class gap under an inlet-speed t_pass gap: Holm over the family
    leaves it just above alpha), so the forward step also scores every observable
    that the best single effect leaves with a gap, significant or only nominally
    (raw p <= alpha, score or signed residual). The weights pick the loss; the
    held-out tests stay what guards the names.

    Parameters
    ----------
    weights : mapping observable -> float
        :func:`.gap.observable_weights` of the baseline copies (all observables).
    base_gap : GapResult
        Gap against the baseline (all fibers).
    left : GapResult
        Gap left by the best single effect (at its pooled value when checked).
    """
    keep = set(base_gap.flagged) | set(left.flagged)
    for g in left.gaps.values():
        if g.test.p_value <= alpha or any(q <= alpha for q in g.bias_p):
            keep.add(g.name)
    return {o: (w if o in keep else 0.0) for o, w in weights.items()}


@dataclass(frozen=True)
class SelectionInput:
    """What the forward step needs from the single-effect step.

    Attributes
    ----------
    observed : DataFrame
        Measured table (n rows).
    folds : sequence of ndarray
        The two folds of the cross-fitting.
    fold_values : dict name -> [value scoring fold 0, value scoring fold 1]
        Single-effect fits.
    base_values : dict observable -> ndarray (n, 1 + copies)
        :func:`.gap.value_matrices` of the baseline copies.
    single_values : dict name -> (observable -> ndarray (n, 1 + copies))
        The same with each single effect on (cross-fitted).
    weights : dict observable -> float
        Weights of the fit and decision loss of the pairs (:func:`pair_weights`).
    observables : tuple of str
    copies, fit_copies, fit_evals : int
        The plan's copies per evaluation, copies per fit evaluation, Brent steps.
    alpha : float
    n_perm : int
    rounds : int
        Coordinate-descent rounds of the joint fit (1: the added effect only,
        the first held at its single value; 2: then the first refitted too).
    refit_evals : int
        Brent steps of each member's pooled refit (:func:`pair_refits`; the
        workflow passes :attr:`.settings.Plan.refit_evals`).
    """

    observed: pd.DataFrame
    folds: Sequence[np.ndarray]
    fold_values: Mapping[str, Sequence[float]]
    base_values: Mapping[str, np.ndarray]
    single_values: Mapping[str, Mapping[str, np.ndarray]]
    weights: Mapping[str, float]
    observables: tuple[str, ...]
    copies: int
    fit_copies: int
    fit_evals: int
    alpha: float
    n_perm: int
    rounds: int = 2
    refit_evals: int = 3


def joint_fit(
    first: Candidate,
    second: Candidate,
    start: Mapping[str, float],
    train: np.ndarray,
    inp: SelectionInput,
    maker: CopyMaker,
    on_fit: Callable[[Fit], None] | None = None,
) -> dict[str, float]:
    """Fit both values of a pair on the training fibers by coordinate descent.

    Round 1 fits ``second`` with ``first`` held at ``start[first]`` (its single
    fit); round 2 refits ``first`` with ``second`` held at the value just found,
    and so on for ``inp.rounds`` rounds. Each step is :func:`.fit.fit_effect` with
    the other member fixed; its baseline point (the fitted member at 0) is the
    other member alone, so a member that does not help goes back to 0 and the
    pair's loss never increases from round to round (up to the copies' noise).

    Parameters
    ----------
    start : mapping name -> float
        Starting values; ``start[second]`` gives the sign a signed effect is
        searched on first (0: both sides).
    train : ndarray of int
        Fibers of the training fold.

    Returns
    -------
    dict name -> float : both fitted values.
    """
    obs = inp.observed.iloc[train].reset_index(drop=True)
    cur = {c.name: float(start.get(c.name, 0.0)) for c in (first, second)}
    order = [second, first]
    for r in range(inp.rounds):
        cand = order[r % 2]
        other = order[(r + 1) % 2]
        fixed = {other.name: cur[other.name]}
        base_tr = maker.copies(
            range(inp.fit_copies), fixed, train, desc=f"pair-fit {other.name} (+{cand.name})"
        )
        fit = fit_effect(
            cand,
            maker,
            obs,
            base_tr,
            train,
            inp.observables,
            inp.weights,
            inp.fit_evals,
            side=float(np.sign(cur[cand.name])),
            fixed=fixed,
            stage="pair-fit",
            # from round 2 on, the current pair was the previous step's best point:
            # its runs are held, so it is a free starting value
            known=[cur[cand.name]] if r > 0 else [],
            # the folds' values are quoted for a pair that is not refitted: the score
            # test's zero, not the best of Brent's golden-section points
            estimate=True,
        )
        if on_fit is not None:
            on_fit(fit)
        cur[cand.name] = float(fit.value)
    return cur


def pair_refits(
    members: Sequence[Candidate],
    fold_values: Mapping[str, Sequence[float]],
    inp: SelectionInput,
    maker: CopyMaker,
    on_fit: Callable[[Fit], None] | None = None,
) -> tuple[dict[str, float], dict[str, tuple[float, float, bool, bool]]]:
    """Each member of a pair refitted on all fibers, with its 95 % interval.

    A single effect's quoted value is its pooled refit (:func:`.fit.pooled_refit`:
    the two halves' values evaluated on all fibers, then a search around them, the
    score test's zero) and its interval the score test over the fibers
    (:func:`.estimate.score_interval`). A member of a pair gets the same two functions,
    with the other member held fixed (``fixed``), so its loss profile is that of
    one value on all fibers: one more round of :func:`joint_fit`'s coordinate
    descent, on all fibers. The members are refitted in the given order, each with
    the other at its latest value: its refit when it has one, else the mean of its
    folds' fits. Give the member the joint fit's last round did *not* refit first
    (the added one, fitted in round 1 against the first member's single value,
    which has absorbed part of the added member's effect): refitted the other way
    round, the added member is biased by the first member's biased fold values and
    its interval under-covers. Each interval is conditional on the other member's value: it does not
    carry that value's own uncertainty.

    Parameters
    ----------
    members : sequence of Candidate
        The pair, in the order they are refitted.
    fold_values : mapping name -> (value scoring fold 0, value scoring fold 1)
        The joint fits of the two folds.
    inp : SelectionInput
        Its ``weights`` (the pair's loss), ``fit_copies`` and ``refit_evals`` are used.
    on_fit : callable, optional
        Called with every refit (the report's fit table).

    Returns
    -------
    values : dict name -> float
        Each member's refitted value.
    intervals : dict name -> (lo, hi, open_lo, open_hi)
        :func:`.estimate.score_interval` of each refit.
    """
    # an alternative (categorical) is on or off: on when either fold chose it
    held = {
        c.name: float(max(fold_values[c.name]) if c.categorical else np.mean(fold_values[c.name]))
        for c in members
    }
    intervals: dict[str, tuple[float, float, bool, bool]] = {}
    for cand in members:
        fixed = {n: v for n, v in held.items() if n != cand.name}
        label = ", ".join(f"{n}={v:.4g}" for n, v in fixed.items())
        # the value 0 of this member: the other member alone, on all fibers
        base = maker.copies(range(inp.fit_copies), fixed, desc=f"pair-refit {label}")
        fit = pooled_refit(cand, maker, inp.observed, base,
                           [float(v) for v in fold_values[cand.name]], inp.observables,
                           inp.weights, inp.refit_evals, fixed=fixed)  # fmt: skip
        if on_fit is not None:
            on_fit(fit)
        held[cand.name] = float(fit.value)
        intervals[cand.name] = (
            (fit.value, fit.value, False, False) if cand.categorical else score_interval(fit)
        )
        log.info("pair refit %s (with %s): %.4g %s", cand.name, label, fit.value,
                 intervals[cand.name])  # fmt: skip
    return held, intervals


#: One pair to try: the first member (a significant single effect), the partner
#: added to it, and the selection input (its loss weights follow the gap the first
#: member leaves, :func:`pair_weights`).
PairTrial = tuple[Candidate, Candidate, SelectionInput]


def pair_trials(queues: Sequence[Sequence[PairTrial]], k: int) -> list[list[PairTrial]]:
    """The first ``k`` pairs taken in turn from each first member's ranked partners.

    Parameters
    ----------
    queues : sequence of sequence of PairTrial
        Per first member (best first), its partners best-ranked first.
    k : int
        Pairs to try in all; a set of two effects is tried once.

    Returns
    -------
    list of list of PairTrial
        Rounds: round r holds each first member's r-th partner (:func:`forward_pairs`
        finishes the round in which a pair explains the gap).
    """
    rounds: list[list[PairTrial]] = []
    seen: set[frozenset[str]] = set()
    depth = max((len(q) for q in queues), default=0)
    for r in range(depth):
        rnd: list[PairTrial] = []
        for q in queues:
            if r >= len(q) or len(seen) >= k:
                continue
            key = frozenset((q[r][0].name, q[r][1].name))
            if key not in seen:
                seen.add(key)
                rnd.append(q[r])
        if rnd:
            rounds.append(rnd)
    return rounds


def forward_pairs(
    rounds: Sequence[Sequence[PairTrial]],
    maker: CopyMaker,
    rng: np.random.Generator,
    on_fit: Callable[[Fit], None] | None = None,
) -> tuple[list[SetHeldOut], dict[str, list[pd.DataFrame]]]:
    """Try the pairs round by round, up to the round in which one explains the gap.

    Parameters
    ----------
    rounds : sequence of sequence of PairTrial
        (first, partner, input): ``first`` a significant single effect with its
        fold values in ``input.fold_values``, ``partner`` the effect added to it
        (:func:`pair_trials`). A round is finished once begun, so that the best
        partners of two look-alike first members (off_midplane and inlet_speed)
        are both tried and two sets that explain make the verdict ambiguous.
    on_fit : callable, optional
        Called with every fit of the joint fits (for the report's fit table).

    Returns
    -------
    sets : list of SetHeldOut
        One per pair whose added member was fitted away from 0 on some fold.
    copies : dict set name -> list of DataFrame
        Copies of each set (all fibers), final values when checked, else cross-fitted.
    """
    tried: list[dict] = []
    # Holm over every member of every pair that may be tried (untried: p = 1), so
    # stopping at the first pair that explains the gap tests no more liberally than
    # trying them all (Holm is monotone in the p-values)
    family = 2 * sum(len(rnd) for rnd in rounds)
    finals: dict[int, tuple[GapResult, list[pd.DataFrame]]] = {}
    explained: int | None = None  # the round in which a pair explained the gap
    for r, (first, cand, inp) in ((r, t) for r, rnd in enumerate(rounds) for t in rnd):
        if explained is not None and r > explained:
            break
        folds, obs, w = inp.folds, inp.observed, inp.weights
        base_scores = weighted_loss(inp.base_values, w)
        single_scores = {n: weighted_loss(v, w) for n, v in inp.single_values.items()}
        v1 = [float(v) for v in inp.fold_values[first.name]]
        single = inp.fold_values.get(cand.name, [0.0, 0.0])
        per_fold = [
            joint_fit(
                first,
                cand,
                {first.name: v1[f_idx], cand.name: float(single[f_idx])},
                folds[1 - f_idx],
                inp,
                maker,
                on_fit,
            )
            for f_idx in range(len(folds))
        ]
        if all(pf[cand.name] == 0.0 for pf in per_fold) or all(
            pf[first.name] == 0.0 for pf in per_fold
        ):
            log.info("pair %s + %s: a member stays at 0 on both folds", first.name, cand.name)
            continue
        names = (first.name, cand.name)
        cps = crossfit_copies(
            maker, folds, per_fold, inp.copies, f"pair-held-out {first.name}+{cand.name}"
        )
        v_after = value_matrices(obs, cps, inp.observables)
        scores = weighted_loss(v_after, w)
        # A's contribution: the pair against B alone; B's: the pair against A alone.
        # A partner never fitted alone (ranked only by the gap A leaves) is taken
        # alone at its pair values, cross-fitted like the pair.
        b_alone = single_scores.get(cand.name)
        if b_alone is None:
            cps_b = crossfit_copies(
                maker,
                folds,
                [{cand.name: pf[cand.name]} for pf in per_fold],
                inp.copies,
                f"pair-held-out {cand.name} alone",
            )
            b_alone = weighted_loss(value_matrices(obs, cps_b, inp.observables), w)
        without = {
            first.name: b_alone,
            cand.name: single_scores.get(first.name, base_scores),
        }
        gains = {m: paired_improvement(without[m], scores) for m in names}
        tried.append(
            {
                "members": (first, cand),
                "inp": inp,
                "values": {m: float(np.mean([pf[m] for pf in per_fold])) for m in names},
                "fold": {m: (per_fold[0][m], per_fold[1][m]) for m in names},
                "residual": assess_gap(v_after, rng, alpha=inp.alpha, n_perm=inp.n_perm),
                "copies": cps,
                "p": {m: boot_p(gains[m], rng) for m in names},
                # the bootstrap intervals once per pair (_set_of is called again at the end)
                "gains_ci": {m: bootstrap_mean_ci(gains[m], rng) for m in names},
                "improvement_ci": bootstrap_mean_ci(paired_improvement(base_scores, scores), rng),
            }
        )
        i = len(tried) - 1
        if _set_of(tried, i, family, rng).significant(inp.alpha):
            st, finals[i] = _checked(tried, i, family, rng, maker, on_fit)
            if replace(st, final=finals[i][0]).explains(inp.alpha):
                explained = r  # finish this round, then stop
    sets: list[SetHeldOut] = []
    out_copies: dict[str, list[pd.DataFrame]] = {}
    for i, t in enumerate(tried):
        st = _set_of(tried, i, family, rng)
        out_copies[st.name] = t["copies"]
        if i not in finals and st.significant(t["inp"].alpha):
            # significant only under the final family (a later pair's p moved it up)
            st, finals[i] = _checked(tried, i, family, rng, maker, on_fit)
        if i in finals:
            st = replace(st, final=finals[i][0])
            out_copies[st.name] = finals[i][1]
        log.info(
            "pair %s: gains %s, p_holm %s",
            st.name,
            {m: round(g[0], 3) for m, g in st.gains.items()},
            {m: round(v, 4) for m, v in st.p_holm.items()},
        )
        sets.append(st)
    return sets, out_copies


def _checked(
    tried: list[dict],
    i: int,
    family: int,
    rng: np.random.Generator,
    maker: CopyMaker,
    on_fit: Callable[[Fit], None] | None,
) -> tuple[SetHeldOut, tuple[GapResult, list[pd.DataFrame]]]:
    """Pair ``i`` with its members refitted on all fibers and their intervals
    (:func:`pair_refits`), as a significant single effect is refitted before
    its adequacy check (the refitted values are the pair's quoted values), and the
    gap it leaves there with the copies that measured it. Called once per pair (the
    caller keeps the result in ``finals``)."""
    t = tried[i]
    inp = t["inp"]
    # first the member the joint fit's last round did not refit (joint_fit's round r
    # fits the added member when r is even): the added one for 2 rounds
    first, added = t["members"]
    last = added if (inp.rounds - 1) % 2 == 0 else first
    order = (first, added) if last is added else (added, first)
    refit, t["intervals"] = pair_refits(order, t["fold"], inp, maker, on_fit)
    t["values"] = {m: refit[m] for m in t["values"]}  # the set's member order
    st = _set_of(tried, i, family, rng)
    final = maker.copies(range(inp.copies), st.values, desc=f"pair-final {st.name}")
    v_final = value_matrices(inp.observed, final, inp.observables)
    return st, (assess_gap(v_final, rng, alpha=inp.alpha, n_perm=inp.n_perm), final)


def _set_of(tried: list[dict], i: int, family: int, rng: np.random.Generator) -> SetHeldOut:
    """Pair ``i`` of ``tried``, Holm-adjusted over ``family`` members (untried: p = 1)."""
    raw = [t["p"][m] for t in tried for m in t["p"]]
    adj = holm(np.array(raw + [1.0] * max(family - len(raw), 0)))
    at = sum(len(t["p"]) for t in tried[:i])
    t = tried[i]
    names = list(t["p"])
    return SetHeldOut(
        values=t["values"],
        fold_values=t["fold"],
        gains=t["gains_ci"],
        p_values=dict(t["p"]),
        p_holm={m: float(adj[at + j]) for j, m in enumerate(names)},
        improvement=t["improvement_ci"],
        residual=t["residual"],
        intervals=dict(t.get("intervals", {})),
    )
