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
(``followup``), the verdict's two hypotheses tested on them (:mod:`.settle`);
(9) the dispersion tests the report shows. The simulation count is planned up
front and never exceeds ``budget``: the analysis (1-6) by :func:`.settings.plan_budget`,
the follow-ups (7) by :func:`.followup.followup_costs`; a follow-up that does
not fit in what the analysis leaves is skipped (``extra['power_skipped']`` ...),
and a batch the budget refuses inside a stage after the verdict's inputs
(pairs, follow-ups) ends that stage only, so a verdict reached is always
returned and reported.

The stages (1-6) are the functions of :mod:`.stages`; what a run found is a
:class:`~.result.DiscrepancyResult`, which the report receives.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.candidates import show_values
from fibersweep.discrepancy.copies import CopyMaker
from fibersweep.discrepancy.decide import decide
from fibersweep.discrepancy.followup import followup as next_steps
from fibersweep.discrepancy.followup import followup_costs, settle_followup
from fibersweep.discrepancy.gap import combined_excess
from fibersweep.discrepancy.observables import has_tracks
from fibersweep.discrepancy.result import DiscrepancyResult
from fibersweep.discrepancy.schema import MeasuredData
from fibersweep.discrepancy.settings import DiscrepancySettings, plan_budget
from fibersweep.discrepancy.simulate import BudgetExhausted, Simulator
from fibersweep.discrepancy.stages import (
    Run,
    cross_fit,
    dispersion,
    noise_floor,
    pairs,
    rank,
    refit,
)
from fibersweep.errors import InputError
from fibersweep.flow.field import FlowField

__all__ = [
    "DiscrepancyResult",
    "DiscrepancySettings",
    "run_discrepancy",
    "settle_result",
]

log = logging.getLogger(__name__)


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
    costs = followup_costs(measured.starts, s, plan, candidates)
    log.info("plan: %s, total %d runs; then at most %s", plan.cost(n), plan.total(n), costs)
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
        skipped: dict[str, str] = {}
        if st.gap.any:
            sim.expect(plan.total(n) - cost["baseline"] - cost["pairs"], later=cost["pairs"])
            st = refit(cross_fit(rank(st)))
            try:  # planned within the budget; a refused batch ends forward selection only
                st = pairs(st)
            except BudgetExhausted as err:
                skipped["pairs"] = f"skipped: budget ({err})"
                log.warning("pairs %s", skipped["pairs"])
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
        if skipped:
            extra["pairs_skipped"] = skipped["pairs"]
        extra["followup_costs"] = costs
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
        gap_per_fiber=combined_excess(st.gap, st.weights),
        dispersion=dispersion(st),
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
    error bound is for one look at fresh fibers, :mod:`.discriminant`).
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
