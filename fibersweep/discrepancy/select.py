"""Forward selection: add a second effect to the best single one, out of sample.

When no single effect explains the gap, every other fitted candidate B is
added to the effect A that improved the held-out fibers most (A need not be
significant alone: with B's part of the gap left in, A's own improvement can be
too noisy to be; the set needs each member's own contribution significant):

1. joint fit, on the same two folds as the single fits: with the first effect
   A held at the value fitted on the training fold, B's value is fitted there
   (:func:`fit.fit_effect` with ``fixed``);
2. cross-fitted copies with both effects on score the held-out fold;
3. each member's own contribution is the per-fiber improvement of the pair
   over the pair without it (over B alone for A, over A alone for B), tested
   by a one-sided bootstrap; the p-values of every member of every pair form
   one Holm family;
4. a pair whose members both contribute significantly is checked for
   adequacy on all fibers, with each member at the mean of its two fold
   values (the pooled estimate).

The rule of :func:`decide.decide` then names the pair when it leaves no
significant gap. Two effects are the most this step adds: a third would need
more fibers than the studies this was measured on (N <= 200) hold.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from fibersweep.discrepancy.copies import CopyMaker
from fibersweep.discrepancy.decide import SetHeldOut
from fibersweep.discrepancy.fit import Fit, fit_effect
from fibersweep.discrepancy.gap import (
    GapResult,
    assess_gap,
    paired_improvement,
    value_matrices,
    weighted_loss,
)
from fibersweep.discrepancy.library import Candidate
from fibersweep.discrepancy.stats import bootstrap_mean_ci, holm

__all__ = ["crossfit_copies", "boot_p", "SelectionInput", "forward_pairs"]

log = logging.getLogger(__name__)


def boot_p(d: np.ndarray, rng: np.random.Generator, n_boot: int = 4000) -> float:
    """One-sided bootstrap p-value of mean(d) <= 0 over the finite entries of d."""
    d = np.asarray(d, dtype=np.float64)
    d = d[np.isfinite(d)]
    if len(d) == 0:
        return 1.0
    means = d[rng.integers(0, len(d), size=(n_boot, len(d)))].mean(axis=1)
    return float((1 + np.sum(means <= 0.0)) / (1 + n_boot))


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
    out = []
    for k in range(copies):
        parts = [
            maker.copy(k, dict(eff), held, desc=desc)
            for held, eff in zip(folds, effects_per_fold, strict=True)
        ]
        df = pd.concat(parts, ignore_index=True)
        out.append(df.iloc[order].reset_index(drop=True))
    return out


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
    base_scores : dict observable -> ndarray (n,)
        Weighted held-out scores against the baseline copies.
    single_scores : dict name -> (observable -> ndarray (n,))
        The same with each single effect on (cross-fitted).
    weights : dict observable -> float
        Weights of the fit and decision loss (0 for observables without a gap).
    observables : tuple of str
    copies, fit_copies, fit_evals : int
        The plan's copies per evaluation, copies per fit evaluation, Brent steps.
    alpha : float
    n_perm : int
    """

    observed: pd.DataFrame
    folds: Sequence[np.ndarray]
    fold_values: Mapping[str, Sequence[float]]
    base_scores: Mapping[str, np.ndarray]
    single_scores: Mapping[str, Mapping[str, np.ndarray]]
    weights: Mapping[str, float]
    observables: tuple[str, ...]
    copies: int
    fit_copies: int
    fit_evals: int
    alpha: float
    n_perm: int


def forward_pairs(
    first: str,
    others: Sequence[Candidate],
    inp: SelectionInput,
    maker: CopyMaker,
    rng: np.random.Generator,
    on_fit: Callable[[Fit], None] | None = None,
) -> tuple[list[SetHeldOut], dict[str, list[pd.DataFrame]]]:
    """Try every pair ``first + B`` (see the module docstring).

    Parameters
    ----------
    first : str
        The single effect that improved the held-out fibers most.
    others : sequence of Candidate
        Effects to add (``first`` excluded).
    on_fit : callable, optional
        Called with every joint fit (for the report's fit table).

    Returns
    -------
    sets : list of SetHeldOut
        One per pair whose added member was fitted away from 0 on some fold.
    copies : dict set name -> list of DataFrame
        Copies of each set (all fibers), final values when checked, else cross-fitted.
    """
    folds = inp.folds
    obs = inp.observed
    v1 = [float(v) for v in inp.fold_values[first]]
    tried: list[dict] = []
    for cand in others:
        vals = []
        for f_idx in range(len(folds)):
            train = folds[1 - f_idx]
            fixed = {first: v1[f_idx]}
            base_tr = [
                maker.copy(k, fixed, train, desc=f"fit {first} (+{cand.name})")
                for k in range(inp.fit_copies)
            ]
            single = inp.fold_values.get(cand.name, [0.0, 0.0])
            fit = fit_effect(
                cand,
                maker,
                obs.iloc[train].reset_index(drop=True),
                base_tr,
                train,
                inp.observables,
                inp.weights,
                inp.fit_evals,
                side=float(np.sign(single[f_idx])),
                fixed=fixed,
            )
            if on_fit is not None:
                on_fit(fit)
            vals.append(float(fit.value))
        if all(v == 0.0 for v in vals):
            log.info("pair %s + %s: the added effect stays at 0", first, cand.name)
            continue
        per_fold = [{first: v1[f], cand.name: vals[f]} for f in range(len(folds))]
        cps = crossfit_copies(maker, folds, per_fold, inp.copies, f"held-out {first}+{cand.name}")
        v_after = value_matrices(obs, cps, inp.observables)
        scores = weighted_loss(v_after, inp.weights)
        # A's contribution: the pair against B alone; B's: the pair against A alone
        without = {
            first: inp.single_scores.get(cand.name, inp.base_scores),
            cand.name: inp.single_scores[first],
        }
        gains = {m: paired_improvement(without[m], scores) for m in (first, cand.name)}
        tried.append(
            {
                "values": {first: float(np.mean(v1)), cand.name: float(np.mean(vals))},
                "fold": {first: (v1[0], v1[1]), cand.name: (vals[0], vals[1])},
                "gains": gains,
                "improvement": paired_improvement(inp.base_scores, scores),
                "residual": assess_gap(v_after, rng, alpha=inp.alpha, n_perm=inp.n_perm),
                "copies": cps,
            }
        )
    raw = [boot_p(t["gains"][m], rng) for t in tried for m in t["gains"]]
    adj = holm(np.array(raw)) if raw else np.array([])
    sets: list[SetHeldOut] = []
    out_copies: dict[str, list[pd.DataFrame]] = {}
    at = 0
    for t in tried:
        names = list(t["gains"])
        p = {m: raw[at + i] for i, m in enumerate(names)}
        p_adj = {m: float(adj[at + i]) for i, m in enumerate(names)}
        at += len(names)
        st = SetHeldOut(
            values=t["values"],
            fold_values=t["fold"],
            gains={m: bootstrap_mean_ci(t["gains"][m], rng) for m in names},
            p_values=p,
            p_holm=p_adj,
            improvement=bootstrap_mean_ci(t["improvement"], rng),
            residual=t["residual"],
        )
        out_copies[st.name] = t["copies"]
        if st.significant(inp.alpha):
            final = [maker.copy(k, st.values, desc=f"final {st.name}") for k in range(inp.copies)]
            v_final = value_matrices(obs, final, inp.observables)
            gap: GapResult = assess_gap(v_final, rng, alpha=inp.alpha, n_perm=inp.n_perm)
            st = replace(st, final=gap)
            out_copies[st.name] = final
        log.info(
            "pair %s: gains %s, p_holm %s",
            st.name,
            {m: round(g[0], 3) for m, g in st.gains.items()},
            {m: round(v, 4) for m, v in st.p_holm.items()},
        )
        sets.append(st)
    return sets, out_copies
