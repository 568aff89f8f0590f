"""A sweep: run it (``fibersweep run``) or estimate what is left and its cost (``--dry-run``)."""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from dataclasses import field as attr
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # annotations only: the API imports what it runs when it runs it
    from fibersweep.config import Config
    from fibersweep.config.flow import FlowSettings
    from fibersweep.results import Results
    from fibersweep.sweep.estimate import UncachedEstimate
    from fibersweep.sweep.plan import SweepPlan

from fibersweep.api.common import _flow_bars, _sweep_config, load
from fibersweep.api.progress import SweepProgress, _progress

log = logging.getLogger("fibersweep.api")


@dataclass(frozen=True)
class SweepRun:
    """What :func:`run` did: where the results are, and what the table holds now.

    Attributes
    ----------
    path : Path
        The output folder (``run.output``); :meth:`load` reads it.
    config : Config
        The resolved config the sweep ran.
    ran : int
        Runs finished in this call (ok or failed).
    counts : dict
        Runs per class (a pillar array's: per mode) in the whole table afterwards.
    failed : int
        Failed runs in the whole table afterwards.
    ran_counts : dict
        Runs per class in this call (``failed`` for failures).
    wall_s : float
        Seconds spent running [s].
    failures : tuple of str
        One line per failed run of this call (its id, start and reason).
    refinement : dict or None
        With ``sweep.refine``: rounds, runs, boundary brackets located / open / stuck
        and why it stopped (``stopped``).
    warnings : tuple of str
        What a reader should know: a class column that mixes pole-vaulting rules, and
        where the settings leave the validated range, each naming the setting to change
        and its source page (:mod:`fibersweep.sweep.validity`).
    """

    path: Path
    config: Config = attr(repr=False)
    ran: int = 0
    counts: dict[str, int] = attr(default_factory=dict)
    failed: int = 0
    ran_counts: dict[str, int] = attr(default_factory=dict)
    wall_s: float = 0.0
    failures: tuple[str, ...] = ()
    refinement: dict[str, Any] | None = None
    warnings: tuple[str, ...] = ()

    @property
    def rate(self) -> float:
        """Runs per second of this call [1/s] (0 when none ran)."""
        return self.ran / self.wall_s if self.ran and self.wall_s > 0 else 0.0

    def load(self, trajectories: bool = True) -> Results:
        """The results folder read back (:func:`load`)."""
        return load(self.path, trajectories)


def run(
    config: str | Path | Config,
    *overrides: str,
    output: str | Path | None = None,
    workers: int | None = None,
    executor: str | None = None,
    scheduler: str | None = None,
    resume: bool = True,
    retry_failed: bool = False,
    max_points: int | None = None,
    progress: bool | SweepProgress | Callable[[Mapping[str, Any]], None] = False,
) -> SweepRun:
    """Run a sweep: flow field (cached), fiber runs across workers, Parquet results
    (``fibersweep run``).

    Runs already in the output folder are kept (the same call again does only the
    missing runs); with ``sweep.refine``, the refinement rounds follow.

    Parameters
    ----------
    config : str, Path or Config
        The sweep's config file, or a loaded config.
    *overrides : str
        ``KEY=VALUE`` settings that replace the config's (values are YAML), e.g.
        ``"sweep.theta0=[-4.0, 4.0]"``; recorded in the manifest as given.
    output : str or Path, optional
        Output folder [default: ``run.output``].
    workers : int, optional
        Worker processes [default: ``run.workers``].
    executor : str, optional
        Where runs execute: ``local`` or ``dask`` [default: ``run.executor``].
    scheduler : str, optional
        Dask scheduler ``tcp://HOST:PORT`` (implies ``executor="dask"``).
    resume : bool
        Keep finished runs; False moves them aside to a ``previous-*`` folder.
    retry_failed : bool
        Re-run only the failed runs.
    max_points : int, optional
        Allow sweeps up to this many points [default: ``run.max_points``].
    progress : bool, SweepProgress or callable
        False: quiet (the plan is logged); True: a progress bar (:class:`SweepBar`);
        a :class:`SweepProgress`: its hooks are called; a function: called with each
        finished run's row.

    Returns
    -------
    SweepRun
        The folder, the counts of its table and of this call; ``.load()`` reads it.

    Raises
    ------
    ConfigError
        A bad setting, named.
    KeyboardInterrupt
        On Ctrl-C (or SIGTERM through the command line); every run finished before
        it is saved.
    """
    from fibersweep.sweep.fields import flow_keys_for
    from fibersweep.sweep.plan import sweep_settings
    from fibersweep.sweep.rules import mixed_rules_message
    from fibersweep.sweep.runner import run_sweep
    from fibersweep.sweep.store import read_runs
    from fibersweep.sweep.validity import combination_facts, warnings_for

    cfg = _sweep_config(config, overrides, max_points, output, workers, executor, scheduler)
    hooks = _progress(progress)
    hooks.start(cfg, flow_keys_for(cfg))
    try:
        with _flow_bars(hooks.bars):
            summary = run_sweep(
                cfg, resume=resume, retry_failed=retry_failed, progress=hooks.row,
                on_plan=hooks.plan, overrides=list(overrides), on_round=hooks.round,
            )  # fmt: skip
    finally:
        hooks.close()
    warnings = []
    table = read_runs(summary.out)
    if summary.ran:  # rows added under this config's rule to a folder labelled by another
        message = mixed_rules_message(table, summary.out)
        if message:
            warnings.append(message)
            log.info("%s", message)
    # where the settings leave the validated range: once per run, naming what to change
    for message in warnings_for(combination_facts(sweep_settings(cfg), table)):
        warnings.append(message)
        log.info("outside the validated range: %s", message)
    log.info("ran %d runs in %.1f s -> %s; failed in the table: %d",
             summary.ran, summary.wall_s, summary.out, summary.failed)  # fmt: skip
    return SweepRun(
        path=Path(summary.out),
        config=cfg,
        ran=summary.ran,
        counts=dict(summary.table_counts),
        failed=summary.failed,
        ran_counts=dict(summary.counts),
        wall_s=summary.wall_s,
        failures=tuple(summary.failures),
        refinement=summary.refinement,
        warnings=tuple(warnings),
    )


@dataclass(frozen=True)
class SweepEstimate:
    """What :func:`run` would do and how long it would take (``fibersweep run --dry-run``).

    Attributes
    ----------
    config : Config
        The resolved config.
    plan : SweepPlan
        Done and to do (with the refinement rounds the stored runs already determine).
    fields : dict
        Flow key -> (FlowSettings, whether cached), in the order the sweep makes them.
    per_run_s : float or None
        Seconds per run [s] (None: unknown).
    timing : str
        Where ``per_run_s`` comes from: ``finished`` (the mean of the finished runs),
        ``timed`` (runs of this sweep timed on its cached field), ``probe`` (timed on
        a probe field), or ``none``.
    timed_runs : int
        Runs timed (past one pillar one; in a pillar array spread over the lengths).
    probes : tuple of (FlowSettings, UncachedEstimate)
        The estimate of each flow field that is not cached.
    flow_s : float
        Seconds to compute the fields not cached [s].
    seconds : float or None
        The whole estimate [s], fields included (None: unknown).
    workers : int
        Workers of the sweep.
    free_workers : int
        Workers counted in the estimate: on a busy machine only as many as the free
        cores hold (a cluster's all).
    load, cpus : float, int
        The machine's load average and cores.
    round : int
        The refinement round the stored runs determine (0: none).
    refinement : dict or None
        The stored refinement's summary (as :attr:`SweepRun.refinement`).
    """

    config: Config = attr(repr=False)
    plan: SweepPlan = attr(repr=False)
    fields: dict[str, tuple[FlowSettings, bool]] = attr(repr=False)
    per_run_s: float | None
    timing: str
    timed_runs: int
    probes: tuple[tuple[FlowSettings, UncachedEstimate], ...]
    flow_s: float
    seconds: float | None
    workers: int
    free_workers: int
    load: float
    cpus: int
    round: int = 0
    refinement: dict[str, Any] | None = None

    @property
    def compile_s(self) -> float:
        """Seconds the probes took to get the flow kernels ready (compiled on first use) [s]."""
        return max((e.compile_s for _, e in self.probes), default=0.0)

    @property
    def warmup_s(self) -> float:
        """Seconds the probes took to get the fiber kernels ready [s]."""
        return max((e.warmup_s for _, e in self.probes), default=0.0)


def estimate(
    config: str | Path | Config,
    *overrides: str,
    output: str | Path | None = None,
    workers: int | None = None,
    executor: str | None = None,
    scheduler: str | None = None,
    resume: bool = True,
    retry_failed: bool = False,
    max_points: int | None = None,
) -> SweepEstimate:
    """What a sweep has done and has to do, and how long it will take; runs nothing
    (``fibersweep run --dry-run``).

    The time per run is the mean of the finished runs, else timed on the sweep's
    cached field, else on a short probe of the field that is not cached (whose
    solve is estimated from the probe's speed, not computed).

    Parameters
    ----------
    config : str, Path or Config
        The sweep's config file, or a loaded config.
    *overrides : str
        ``KEY=VALUE`` settings that replace the config's.
    output : str or Path, optional
        Output folder [default: ``run.output``]: what is done there.
    workers : int, optional
        Worker processes the estimate is for [default: ``run.workers``].
    executor : str, optional
        ``local`` or ``dask`` [default: ``run.executor``].
    scheduler : str, optional
        Dask scheduler ``tcp://HOST:PORT`` (implies ``executor="dask"``; the machine's
        own load is then not counted).
    resume : bool
        Keep finished runs (False: all of them are to do).
    retry_failed : bool
        Only the failed runs are to do.
    max_points : int, optional
        Allow sweeps up to this many points [default: ``run.max_points``].

    Returns
    -------
    SweepEstimate
        The plan (done, to do), the time per run and where it comes from, the estimate
        [s] (``seconds``; None when unknown).
    """
    from dataclasses import replace

    from fibersweep.fiber.result import FiberStart
    from fibersweep.sweep.estimate import (
        busy_cores,
        estimate_run_s,
        estimate_uncached,
        free_workers,
        sample_tasks,
    )
    from fibersweep.sweep.fields import flow_keys_for
    from fibersweep.sweep.plan import plan_sweep, sweep_settings

    cfg = _sweep_config(config, overrides, max_points, output, workers, executor, scheduler)
    load_avg, cpus = busy_cores()  # before the probes below add to it
    plan = plan_sweep(cfg, None, resume=resume, retry_failed=retry_failed)
    rnd, info = 0, None
    if cfg.sweep.refine is not None and not plan.fresh:
        from fibersweep.sweep.refine import stored_rounds
        from fibersweep.sweep.store import read_runs

        stored = read_runs(plan.out)
        extra, rnd, info = stored_rounds(cfg.sweep.refine, plan.settings, plan.tasks, stored)
        if extra:
            plan = plan_sweep(cfg, None, retry_failed=retry_failed, extra=extra)
    fields = flow_keys_for(cfg)
    per_run = plan.mean_run_s
    timing = "finished" if per_run is not None else "none"
    flow_s = 0.0
    probes: list[tuple[Any, Any]] = []
    if plan.todo:
        task = plan.todo[len(plan.todo) // 2]
        cached = fields[task.flow_key][1]
        missing = [flow for flow, is_cached in fields.values() if not is_cached]
        if per_run is None and cached:
            per_run, timing = estimate_run_s(cfg, plan.todo), "timed"
        if missing:
            # the runs are timed on the probe field of the first field not cached: its
            # middle run, or in a pillar array runs spread across the lengths
            sub = next((s.config for s in sweep_settings(cfg) if s.id == task.settings), cfg)
            picks = sample_tasks(plan.todo) if cfg.flow.array is not None else [task]
            start = [FiberStart(theta0=t.theta0, y0=t.y0, length=t.length) for t in picks]
            for flow in missing:
                e = estimate_uncached(flow, sub.fiber, start)
                flow_s += e.flow_s
                probes.append((flow, e))
                start = start[:1]  # the runs are timed once, on the first probe field
            if per_run is None:
                per_run, timing = probes[0][1].run_s, "probe"
    timed = 1 if cfg.flow.array is None or not plan.todo else len(sample_tasks(plan.todo))
    # as SweepPlan.estimate_s: no more workers busy than runs to do; on a busy machine only
    # as many as the free cores hold (a cluster's workers: this machine's load is not theirs)
    remote = cfg.run.scheduler is not None
    free = cfg.run.workers if remote else free_workers(cfg.run.workers, load_avg, cpus)
    est = None if per_run is None else replace(plan, mean_run_s=per_run).estimate_s(free)
    if est is not None and flow_s:
        est += flow_s
    return SweepEstimate(
        config=cfg, plan=plan, fields=fields, per_run_s=per_run, timing=timing,
        timed_runs=timed, probes=tuple(probes), flow_s=flow_s, seconds=est,
        workers=cfg.run.workers, free_workers=free, load=load_avg, cpus=cpus, round=rnd,
        refinement=info,
    )  # fmt: skip


# --------------------------------------------------------------------------- one fiber
