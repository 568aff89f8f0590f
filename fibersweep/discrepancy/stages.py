"""The workflow's stages: the fixed inputs of a run, the state each stage returns, the stages.

Each step is a stage function over a frozen :class:`State` that returns a new
state: (1-3) :func:`noise_floor` (jittered baseline copies, the gap per
observable, where it lives), (4) :func:`rank` (the library ranked by signature
on one half), (5) :func:`cross_fit` (each chosen effect fitted on each half and
scored on the other), (6) :func:`refit` (the significant ones refitted on all
fibers, and the gap they leave), (6b) :func:`pairs` (forward selection when the
best single effect leaves a gap). :func:`dispersion` reads the dispersion test
off the state at the end. The fixed inputs of a run (settings, plan, folds, the
shared random generator and the copy maker) are a frozen :class:`Run`. The
stages draw from the one generator in this order, so a run is reproducible from
its seed; :func:`dispersion` draws from a stream of its own.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pandas as pd

from fibersweep.discrepancy.candidates import LIBRARY, Candidate
from fibersweep.discrepancy.copies import CopyMaker, crossfit_copies
from fibersweep.discrepancy.decide import HeldOut, SetHeldOut, adequate, evaluate_heldout
from fibersweep.discrepancy.dispersion import dispersion_test, spread_test
from fibersweep.discrepancy.estimate import Fit, score_interval
from fibersweep.discrepancy.fit import fold_fits, pooled_refit
from fibersweep.discrepancy.gap import (
    GapResult,
    assess_gap,
    combined_excess,
    describe,
    feature_vector,
    observable_weights,
    value_matrices,
    weighted_loss,
)
from fibersweep.discrepancy.localise import FEATURES, Region, find_region
from fibersweep.discrepancy.pairs import SelectionInput, forward_pairs, pair_trials, pair_weights
from fibersweep.discrepancy.scores import PermTest
from fibersweep.discrepancy.settings import PAIR_FIRSTS, TIE_COSINE, DiscrepancySettings, Plan
from fibersweep.discrepancy.signatures import (
    Signature,
    choose_candidates,
    rank_effects,
    rank_partners,
)

__all__ = [
    "DISPERSION_PERM",
    "Run",
    "State",
    "cross_fit",
    "dispersion",
    "noise_floor",
    "pairs",
    "rank",
    "refit",
]

#: Permutations of each dispersion test of :func:`dispersion`.
DISPERSION_PERM = 1999


def _features(table: pd.DataFrame) -> np.ndarray:
    cols = []
    for name in FEATURES:
        if name == "contact":
            cols.append(
                table["contact"].to_numpy(dtype=np.float64)
                if "contact" in table
                else np.zeros(len(table))
            )
        else:
            cols.append(table[name].to_numpy(dtype=np.float64))
    return np.column_stack(cols)


def _subset(dfs: list[pd.DataFrame], rows: np.ndarray) -> list[pd.DataFrame]:
    return [d.iloc[rows].reset_index(drop=True) for d in dfs]


@dataclass(frozen=True)
class Run:
    """The fixed inputs of one workflow run (the random generator and the copy maker
    are shared, stateful helpers: every stage draws from them in turn).

    Attributes
    ----------
    settings : DiscrepancySettings
    plan : Plan
    candidates : list of Candidate
        The candidates considered: library effects and declared settings.
    observed : DataFrame
        Measured fibers, index 0..n-1.
    observables : tuple of str
        The measured observables scored.
    folds : list of ndarray
        The two halves of the fibers (cross-fitting).
    rng : numpy.random.Generator
    maker : CopyMaker
    """

    settings: DiscrepancySettings
    plan: Plan
    candidates: list[Candidate]
    observed: pd.DataFrame
    observables: tuple[str, ...]
    folds: list[np.ndarray]
    rng: np.random.Generator
    maker: CopyMaker

    @property
    def n(self) -> int:
        return len(self.observed)

    def candidate(self, name: str) -> Candidate:
        return next(c for c in self.candidates if c.name == name)


@dataclass(frozen=True)
class State:
    """What the stages have found so far; each stage returns a new state.

    Attributes
    ----------
    run : Run
    base : list of DataFrame
        Baseline copies (the noise floor).
    values : dict
        Observed and copy values per observable (:func:`value_matrices`).
    weights, w_gap : dict of str -> float
        Observable weights; the same with zero for observables without a gap.
    gap : GapResult
    desc : dict
        Descriptive gap summary.
    region, by_obs, region_text
        Where the gap lives (all observables, per flagged observable, as text).
    signatures, lead
        Effects ranked by signature; the leading one ('' when none matches).
    chosen : tuple of Signature
        The candidates fitted.
    fits : tuple of Fit
    fold_values : dict of str -> list of float
        Each fitted effect's value on each fold.
    eff_values : dict
        Held-out values of each fitted effect.
    heldout : tuple of HeldOut
    effect_copies : dict of str -> list of DataFrame
    intervals : dict of str -> (lo, hi, open_lo, open_hi)
        95 % interval of the pooled refits (:func:`.estimate.score_interval`).
    sets : tuple of SetHeldOut
        Pairs tried by forward selection.
    """

    run: Run
    base: list[pd.DataFrame]
    values: dict[str, Any]
    weights: dict[str, float]
    gap: GapResult
    desc: dict[str, Any]
    w_gap: dict[str, float]
    region: Region
    by_obs: dict[str, Region]
    region_text: str
    signatures: tuple[Signature, ...] = ()
    chosen: tuple[Signature, ...] = ()
    lead: str = ""
    fits: tuple[Fit, ...] = ()
    fold_values: dict[str, list[float]] = field(default_factory=dict)
    eff_values: dict[str, Any] = field(default_factory=dict)
    heldout: tuple[HeldOut, ...] = ()
    effect_copies: dict[str, list[pd.DataFrame]] = field(default_factory=dict)
    intervals: dict[str, tuple[float, float, bool, bool]] = field(default_factory=dict)
    sets: tuple[SetHeldOut, ...] = ()


def noise_floor(run: Run) -> State:
    """(1) jittered baseline copies, (2) the gap per observable, (3) where it lives."""
    s, plan, observed = run.settings, run.plan, run.observed
    base = run.maker.copies(range(plan.copies), None, desc=f"baseline ({plan.copies} copies)")
    values = value_matrices(observed, base, run.observables)
    weights = observable_weights(values)
    gap = assess_gap(values, run.rng, alpha=s.alpha, n_perm=s.n_perm)
    desc = describe(values)
    # fits and the held-out decision score the observables with a gap (less noise);
    # the residual check after an effect still looks at all of them
    w_gap = {o: (w if o in gap.flagged else 0.0) for o, w in weights.items()}
    X = _features(observed)
    region = find_region(X, combined_excess(gap, weights))
    by_obs = {o: find_region(X, gap.per_fiber[o]) for o in gap.flagged}
    region_text = by_obs[gap.flagged[0]].describe() if gap.any else region.describe()
    return State(run, base, values, weights, gap, desc, w_gap, region, by_obs, region_text)


def rank(st: State) -> State:
    """(4) rank the library by signature on fold 0's fit half; keep the best few."""
    run, plan = st.run, st.run.plan
    signatures = rank_effects(
        feature_vector(st.gap),
        run.candidates,
        run.maker,
        _subset(st.base, run.folds[1]),
        run.folds[1],
        run.observables,
        probe_copy=max(plan.copies, plan.random_copies) + 1,
        rng=run.rng,
    )
    chosen = choose_candidates(signatures, plan.candidates, plan.tied, TIE_COSINE)
    lead = chosen[0].name if chosen else ""  # a random lead gets more copies
    return replace(st, signatures=tuple(signatures), chosen=tuple(chosen), lead=lead)


def cross_fit(st: State) -> State:
    """(5) fit the chosen effects on each fold and score the other fold with that value.

    Every fiber is held out exactly once; each fitted effect's held-out copies are
    compared with the baseline (:func:`evaluate_heldout`).
    """
    run, plan, s = st.run, st.run.plan, st.run.settings
    fits: list[Fit] = []
    fold_values: dict[str, list[float]] = {}
    for sg in st.chosen:
        cand = run.candidate(sg.name)
        base = st.base[: plan.fit_copies_of(cand, cand.name == st.lead)]
        # each half's value is the score test's zero, as the pooled refit's (fit.py)
        per_fold = fold_fits(cand, run.maker, run.observed, base, run.folds,
                             run.observables, st.w_gap, plan.fit_evals,
                             side=float(np.sign(sg.probe)))  # fmt: skip
        fits += per_fold
        fold_values[sg.name] = [f.value for f in per_fold]
    base_scores = weighted_loss(st.values, st.w_gap)
    eff_scores, eff_values, residuals, fitted = {}, {}, {}, {}
    effect_copies: dict[str, list[pd.DataFrame]] = {}
    kept: dict[str, list[float]] = {}
    for name, vals in fold_values.items():
        if all(v == 0.0 for v in vals):
            continue  # both folds kept the baseline: nothing to add
        # scored against the 8 baseline copies: both fair scores are unbiased
        # at any ensemble size, so the two ensembles need not be the same size
        ncp = plan.copies_of(run.candidate(name), name == st.lead)
        cps = crossfit_copies(
            run.maker, run.folds, [{name: v} for v in vals], ncp, f"held-out {name}"
        )
        effect_copies[name] = cps
        v_after = value_matrices(run.observed, cps, run.observables)
        eff_values[name] = v_after
        eff_scores[name] = weighted_loss(v_after, st.w_gap)
        residuals[name] = assess_gap(v_after, run.rng, alpha=s.alpha, n_perm=s.n_perm)
        fitted[name] = float(np.mean(vals))
        kept[name] = [float(v) for v in vals]
    # random effects: the held-out spread test (decide.py), on the same held-out copies
    spread = {}
    for name in (n for n in fitted if run.candidate(n).random):
        t = spread_test(st.values, eff_values[name], run.rng, n_perm=s.n_perm)
        if t is not None:
            spread[name] = t
    heldout = evaluate_heldout(fitted, base_scores, eff_scores, residuals, run.rng, s.alpha,
                               spread=spread)  # fmt: skip
    return replace(
        st,
        fits=st.fits + tuple(fits),
        fold_values=kept,
        eff_values=eff_values,
        heldout=tuple(heldout),
        effect_copies={**st.effect_copies, **effect_copies},
    )


def refit(st: State) -> State:
    """(6) adequacy: refit the significant candidates on all fibers, near their fold
    values, and test the gap left with the effect at that value.

    Random effects significant by their spread test only (:mod:`.decide`) come after
    those significant by the score, within the same ``plan.refits`` (the budget);
    a random effect also gets a two-sided dispersion test at its pooled value.
    """
    run, plan, s = st.run, st.run.plan, st.run.settings
    sig = sorted((h for h in st.heldout if h.significant), key=lambda h: -h.improvement[0])
    sig += sorted(
        (h for h in st.heldout if h.spread_significant and not h.significant),
        key=lambda h: h.spread_p_holm,
    )
    fits: list[Fit] = []
    intervals = dict(st.intervals)
    effect_copies = dict(st.effect_copies)
    final = {}
    calm: dict[str, Any] = {}
    for h in sig[: plan.refits]:
        cand = run.candidate(h.name)
        base = st.base[: plan.fit_copies_of(cand, cand.name == st.lead)]
        # both halves' values evaluated first, then a search around them
        fit = pooled_refit(cand, run.maker, run.observed, base, st.fold_values[h.name],
                           run.observables, st.w_gap, plan.refit_evals)  # fmt: skip
        fits.append(fit)
        # an alternative is named or not: its "interval" is the alternative itself
        intervals[h.name] = (
            (fit.value, fit.value, False, False) if cand.categorical else score_interval(fit)
        )
        if fit.value == 0.0:
            final[h.name] = (0.0, st.gap)
            continue
        cps = run.maker.copies(range(plan.copies), {h.name: fit.value}, desc=f"final {h.name}")
        v_final = value_matrices(run.observed, cps, run.observables)
        final[h.name] = (fit.value, assess_gap(v_final, run.rng, alpha=s.alpha, n_perm=s.n_perm))
        if cand.random:  # neither over- nor under-dispersed at its value
            calm[h.name] = dispersion_test(v_final, run.rng, n_perm=s.n_perm, two_sided=True)
        effect_copies[h.name] = cps
    heldout = [
        replace(
            h,
            value=final[h.name][0],
            final=final[h.name][1],
            final_dispersion=calm.get(h.name),
            explains=(h.significant or h.spread_significant)
            and adequate(final[h.name][1])
            and (h.name not in calm or calm[h.name].p_value > s.alpha),
        )
        if h.name in final
        else replace(h, explains=False)
        for h in st.heldout
    ]
    return replace(
        st,
        fits=st.fits + tuple(fits),
        heldout=tuple(heldout),
        intervals=intervals,
        effect_copies=effect_copies,
    )


def pairs(st: State) -> State:
    """(6b) forward selection when the best significant single effect leaves a gap.

    Each first member must be significant alone (see :mod:`.pairs`). Partners are
    added to the ``PAIR_FIRSTS`` significant singles that leave a gap, best held-out
    improvement first, the plan's pairs taken from their rankings in turn
    (:func:`.pairs.pair_trials`).
    """
    run, plan, s = st.run, st.run.plan, st.run.settings
    helped = sorted((h for h in st.heldout if h.significant), key=lambda h: -h.improvement[0])
    if not helped or helped[0].explains or plan.pairs <= 0:
        return st
    queues = []
    for h in [h for h in helped if not h.explains][:PAIR_FIRSTS]:
        # partners ranked by how well their signature matches the gap this single
        # effect leaves (not the whole gap, which it dominates)
        left = h.final or h.residual
        inp = SelectionInput(
            observed=run.observed,
            folds=run.folds,
            fold_values=st.fold_values,
            base_values=st.values,
            single_values=st.eff_values,
            weights=pair_weights(st.weights, st.gap, left, s.alpha),
            observables=run.observables,
            copies=plan.copies,
            fit_copies=plan.fit_copies,
            fit_evals=plan.fit_evals,
            alpha=s.alpha,
            n_perm=s.n_perm,
            rounds=plan.pair_rounds,
            refit_evals=plan.refit_evals,
        )
        first = run.candidate(h.name)
        # two candidates that set one setting cannot be on together
        clash = {c.name for c in run.candidates if c.conflicts(first)}
        sigs = [sg for sg in st.signatures if sg.name not in clash or sg.name == first.name]
        ranked = rank_partners(h.name, sigs, left, plan.pairs)
        queues.append([(first, run.candidate(name), inp) for name in ranked])
    fits: list[Fit] = []
    trials = pair_trials(queues, plan.pairs)
    sets, set_copies = forward_pairs(trials, run.maker, run.rng, fits.append)
    return replace(
        st,
        fits=st.fits + tuple(fits),
        sets=tuple(sets),
        effect_copies={**st.effect_copies, **set_copies},
    )


def dispersion(st: State) -> dict[str, PermTest]:
    """The dispersion test of the data against the baseline copies, and against the
    copies of each random library effect simulated on every fiber (its final copies).

    Outside the Holm family of the gap: it names nothing and does not change the
    verdict; it says whether the outcomes are spread more widely than the model's.
    It draws from a stream of its own (``[seed, 23]``), after every other stage.

    Returns
    -------
    dict of str -> PermTest
        ``'baseline'``, then each such effect by name
        (:func:`.dispersion.dispersion_test`, one-sided, ``DISPERSION_PERM``
        permutations).
    """
    run = st.run
    rng = np.random.default_rng([run.settings.seed, 23])

    def one(copies: list[pd.DataFrame]) -> PermTest:
        values = value_matrices(run.observed, copies, run.observables)
        return dispersion_test(values, rng, DISPERSION_PERM)

    out = {"baseline": one(st.base)}
    for name, cps in st.effect_copies.items():
        if name in LIBRARY and LIBRARY[name].random and len(cps[0]) == run.n:
            out[name] = one(cps)
    return out
