"""Forward selection: add a second effect to a significant single one, out of sample.

When the best single effect leaves a gap, other candidates B are added to the
significant effects A that leave one (the ``settings.PAIR_FIRSTS`` that improved
the held-out fibers most; each A must be significant alone: from a
non-significant start the step once named a wrong pair, a wrong A plus a B that
undid A's side effect; the set also needs each member's own contribution
significant):

0. partners are ranked by their signature against the gap A leaves
   (:func:`pairfit.rank_partners`), not against the whole gap, which A
   dominates; and the loss also scores the observables A leaves with a gap
   (:func:`pairfit.pair_weights`): B's part of the gap often shows only once
   A's is removed, and a loss blind to it can neither fit B nor see its
   contribution. The plan's pairs are taken in turn from each A's ranking
   (A1's best partner, A2's best, A1's second, ...; :func:`pair_trials`), a
   set of two effects tried once;
1. joint fit, on the same two folds as the single fits, by coordinate descent
   (:func:`pairfit.joint_fit`): B is fitted with A at its single value, then A
   is refitted with B at that value, both on the training fold only;
2. cross-fitted copies with both effects on score the held-out fold;
3. each member's own contribution is the per-fiber improvement of the pair
   over the pair without it (over B alone for A, over A alone for B), tested
   by a one-sided bootstrap; the p-values of every member of every pair form
   one Holm family;
4. a pair whose members both contribute significantly is refitted on all
   fibers (:func:`pairfit.pair_refits`) and checked for adequacy there.

Pairs are tried in that order, and the step stops after the round in which a
pair explains the gap (significant contributions, no gap left): the other
first member's pair of that round is still tried, so that two look-alike first
members (off_midplane and inlet_speed, held-out improvements 1.02 and 1.00 with
friction = 0.35 + inlet_speed = -0.04 hidden) give two explaining sets and an
ambiguous verdict, not whichever came first. The Holm family is every member of
every pair that may be tried, the untried ones counted with p = 1: Holm is
monotone in the p-values, so stopping early never rejects more than trying
every pair would.

The rule of :func:`decide.decide` then names the pair when it leaves no
significant gap and no single effect explains the gap. Two effects are the
most this step adds: a third would need more fibers than the studies this was
measured on (N <= 200) hold.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace

import numpy as np
import pandas as pd

from fibersweep.discrepancy.copies import CopyMaker
from fibersweep.discrepancy.decide import SetHeldOut
from fibersweep.discrepancy.fit import Fit
from fibersweep.discrepancy.gap import (
    GapResult,
    assess_gap,
    paired_improvement,
    value_matrices,
    weighted_loss,
)
from fibersweep.discrepancy.library import Candidate
from fibersweep.discrepancy.pairfit import SelectionInput, joint_fit, pair_refits
from fibersweep.discrepancy.stats import boot_p, bootstrap_mean_ci, holm

__all__ = ["PairTrial", "crossfit_copies", "forward_pairs", "pair_trials"]

log = logging.getLogger(__name__)


def crossfit_copies(
    maker: CopyMaker,
    folds: Sequence[np.ndarray],
    effects_per_fold: Sequence[Mapping[str, float]],
    copies: int,
    desc: str,
) -> list[pd.DataFrame]:
    """Copies 0..copies-1 of every fiber, fold f simulated with ``effects_per_fold[f]``.

    Returns
    -------
    list of DataFrame, each with one row per fiber in the original order.
    """
    order = np.argsort(np.concatenate(folds))
    per_fold = [
        maker.copies(range(copies), dict(eff), held, desc=desc)
        for held, eff in zip(folds, effects_per_fold, strict=True)
    ]
    return [
        pd.concat([p[k] for p in per_fold], ignore_index=True).iloc[order].reset_index(drop=True)
        for k in range(copies)
    ]


#: One pair to try: the first member (a significant single effect), the partner
#: added to it, and the selection input (its loss weights follow the gap the first
#: member leaves, :func:`pairfit.pair_weights`).
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
    (:func:`pairfit.pair_refits`), as a significant single effect is refitted before
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
