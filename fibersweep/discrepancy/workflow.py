"""The discrepancy workflow: noise floor, gap, localisation, ranking, fit, held-out decision.

:func:`run_discrepancy` is the library entry point of ``fibersweep discrepancy``.
It simulates (1) ``copies`` jittered baseline copies of every measured fiber,
(2) tests the gap per observable against them, (3) localises it, (4) probes
and ranks the library's effects on one half of the fibers, (5) fits the best
few on each half and scores each half with the value fitted on the other
(two-fold cross-fitting: every fiber is held out once), compares with the
baseline and decides; (6) when the best single effect leaves a gap, it tries
adding other candidates to the significant ones that helped most and leave one
(:mod:`.pairs`, forward selection); (7) after the verdict, the power analysis
and what to measure next (:mod:`.followup`); (8) with fibers measured after it
(``followup``), the verdict's two hypotheses tested on them (:mod:`.settle`).
The simulation count is planned up front and never exceeds ``budget``.

Each step is a stage function over a frozen :class:`State` that returns a new
state (:func:`noise_floor`, :func:`rank`, :func:`cross_fit`, :func:`refit`,
:func:`pairs`); the fixed inputs of a run (settings, plan, folds, the shared
random generator and the copy maker) are a frozen :class:`Run`. The stages draw
from the one generator in this order, so a run is reproducible from its seed.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pandas as pd

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.candidates import Candidate, show_values
from fibersweep.discrepancy.copies import CopyMaker, crossfit_copies
from fibersweep.discrepancy.decide import (
    HeldOut,
    SetHeldOut,
    Verdict,
    adequate,
    decide,
    evaluate_heldout,
)
from fibersweep.discrepancy.dispersion import dispersion_test, spread_test
from fibersweep.discrepancy.estimate import Fit, score_interval
from fibersweep.discrepancy.fit import fold_fits, pooled_refit
from fibersweep.discrepancy.followup import followup as next_steps
from fibersweep.discrepancy.followup import settle_followup
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
from fibersweep.discrepancy.observables import has_tracks
from fibersweep.discrepancy.pairs import SelectionInput, forward_pairs, pair_trials, pair_weights
from fibersweep.discrepancy.schema import MeasuredData
from fibersweep.discrepancy.settings import (
    PAIR_FIRSTS,
    TIE_COSINE,
    DiscrepancySettings,
    Plan,
    plan_budget,
)
from fibersweep.discrepancy.signatures import (
    Signature,
    choose_candidates,
    rank_effects,
    rank_partners,
)
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.errors import InputError
from fibersweep.flow.field import FlowField

__all__ = [
    "DiscrepancyResult",
    "DiscrepancySettings",
    "Plan",
    "Run",
    "State",
    "cross_fit",
    "noise_floor",
    "pairs",
    "plan_budget",
    "rank",
    "refit",
    "run_discrepancy",
    "settle_result",
]

log = logging.getLogger(__name__)


@dataclass
class DiscrepancyResult:
    """Everything the report needs."""

    verdict: Verdict
    gap: GapResult
    descriptive: dict[str, Any]
    region: Region
    region_by_observable: dict[str, Region]
    signatures: list[Signature]
    fits: list[Fit]
    heldout: list[HeldOut]
    sets: list[SetHeldOut]
    heldout_before: GapResult | None
    plan: Plan
    simulations: int
    failed_runs: int
    failed_by_stage: dict[str, int]
    seconds: float
    observed: pd.DataFrame
    baseline_copies: list[pd.DataFrame]
    effect_copies: dict[str, list[pd.DataFrame]]
    heldout_rows: np.ndarray  # fibers scored out of sample (all of them, by cross-fitting)
    weights: dict[str, float]
    settings: DiscrepancySettings
    observables: tuple[str, ...]
    extra: dict[str, Any] = field(default_factory=dict)


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
        95 % score-test interval of the pooled refits.
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


def run_discrepancy(
    measured: MeasuredData,
    field_: FlowField,
    fiber: FiberSettings,
    settings: DiscrepancySettings | None = None,
    progress: bool = True,
    flow: Any = None,
    cache_dir: Any = None,
    followup: MeasuredData | None = None,
) -> DiscrepancyResult:
    """Run the whole workflow (see the module docstring): the stages in turn, then the verdict.

    Parameters
    ----------
    measured : MeasuredData
        Validated measurements.
    field_ : FlowField
        Baseline flow field.
    fiber : FiberSettings
        Baseline fiber settings (its ``effects`` must be empty or are the baseline).
    settings : DiscrepancySettings
    progress : bool
        tqdm progress bars.
    flow : FlowSettings, optional
        The field's settings, and ``cache_dir`` the flow cache: where a declared
        flow candidate's field is found or solved (:class:`.simulate.Simulator`).
    followup : MeasuredData, optional
        Fibers measured after a first analysis of ``measured`` (at the starts its
        what-to-measure-next gave): the verdict's two hypotheses are tested on
        them (:mod:`.settle`). The analysis of ``measured`` is the same with or
        without them (their runs come on top of ``budget``);
        ``extra['verdict_first']`` keeps its verdict.
    """
    s = settings or DiscrepancySettings()
    t0 = time.perf_counter()
    candidates = s.candidates_of()
    n = len(measured)
    if n < 8:
        raise InputError(f"measured: {n} fibers are too few for a held-out split (need >= 8)")
    plan = plan_budget(n, s, candidates)
    log.info("plan: %s, total %d runs", plan.cost(n), plan.total(n))
    obs_names = tuple(o for o in measured.observed)
    observed = measured.table.reset_index(drop=True)
    rng = np.random.default_rng([s.seed, 11])
    perm = rng.permutation(n)
    folds = [np.sort(perm[: n // 2]), np.sort(perm[n // 2 :])]

    # the follow-up fibers' runs come on top of the budget, so the analysis of the
    # first fibers, power and what-to-measure-next included, is the same without them
    extra_runs = 2 * s.settle_copies * len(followup) if followup is not None else 0
    with Simulator(
        field_, fiber, workers=s.workers, progress=progress,
        budget=None if s.budget is None else s.budget + extra_runs,
        executor=s.executor, scheduler=s.scheduler, planned=plan.total(n),
        tracks=has_tracks(obs_names), candidates=candidates, flow=flow, cache_dir=cache_dir,
    ) as sim:  # fmt: skip
        maker = CopyMaker(measured.starts, s.noise, s.seed, sim)
        run = Run(s, plan, candidates, observed, obs_names, folds, rng, maker)
        # the bar counts what will run; a stage that runs only on some outcomes is said
        cost = plan.cost(n)
        sim.expect(cost["baseline"], later=plan.total(n) - cost["baseline"])
        st = noise_floor(run)
        if st.gap.any:
            sim.expect(plan.total(n) - cost["baseline"] - cost["pairs"], later=cost["pairs"])
            st = pairs(refit(cross_fit(rank(st))))
        sim.expect(0)  # follow-ups size their own batches
        heldout = list(st.heldout)
        by_name = {c.name: c for c in candidates}

        def show(vals: Mapping[str, float]) -> str:
            return show_values(dict(vals), by_name)

        verdict = decide(st.gap, heldout, st.region_text, rng, s.alpha, list(st.sets),
                         show=show, declared=[c.name for c in s.declared])  # fmt: skip
        first, more = verdict, {}
        if followup is not None:  # first: the budget beyond s.budget is for its runs only
            used0 = sim.used
            verdict, more = settle_followup(first, heldout, st.fold_values, followup, sim, s,
                                            obs_names, show)  # fmt: skip
            more["verdict_first"] = first
            if s.budget is not None:  # what it did not use is not the next stages'
                sim.budget = s.budget + (sim.used - used0)
        extra = next_steps(first, heldout, st.fold_values, candidates, maker, sim, plan, s,
                           obs_names, rng, show=show)  # fmt: skip
        extra.update(more)
        used, failed, by_stage = sim.used, sim.failed, dict(sim.failed_by_stage)
        extra["runs_by_stage"] = dict(sim.used_by_stage)
        extra["seconds_by_stage"] = {k: round(v, 1) for k, v in sim.seconds_by_stage.items()}
        extra["runs_without_reuse"] = maker.runs_without_reuse

    return DiscrepancyResult(
        verdict=verdict,
        gap=st.gap,
        descriptive=st.desc,
        region=st.region,
        region_by_observable=st.by_obs,
        signatures=list(st.signatures),
        fits=list(st.fits),
        heldout=heldout,
        sets=list(st.sets),
        # every fiber is held out once: the 'before' gap is the full gap
        heldout_before=st.gap if st.gap.any else None,
        plan=plan,
        simulations=used,
        failed_runs=failed,
        failed_by_stage=by_stage,
        seconds=time.perf_counter() - t0,
        observed=observed,
        baseline_copies=st.base,
        effect_copies=dict(st.effect_copies),
        heldout_rows=np.arange(n),
        weights=st.weights,
        settings=s,
        observables=obs_names,
        extra={"fold_values": dict(st.fold_values), "intervals": dict(st.intervals), **extra},
    )


def settle_result(
    res: DiscrepancyResult,
    followup: MeasuredData,
    field_: FlowField,
    fiber: FiberSettings,
    progress: bool = True,
    flow: Any = None,
    cache_dir: Any = None,
) -> DiscrepancyResult:
    """An analysis already run, with follow-up fibers put to its two-way question.

    The same as :func:`run_discrepancy` with ``followup``, without running the
    analysis of the first fibers again. ``field_``, ``fiber``, ``flow`` and
    ``cache_dir``: those of that analysis. A result already settled is settled
    again from its first verdict (the new follow-up replaces the old; the test's
    error bound is for one look at fresh fibers, :mod:`.settle`).
    """
    s = res.settings
    by_name = {c.name: c for c in s.candidates_of()}
    scored = tuple(o for o in res.observables if o in followup.observed)
    first = res.extra.get("verdict_first", res.verdict)  # a settled result: its first verdict
    with Simulator(
        field_, fiber, workers=s.workers, budget=None, progress=progress, executor=s.executor,
        scheduler=s.scheduler, tracks=has_tracks(scored),
        candidates=list(by_name.values()), flow=flow, cache_dir=cache_dir,
    ) as sim:  # fmt: skip
        verdict, more = settle_followup(
            first, res.heldout, res.extra["fold_values"], followup, sim, s,
            res.observables, lambda v: show_values(dict(v), by_name),
        )  # fmt: skip
        used, failed = sim.used, sim.failed
        stages = {k: res.extra.get("runs_by_stage", {}).get(k, 0) + v
                  for k, v in sim.used_by_stage.items()}  # fmt: skip
        failed_stages = {k: res.failed_by_stage.get(k, 0) + v
                         for k, v in sim.failed_by_stage.items()}  # fmt: skip
    extra = {**res.extra, "verdict_first": first, **more,
             "runs_by_stage": {**res.extra.get("runs_by_stage", {}), **stages}}  # fmt: skip
    return replace(res, verdict=verdict, extra=extra, simulations=res.simulations + used,
                   failed_runs=res.failed_runs + failed,
                   failed_by_stage={**res.failed_by_stage, **failed_stages})  # fmt: skip
