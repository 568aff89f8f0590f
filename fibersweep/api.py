"""The public Python API: what each command of the CLI does, as a function.

Every function takes the config as a path or a :class:`~fibersweep.config.Config`,
with ``KEY=VALUE`` overrides (dotted keys, YAML values) as further positional
arguments, exactly as the command line does; it returns what the command prints or
writes, as objects (frozen dataclasses, pandas tables). The command line
(:mod:`fibersweep.cli`) parses its options, calls one of these functions and
prints the result.

>>> import fibersweep
>>> res = fibersweep.run("configs/quick.yaml", "sweep.y0=[0.3, 0.4]")  # doctest: +SKIP
>>> res.load().runs[["theta0", "y0", "class", "delta"]]                 # doctest: +SKIP

Nothing here prints: what a function has to say goes to :mod:`logging` (logger
``fibersweep.api``), and progress bars are off unless ``progress=True`` is given
(they then take the form that suits the output: a terminal, a log file or a
notebook, :mod:`fibersweep.progressbar`). Bad input raises
:class:`~fibersweep.errors.InputError` (a config error,
:class:`~fibersweep.config.ConfigError`, names the field), a failed computation
:class:`~fibersweep.errors.FibersweepError`.

Units are those of the config and the results tables: lengths in µm, angles in
degrees, times in s; past one pillar ``y0`` is in h_obs and ``length`` in l_obs,
in a pillar array ``y0`` is a fraction of ``period_y`` and ``length`` is in µm
(``docs/reference/columns.md``).
"""

from __future__ import annotations

import logging
import math
from collections import Counter
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from dataclasses import field as attr
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # annotations only: the API imports what it runs when it runs it
    import pandas as pd

    from fibersweep.config import Config
    from fibersweep.config.fiber import ClassifySettings, FiberSettings
    from fibersweep.config.flow import FlowSettings
    from fibersweep.discrepancy.workflow import DiscrepancyResult, DiscrepancySettings
    from fibersweep.fiber.result import RunResult
    from fibersweep.flow.cache import CacheInfo
    from fibersweep.flow.uncertainty import SeparatrixEstimate
    from fibersweep.results import Results
    from fibersweep.sorting.design import GroupAnswer
    from fibersweep.sorting.report import ShortRows
    from fibersweep.sweep.estimate import UncachedEstimate
    from fibersweep.sweep.plan import SweepPlan

__all__ = [
    "load_config",
    "run",
    "estimate",
    "simulate",
    "flow_field",
    "sort_report",
    "classify",
    "discrepancy",
    "load",
    "Classified",
    "DiscrepancyPlan",
    "DiscrepancyReport",
    "FieldReport",
    "FiberRun",
    "FlowFields",
    "SortReport",
    "SweepBar",
    "SweepEstimate",
    "SweepProgress",
    "SweepRun",
]

log = logging.getLogger(__name__)

# --------------------------------------------------------------------------- config


def load_config(
    config: str | Path | Config, *overrides: str, max_points: int | None = None
) -> Config:
    """A config resolved as every command sees it: overrides applied, defaults filled in,
    every check made.

    Parameters
    ----------
    config : str, Path or Config
        A YAML config file, or a config already loaded (then only ``overrides`` and
        ``max_points`` are applied and checked).
    *overrides : str
        ``KEY=VALUE`` settings that replace the config's, e.g. ``"flow.dx=2"``,
        ``"sweep.y0=[0.3, 0.4]"`` (values are YAML).
    max_points : int, optional
        Allow sweeps up to this many points (``run.max_points``).

    Returns
    -------
    Config
        Checked against the executors and the physics of the starts (the sweep's
        :data:`~fibersweep.sweep.starts.PHYSICS`).

    Raises
    ------
    ConfigError
        A bad key or value, named with its line or its override.
    """
    from fibersweep.config import Config, apply_overrides, parse_config
    from fibersweep.config import load_config as read_config
    from fibersweep.sweep.executors import EXECUTORS
    from fibersweep.sweep.starts import PHYSICS

    if not isinstance(config, Config):
        return read_config(
            config, overrides, max_points=max_points, executors=EXECUTORS, physics=PHYSICS
        )
    if not overrides and max_points is None:
        return config
    data = apply_overrides(config.model_dump(mode="json"), {}, overrides)
    if max_points is not None:
        data["run"] = {**data.get("run", {}), "max_points": max_points}
    return parse_config(data, source="config", executors=EXECUTORS, physics=PHYSICS)


def _with_run(cfg: Config, **kw: Any) -> Config:
    """``cfg`` with ``run`` settings given as arguments, checked as in the file."""
    from fibersweep.config import parse_config
    from fibersweep.sweep.starts import PHYSICS

    over = {k: v for k, v in kw.items() if v is not None}
    if not over:
        return cfg
    data = cfg.model_dump(mode="json")
    data["run"].update(over)
    return parse_config(data, source="command line", physics=PHYSICS)


def _sweep_config(
    config: str | Path | Config,
    overrides: Sequence[str],
    max_points: int | None,
    output: str | Path | None,
    workers: int | None,
    executor: str | None,
    scheduler: str | None,
) -> Config:
    """The config of a sweep with the run settings given as arguments (a scheduler
    without an executor means Dask)."""
    cfg = load_config(config, *overrides, max_points=max_points)
    if scheduler and executor is None:
        executor = "dask"
    return _with_run(
        cfg, workers=workers, executor=executor, scheduler=scheduler,
        output=None if output is None else str(output),
    )  # fmt: skip


@contextmanager
def _flow_bars(show: bool) -> Iterator[None]:
    """A bar over the LBM steps, with the residual, for any flow solve in the block.

    One bar per solve (the nested solve does the coarser grids first), closed on
    the grid's last report, so whatever is printed next starts on a line of its
    own. Nothing is shown when the field comes from the cache, or when ``show`` is
    false (the solver then logs its progress).
    """
    if not show:
        yield
        return
    from fibersweep.flow.progress import SolveProgress, on_progress
    from fibersweep.progressbar import progress_bar

    open_: list = []  # the bar of the grid being solved, if any

    def close() -> None:
        while open_:
            open_.pop().close()

    def report(p: SolveProgress) -> None:
        if p.steps == 0 or not open_:  # every solve reports step 0 first
            close()
            open_.append(
                progress_bar(
                    desc=f"flow field, dx = {p.dx:g} µm ({p.cells / 1e6:.2g} M cells)",
                    unit=" steps",
                    postfix="starting (the first solve also compiles the kernels)",
                )
            )
        bar = open_[0]
        if p.steps == 0:
            return
        bar.set_postfix_str(
            f"residual {p.residual:.1e} (stops at {p.tolerance:.0e})", refresh=False
        )
        bar.update(p.steps - bar.n)
        if p.finished:
            close()

    try:
        with on_progress(report):
            yield
    finally:
        close()


# --------------------------------------------------------------------------- run


class SweepProgress:
    """What a sweep reports while it runs; :func:`run` calls these hooks in this order.

    The base class logs the plan and the rounds (logger ``fibersweep.api``, level
    INFO) and shows nothing. Subclass it to follow a sweep: :class:`SweepBar` shows a
    progress bar, the command line adds its printed lines to that.

    Attributes
    ----------
    bars : bool
        Also show a bar over the steps of a flow field that is computed.
    """

    bars = False

    def start(self, config: Config, fields: Mapping[str, tuple[FlowSettings, bool]]) -> None:
        """Before anything runs: the resolved config and its flow fields (key ->
        (settings, whether cached); :func:`fibersweep.sweep.fields.flow_keys_for`)."""
        missing = sum(1 for _, cached in fields.values() if not cached)
        log.info("%s: %d flow fields, %d to compute", config.run.output, len(fields), missing)

    def plan(self, plan: SweepPlan) -> None:
        """The plan of the sweep's first round, before it runs."""
        log.info(
            "%s: %d runs in the sweep; done %d ok, %d failed; to do now %d",
            plan.out, len(plan.tasks), plan.done_ok, plan.done_failed, len(plan.todo),
        )  # fmt: skip

    def row(self, row: Mapping[str, Any]) -> None:
        """A finished run: its row of the runs table."""

    def round(self, number: int, plan: SweepPlan) -> None:
        """Before refinement round ``number`` runs, with its plan."""
        log.info("refinement round %d: %d runs to do", number, len(plan.todo))

    def close(self) -> None:
        """The sweep is over (done, failed or interrupted)."""


class _Rows(SweepProgress):
    """Calls a function with each finished row."""

    def __init__(self, fn: Callable[[Mapping[str, Any]], None]) -> None:
        self._fn = fn

    def row(self, row: Mapping[str, Any]) -> None:
        self._fn(row)


#: Short names of the classes and modes in a sweep's bar.
SHORT = {"Below": "B", "Above": "A", "Pole-vaulting": "PV", "Trapping": "T", "failed": "fail",
         "zigzag": "Z", "displacement": "D", "wrap-and-jump": "WJ", "trapped": "T",
         "mixed": "M"}  # fmt: skip


class SweepBar(SweepProgress):
    """A progress bar over a sweep's runs, with the running count per class (or mode).

    On a terminal a live bar; into a log file a line every 10 s. The first run of
    each worker includes its start-up (kernels compiled on first use): the rate and
    the estimate start after them. One bar per refinement round.

    Attributes
    ----------
    counts : Counter
        Finished runs of this call per class (a pillar array's: per mode), failed
        runs as ``failed``.
    config : Config or None
        The sweep's resolved config (once started).
    """

    bars = True

    def __init__(self) -> None:
        self.counts: Counter = Counter()
        self.config: Config | None = None
        self._bar: Any = None

    @property
    def saved(self) -> int:
        """Runs of this call finished (and saved) so far."""
        return sum(self.counts.values())

    def start(self, config: Config, fields: Mapping[str, tuple[FlowSettings, bool]]) -> None:
        self.config = config

    def _new(self, n: int) -> None:
        from fibersweep.progressbar import WarmingBar

        workers = self.config.run.workers if self.config is not None else 1
        self._bar = WarmingBar(
            n,
            warm=min(workers, n),
            note="workers starting (the first runs also compile the kernels)",
            unit="run",
            smoothing=0.1,
        )

    def plan(self, plan: SweepPlan) -> None:
        if plan.todo:
            self._new(len(plan.todo))

    def row(self, row: Mapping[str, Any]) -> None:
        label = row.get("mode") or row["class"]  # a pillar array's runs: the mode
        self.counts[label if row["status"] == "ok" else "failed"] += 1
        bar = self._bar
        if bar is not None:
            counts = self.counts
            shown = [k for k in SHORT if counts[k]] + [k for k in counts if k not in SHORT]
            bar.set_postfix_str(
                " ".join(f"{SHORT.get(k, k or '?')}={counts[k]}" for k in shown), refresh=False
            )
            bar.update(1)

    def round(self, number: int, plan: SweepPlan) -> None:
        self.close()
        if plan.todo:
            self._new(len(plan.todo))

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None


def _progress(progress: bool | SweepProgress | Callable[..., Any] | None) -> SweepProgress:
    if isinstance(progress, SweepProgress):
        return progress
    if progress is True:
        return SweepBar()
    if callable(progress):
        return _Rows(progress)
    return SweepProgress()


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


@dataclass(frozen=True)
class FiberRun:
    """One fiber run of :func:`simulate`.

    Attributes
    ----------
    result : RunResult
        The run: past one pillar its class, δ [h_obs], contact...; through a pillar
        array its mode, rows, shift per row [µm], f and migration angle [deg];
        ``trajectory`` when recorded (:mod:`fibersweep.fiber.result`).
    config : Config
        The resolved config.
    fiber : FiberSettings
        The fiber settings the run used (with ``plot``: the trajectory recorded).
    field : FlowField
        The flow field it ran in (a pillar array's unit cell: ``field.array``).
    returned : float
        With ``reversible``: how far from its start the fiber returned when the flow
        was reversed [µm]; NaN otherwise.
    ready_s : float
        Seconds to make the fiber kernels ready before the run [s]: compiled on first
        use (then loaded from the disk cache).
    figure : Path or None
        The chronophotograph written (``plot``).
    warnings : tuple of str
        Where the settings leave the validated range, each naming the setting to
        change and its source page (:mod:`fibersweep.sweep.validity`).
    """

    result: RunResult
    config: Config = attr(repr=False)
    fiber: FiberSettings = attr(repr=False)
    field: Any = attr(repr=False)
    returned: float = math.nan
    ready_s: float = 0.0
    figure: Path | None = None
    warnings: tuple[str, ...] = ()

    @property
    def array(self) -> Any:
        """The pillar array the fiber crossed (None past one pillar)."""
        return getattr(self.field, "array", None)


def simulate(
    config: str | Path | Config,
    *overrides: str,
    theta0: float,
    y0: float,
    length: float,
    model: str | None = None,
    reversible: bool = False,
    seed: int | None = None,
    plot: str | Path | None = None,
    progress: bool = False,
) -> FiberRun:
    """Run one fiber (``fibersweep simulate``): past one pillar, or through a pillar array.

    Parameters
    ----------
    config : str, Path or Config
        The config (its flow, fiber and run sections; the sweep is not used).
    *overrides : str
        ``KEY=VALUE`` settings, e.g. ``"fiber.model=bead-spring"``.
    theta0 : float
        Start angle from +x [deg].
    y0 : float
        Start lateral position: y0/h_obs past one pillar; in a pillar array a fraction
        of ``period_y`` in the gap before row 0.
    length : float
        Fiber length: L/l_obs past one pillar; in a pillar array L [µm].
    model : str, optional
        Fiber model (the override ``fiber.model=MODEL``, checked with the others).
    reversible : bool
        Also reverse the flow and measure how far from the start the fiber returns
        (not in a pillar array).
    seed : int, optional
        Seed of random effects.
    plot : str or Path, optional
        Write a chronophotograph here (PNG/PDF/SVG by suffix); a flexible fiber is
        drawn through all its beads.
    progress : bool
        Show a bar while a flow field is computed.

    Returns
    -------
    FiberRun
        ``.result`` is the run's :class:`~fibersweep.fiber.result.RunResult`; a run that
        failed has ``result.status != "ok"`` and its ``reason``.

    Raises
    ------
    InputError
        A bad start, before any flow field is solved or kernel compiled when it is a
        start that touches a pillar: the message names the free ranges of y0 at that
        angle and length (:func:`fibersweep.sweep.draws.free_text`).
    """
    import time

    from fibersweep.errors import InputError
    from fibersweep.fiber.result import FiberStart
    from fibersweep.fiber.run import simulate as run_one
    from fibersweep.fiber.run import simulate_reversible
    from fibersweep.flow.cache import get_flow_field
    from fibersweep.plots.shapes import is_flexible
    from fibersweep.sweep.draws import check_start_of, free_text
    from fibersweep.sweep.validity import facts, warnings_for
    from fibersweep.sweep.worker import _warm

    extra = [f"fiber.model={model}"] if model is not None else []
    cfg = load_config(config, *overrides, *extra)
    check_start_of(cfg, theta0, y0, length)  # before the field and the kernels: seconds saved
    warned = warnings_for([facts(cfg.fiber, cfg.flow.array)])
    for w in warned:
        log.info("outside the validated range: %s", w)
    fiber = cfg.fiber
    if plot is not None:  # the drawing needs the trajectory, and a bent fiber its beads
        rec = fiber.record.model_copy(
            update={
                "trajectories": True,
                "samples": max(fiber.record.samples, 2000),
                "all_beads": fiber.record.all_beads or is_flexible(fiber.model),
            }
        )
        fiber = fiber.model_copy(update={"record": rec})
    with _flow_bars(progress):
        flow, _ = get_flow_field(cfg.flow, cfg.run.cache_dir)
    array = getattr(flow, "array", None)
    start = FiberStart(theta0=theta0, y0=y0, length=length)
    if array is not None and reversible:
        raise InputError("--reversible: not available in a pillar array (flow.array)")
    t0 = time.perf_counter()
    _warm(flow, fiber)  # a short run: the kernels compiled on first use, else loaded
    ready_s = time.perf_counter() - t0
    back = math.nan
    try:
        if reversible:
            res, back = simulate_reversible(flow, fiber, start, rng_seed=seed)
        else:
            res = run_one(flow, fiber, start, rng_seed=seed)
    except InputError as exc:  # a start the check above could not see (an effect moved it)
        text = str(exc)
        if text.startswith("y0") and ("touches a pillar" in text or "overlaps" in text):
            raise InputError(f"{text}; {free_text(cfg, theta0, length)}") from None
        raise
    outcome = getattr(res, "mode", None) or res.cls or res.status
    log.info("%s: %s in %.2f s", start, outcome, res.wall_time)
    figure = None if plot is None else _chronophotograph(res, flow, fiber, Path(plot))
    return FiberRun(res, cfg, fiber, flow, float(back), ready_s, figure, warned)


def _chronophotograph(res: RunResult, flow: Any, fiber: FiberSettings, plot: Path) -> Path:
    """The chronophotograph: past one pillar, or through the rows of an array."""
    array = getattr(flow, "array", None)
    if array is None:
        from fibersweep.plots.chrono import chronophotograph

        return chronophotograph(res, flow.geometry, plot)
    from fibersweep.plots.array_chrono import run_dict, run_figure
    from fibersweep.plots.style import paper_style, save_figure

    with paper_style():
        fig = run_figure(array, run_dict(res, fiber.bead_radius), fiber.bead_radius)
        return save_figure(fig, plot)


# --------------------------------------------------------------------------- flow field


@dataclass(frozen=True)
class FieldReport:
    """One flow field of :func:`flow_field`, and what the solver and the analysis say.

    Attributes
    ----------
    key : str
        Cache key of its settings.
    label : str
        The swept flow values that make it (``"base flow settings"`` without any).
    settings : FlowSettings
    field : FlowField
        Velocities [µm/s] on the lattice, with interpolation; a pillar array's unit
        cell (``CellField``, with ``.array``).
    info : CacheInfo
        Where it came from (cache hit or computed), the solver's steps, convergence,
        residual and seconds, the centreline speed reached [µm/s], the grid.
    seconds : float
        Seconds this call took to get it (a load, or the solve) [s].
    separatrix : SeparatrixEstimate or None
        Past one pillar: the far-upstream separatrix [h_obs] with its error (model
        spread, grid error when another level is cached); None in a pillar array or
        when not located (``separatrix_error`` says why).
    separatrix_error : str or None
    figure : Path or None
        The figure written (``plot``).
    """

    key: str
    label: str
    settings: FlowSettings = attr(repr=False)
    field: Any = attr(repr=False)
    info: CacheInfo = attr(repr=False)
    seconds: float
    separatrix: SeparatrixEstimate | None = None
    separatrix_error: str | None = None
    figure: Path | None = None


@dataclass(frozen=True)
class FlowFields:
    """The flow fields of a config (:func:`flow_field`): one, or one per distinct flow
    setting of a sweep over flow settings.

    Attributes
    ----------
    config : Config
    reports : tuple of FieldReport
        In sweep order; the first is the base settings' field when flow is not swept.
    """

    config: Config = attr(repr=False)
    reports: tuple[FieldReport, ...] = ()

    @property
    def field(self) -> Any:
        """The (first) flow field."""
        return self.reports[0].field

    def __iter__(self) -> Iterator[FieldReport]:
        return iter(self.reports)

    def __len__(self) -> int:
        return len(self.reports)


def flow_field(
    config: str | Path | Config,
    *overrides: str,
    force: bool = False,
    plot: str | Path | None = None,
    progress: bool = False,
) -> FlowFields:
    """Compute (or load from the cache) the steady flow field of a config
    (``fibersweep flow``): a channel's, or a pillar array's unit cell.

    A sweep over flow settings (``sweep: {flow.dx: [4, 2]}``) has one field per
    distinct flow setting: each is computed (or found) once.

    Parameters
    ----------
    config : str, Path or Config
        The config (its flow section, and the sweep's flow axes if any).
    *overrides : str
        ``KEY=VALUE`` settings, e.g. ``"flow.dx=2"``.
    force : bool
        Recompute the field even if it is cached.
    plot : str or Path, optional
        Write a figure of the field (PNG/PDF/SVG by suffix); with several fields, one
        per field, its key added to the name.
    progress : bool
        Show a bar over the solver's steps.

    Returns
    -------
    FlowFields
        ``.field`` is the (first) :class:`~fibersweep.flow.field.FlowField`;
        ``.reports`` say, per field, where it came from and its separatrix.
    """
    from fibersweep.flow.cache import cache_key
    from fibersweep.sweep.starts import PHYSICS

    cfg = load_config(config, *overrides)
    distinct: dict[str, tuple[Any, str]] = {}
    for combo in cfg.combinations(PHYSICS):
        key = cache_key(combo.config.flow)
        if key not in distinct:
            values = {k: v for k, v in combo.values.items() if k.startswith("flow.")}
            label = ", ".join(f"{k}={v}" for k, v in values.items()) or "base flow settings"
            distinct[key] = (combo.config.flow, label)
    reports = []
    with _flow_bars(progress):
        for key, (settings, label) in distinct.items():
            where = None if plot is None else Path(plot)
            if where is not None and len(distinct) > 1:
                where = where.with_name(f"{where.stem}-{key}{where.suffix}")
            reports.append(_one_field(key, label, settings, cfg.run.cache_dir, force, where))
    return FlowFields(cfg, tuple(reports))


def _one_field(key: str, label: str, settings: FlowSettings, cache_dir: str, force: bool,
               plot: Path | None) -> FieldReport:  # fmt: skip
    """Compute or load one field; its separatrix (past one pillar) and figure."""
    import time

    from fibersweep.flow.cache import get_flow_field

    t0 = time.perf_counter()
    flow, info = get_flow_field(settings, cache_dir, force=force)
    took = time.perf_counter() - t0
    log.info("flow field %s: %s in %.1f s", key, "cached" if info.hit else "computed", took)
    if settings.array is not None:  # a pillar array's unit cell: no far upstream
        figure = None
        if plot is not None:
            from fibersweep.plots.array import cell_flow_figure
            from fibersweep.plots.style import paper_style, save_figure

            with paper_style():
                figure = save_figure(cell_flow_figure(flow), plot, dpi=110)
        return FieldReport(key, label, settings, flow, info, took, figure=figure)
    from fibersweep.flow.uncertainty import other_level, separatrix_estimate

    est, why = None, None
    try:
        level = other_level(settings, cache_dir)
        est = separatrix_estimate(flow, None if level is None else level[1])
    except ValueError as exc:  # no streamline bracket (e.g. a toy channel)
        why = str(exc)
    figure = None
    if plot is not None:
        from fibersweep.plots.flow import plot_flow

        figure = plot_flow(flow, plot)
    return FieldReport(key, label, settings, flow, info, took, est, why, figure)


# --------------------------------------------------------------------------- classify


@dataclass(frozen=True)
class Classified:
    """What :func:`classify` did to a results folder.

    Attributes
    ----------
    path : Path
        The results folder.
    thresholds : ClassifySettings
        The thresholds and rule applied.
    array : bool
        Pillar-array runs (their modes were re-derived with the trap rule).
    n_runs, n_changed : int
        Runs re-labelled, and how many changed.
    counts : DataFrame
        Runs per class (or mode) per swept combination; written to ``counts_path``.
    counts_path : Path
    warnings : tuple of str
    simulated_trap_time : float or None
        The trap time the runs were simulated with [s] (a run trapped then stopped).
    trapped : int
        Pillar-array runs now trapped.
    """

    path: Path
    thresholds: ClassifySettings
    array: bool
    n_runs: int
    n_changed: int
    counts: pd.DataFrame = attr(repr=False)
    counts_path: Path = attr(repr=False)
    warnings: tuple[str, ...] = ()
    simulated_trap_time: float | None = None
    trapped: int = 0

    @property
    def beyond_simulated(self) -> bool:
        """Whether a longer trap time than the runs' own is asked where some run is
        trapped: a run stopped by its own trap rule cannot tell whether it would have
        moved on."""
        ran = self.simulated_trap_time
        return ran is not None and self.thresholds.trap_time > ran and self.trapped > 0


def classify(
    results: str | Path,
    config: str | Path | Config | None = None,
    *,
    head_blocked_speed: float | None = None,
    trap_time: float | None = None,
    trap_speed: float | None = None,
    rule: str | None = None,
    pivot_fraction: float | None = None,
) -> Classified:
    """Re-classify stored trajectories with new thresholds or rule, no simulation
    (``fibersweep classify``).

    The runs table gets one class column per rule (``class_head_speed``,
    ``class_pivot``, ``class_switch``); ``class`` is the chosen rule's. A pillar
    array's runs get their modes re-derived with the trap rule (``trap_time``,
    ``trap_speed``).

    Parameters
    ----------
    results : str or Path
        Output folder of a sweep (rewritten atomically, under its lock).
    config : str, Path or Config, optional
        Take the thresholds from this config's ``fiber.classify`` [default: the sweep's].
    head_blocked_speed : float, optional
        Head blocked below this fraction of U_center.
    trap_time : float, optional
        In contact and stopped this long [s] -> Trapping.
    trap_speed : float, optional
        'Stopped': centre-of-mass speed below this fraction of U_center.
    rule : str, optional
        Pole-vaulting rule: ``switch``, ``head-speed``, ``pivot`` or ``corner``.
    pivot_fraction : float, optional
        ``pivot`` rule: head travel below this fraction of L while turning.

    Returns
    -------
    Classified

    Raises
    ------
    InputError
        No results there, a bad threshold, or a channel-only option (``rule``,
        ``pivot_fraction``, ``head_blocked_speed``) on pillar-array runs.
    """
    from fibersweep.errors import InputError
    from fibersweep.sweep.manifest import read_manifest
    from fibersweep.sweep.reclassify import reclassify, thresholds_for

    results = Path(results)
    base = load_config(config).fiber.classify if config is not None else None
    man = read_manifest(results) or {}
    run_cfg = man.get("config") or {}
    array = (run_cfg.get("flow") or {}).get("array") is not None
    channel_only = {"--rule": rule, "--pivot-fraction": pivot_fraction,
                    "--head-blocked-speed": head_blocked_speed}  # fmt: skip
    given = [k for k, v in channel_only.items() if v is not None]
    if array and given:
        raise InputError(
            f"{', '.join(given)}: pillar-array runs have modes, not a channel's classes; "
            "classify re-derives their trap rule (--trap-time, --trap-speed), and "
            "sort-report's --zigzag-max and --displacement-min set the other modes"
        )
    th = thresholds_for(
        results, base, head_blocked_speed=head_blocked_speed, trap_time=trap_time,
        trap_speed=trap_speed, rule=rule, pivot_fraction=pivot_fraction,
    )  # fmt: skip
    res = reclassify(results, th)
    is_modes = "mode" in res.counts.columns  # a pillar array: modes
    ran = trapped = None
    if is_modes:
        # the thresholds the runs were simulated with (a re-labelling rewrites the config's)
        simulated = man.get("simulated_classify") or (run_cfg.get("fiber") or {}).get("classify")
        ran = (simulated or {}).get("trap_time")
        counts = res.counts
        trapped = int(counts.loc[counts["mode"] == "trapped", "runs"].sum())
    log.info("re-labelled %d runs (%d changed) with %s", res.n_runs, res.n_changed, th)
    return Classified(
        path=results, thresholds=th, array=is_modes, n_runs=res.n_runs,
        n_changed=res.n_changed, counts=res.counts, counts_path=res.counts_path,
        warnings=tuple(res.warnings), simulated_trap_time=None if ran is None else float(ran),
        trapped=trapped or 0,
    )  # fmt: skip


# --------------------------------------------------------------------------- sort report


@dataclass(frozen=True)
class SortReport:
    """A sorter designer's page of an array sweep (:func:`sort_report`).

    Attributes
    ----------
    path : Path
        The results folder.
    runs : DataFrame
        The array runs, modes re-derived with the report's thresholds, with their
        ``setting`` and thinned trajectories (:func:`fibersweep.results.load_array_results`).
    settings : list of dict
        Per setting combination: ``id``, ``label``, ``values``, ``array``, ``flow``...
    config : dict
        The sweep's stored config.
    migration : DataFrame
        Per setting and length: f and the migration angle over the runs that were not
        trapped, the trapped share, the modes (``migration.csv``;
        :data:`fibersweep.sorting.report.MIGRATION_DOCS`).
    critical : DataFrame
        Every length where the mean f crosses 1/2, with its statistical error, its
        interval (scatter and interpolation, ``ci_lo``, ``ci_hi``) and its bracket [µm]
        (:func:`fibersweep.sorting.report.critical_table`).
    outlets : DataFrame
        Recovery and purity per outlet and length of a ``rows``-row device
        (``outlets.csv``).
    rows : int
        Rows of the device.
    array_rows : int
        Rows the runs crossed (``fiber.array_rows``).
    bead : float
        One bead's length, 2a [µm].
    narrowing : dict
        Setting -> lengths [µm] to add that halve a critical length's bracket wider
        than one bead.
    short : tuple of ShortRows
        Settings whose runs crossed too few rows for f to tell zigzag from displacement.
    key : str or None
        The swept setting the critical length is read against (None: none swept).
    curve : DataFrame or None
        The critical length against ``key`` (``critical.csv``).
    target : float or None
        The critical length asked for [µm].
    separate : tuple of float or None
        The two lengths to separate [µm] (the target is halfway).
    answers : tuple of GroupAnswer
        Per group of the other swept values: the value of ``key`` that gives the target.
    tables : tuple of Path
        The CSV files written.
    figures : tuple of Path
        The figures written.
    notes : tuple of str
        What the figures left out.
    warnings : tuple of str
        Where the sweep's settings (or ``rows``) leave the validated range, each naming
        the setting to change and its source page (:mod:`fibersweep.sweep.validity`).
    caveats : dict
        Setting -> the lengths that decide its critical lengths on few moving runs,
        named with their counts (:func:`fibersweep.sorting.report.thin_crossings`).
    """

    path: Path
    runs: pd.DataFrame = attr(repr=False)
    settings: list[dict] = attr(repr=False)
    config: dict = attr(repr=False)
    migration: pd.DataFrame = attr(repr=False)
    critical: pd.DataFrame = attr(repr=False)
    outlets: pd.DataFrame = attr(repr=False)
    rows: int
    array_rows: int
    bead: float
    narrowing: dict[int, list[float]]
    short: tuple[ShortRows, ...]
    key: str | None = None
    curve: pd.DataFrame | None = None
    target: float | None = None
    separate: tuple[float, float] | None = None
    answers: tuple[GroupAnswer, ...] = ()
    tables: tuple[Path, ...] = ()
    figures: tuple[Path, ...] = ()
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()
    caveats: dict[int, list[str]] = attr(default_factory=dict)


def sort_report(
    results: str | Path,
    *,
    rows: int | None = None,
    outlets: str | float | Sequence[float] = 0.5,
    target_length: float | None = None,
    separate: str | Sequence[float] | None = None,
    setting: str | None = None,
    figures: bool = True,
    zigzag_max: float = 0.25,
    displacement_min: float = 0.75,
    write: bool = True,
) -> SortReport:
    """A sorter designer's page: critical lengths, outlets, and the array setting to
    choose (``fibersweep sort-report``).

    Per setting and fiber length: the displacement fraction f and migration angle
    over the runs that were not trapped, the trapped share and the modes; the
    critical lengths (mean f = 1/2) with their interval (the runs' scatter and the
    interpolation between simulated lengths, :mod:`fibersweep.sorting.interval`),
    and the lengths that decide them on few moving runs; recovery and purity per
    outlet of a device of ``rows`` rows. With a swept array setting: the critical
    length against it, and with ``target_length`` or ``separate``, the value that
    gives it, its interval and the runs to add to be sure. Where the settings leave
    the validated range, ``warnings`` say so.

    Parameters
    ----------
    results : str or Path
        Output folder of an array sweep.
    rows : int, optional
        Rows of the device [default: ``fiber.array_rows``].
    outlets : str, float or sequence of float
        Outlet edges, each a fraction of the full displacement strictly between 0 and
        1 (0: straight on, 1: the tilt at every row); text as ``"0.3,0.7"``.
    target_length : float, optional
        Critical length wanted [µm].
    separate : str or pair of float, optional
        Two lengths to separate, ``"L1,L2"`` [µm]: the target is halfway between them.
    setting : str, optional
        The swept setting to read the critical length against [default: the first
        swept array setting].
    figures : bool
        Write the figures (``RESULTS/figures/``).
    zigzag_max : float
        Mode rule: |f| below this is zigzag.
    displacement_min : float
        Mode rule: f above this is displacement.
    write : bool
        Write the tables (``RESULTS/migration.csv``, ``outlets.csv``, ``critical.csv``).

    Returns
    -------
    SortReport
    """
    from fibersweep.analysis.modes import ModeSettings
    from fibersweep.config.fiber import ARRAY_ROWS
    from fibersweep.results import load_array_results
    from fibersweep.sorting import design as sd
    from fibersweep.sorting import report as sr
    from fibersweep.sweep.validity import facts_from_dict, warnings_for

    results = Path(results)
    edges = sr.parse_edges(outlets)
    target = sd.target_length(target_length, separate)
    runs, settings, cfg = load_array_results(results)
    modes = ModeSettings(zigzag_max=zigzag_max, displacement_min=displacement_min)
    runs = sr.relabel(runs, settings, modes, cfg["fiber"]["classify"]["trap_speed"])
    key = sd.report_key(settings, setting, target)
    array_rows = int(cfg["fiber"].get("array_rows", ARRAY_ROWS))
    n_rows = rows or cfg["fiber"].get("array_rows", ARRAY_ROWS)
    table = sr.migration_table(runs, settings)
    crit = sr.critical_table(table)
    bead = 2.0 * cfg["fiber"]["bead_radius"]
    out = sr.outlet_table(runs, settings, n_rows, edges)
    written = []
    if write:
        written = [results / "migration.csv", results / "outlets.csv"]
        table.to_csv(written[0], index=False)
        out.to_csv(written[1], index=False)
    curve, found = None, []
    thin = sr.thin_crossings(table, crit, settings)
    if key is not None:
        curve = sd.critical_curve(crit, table, settings, key)
        if target is not None:
            found = sd.answers(curve, settings, key, target, bead, table=table, caveats=thin)
        if write:
            curve.to_csv(results / "critical.csv", index=False)
            written.append(results / "critical.csv")
    pair = None
    if separate is not None:
        parts = separate.split(",") if isinstance(separate, str) else separate
        pair = (float(parts[0]), float(parts[1]))
    combos = [
        facts_from_dict(cfg["fiber"], s["array"], s["values"], s["label"],
                        device_rows=rows, trapped=int((g["mode"] == "trapped").sum()),
                        runs=len(g))
        for i, s in enumerate(settings) for g in [runs[runs["setting"] == i]]
    ]  # fmt: skip
    warned = warnings_for(combos)
    for w in warned:
        log.info("outside the validated range: %s", w)
    report = SortReport(
        path=results, runs=runs, settings=settings, config=cfg, migration=table,
        critical=crit, outlets=out, rows=n_rows, array_rows=array_rows, bead=bead,
        narrowing=sr.narrowing_lengths(table, crit, bead),
        short=tuple(sr.short_rows(settings, array_rows)), key=key, curve=curve,
        target=target, separate=pair, answers=tuple(found), tables=tuple(written),
        warnings=warned, caveats=thin,
    )  # fmt: skip
    if figures:
        drawn, notes = _sort_figures(report)
        from dataclasses import replace

        report = replace(report, figures=tuple(drawn), notes=tuple(notes))
    return report


def _slug(values: dict) -> str:
    """File-name part of a setting combination: 'shift=0.1_young_modulus=1e+04'."""
    import re

    parts = [
        f"{k.rsplit('.', 1)[-1]}={v:g}"
        if isinstance(v, int | float)
        else f"{k.rsplit('.', 1)[-1]}={v}"
        for k, v in values.items()
    ]
    return re.sub(r"[^A-Za-z0-9_.=+-]", "_", "_".join(parts))


#: Most settings drawn in one chronophotograph (one panel each).
MAX_PANELS = 6


def _sort_figures(rep: SortReport) -> tuple[list[Path], list[str]]:
    """The sort report's figures, into ``RESULTS/figures/``; and what they left out."""
    from fibersweep.analysis.modes import MODES
    from fibersweep.config.flow import FlowSettings
    from fibersweep.flow.cache import get_flow_field
    from fibersweep.plots import array as pa
    from fibersweep.plots import array_design as pd_
    from fibersweep.plots.labels import describe
    from fibersweep.plots.shapes import ShapeNotStored
    from fibersweep.plots.style import paper_style, save_figure
    from fibersweep.sorting.modes import pick_run

    settings, runs, cfg = rep.settings, rep.runs, rep.config
    fig_dir = rep.path / "figures"
    written, notes = [], []
    with paper_style():
        arrays, shifts, periods, drawn = {}, {}, {}, set()
        for i, s in enumerate(settings):
            # the sweep's cell field, from the cache (solved again if it was removed)
            flow = FlowSettings.model_validate(s["flow"])
            field_, _ = get_flow_field(flow, cfg["run"]["cache_dir"])
            arrays[i] = field_.array
            shifts[i] = field_.array.lateral_shift
            periods[i] = field_.array.period_x
            if s["flow_key"] in drawn:  # settings that share a flow share its figure
                continue
            drawn.add(s["flow_key"])
            flow_values = {k: v for k, v in s["values"].items() if k.startswith("flow.")}
            name = f"cell-flow-{_slug(flow_values)}.png" if flow_values else "cell-flow.png"
            written.append(save_figure(pa.cell_flow_figure(field_), fig_dir / name, dpi=110))
        tilts = {i: math.degrees(math.atan(s["array"]["shift"])) for i, s in enumerate(settings)}
        labels = describe(settings)  # in words with units: "E = 10 kPa"
        written.append(
            save_figure(pd_.migration_figure(rep.migration, tilts, labels, rep.critical),
                        fig_dir / "migration.png")  # fmt: skip
        )
        written.append(save_figure(pd_.outlets_figure(rep.outlets, labels),
                                   fig_dir / "outlets.png"))  # fmt: skip
        written.append(
            save_figure(
                pa.overlay_figure(runs, periods, shifts=shifts, labels=labels),
                fig_dir / "sort-tracks.png",
                dpi=130,
            )
        )
        shown = list(range(len(settings)))
        if len(shown) > MAX_PANELS:
            shown = [
                shown[round(k * (len(shown) - 1) / (MAX_PANELS - 1))] for k in range(MAX_PANELS)
            ]
            notes.append(f"chronophotographs show {MAX_PANELS} of the {len(settings)} settings")
        for mode in MODES:
            picks = [(i, pick_run(runs[runs["setting"] == i], mode)) for i in shown]
            picks = [(i, {**p, "setting_label": labels[i]}) for i, p in picks if p is not None]
            if not picks:
                continue
            try:
                fig = pa.chrono_figure(
                    None,
                    [p for _, p in picks],
                    cfg["fiber"]["bead_radius"],
                    arrays=[arrays[i] for i, _ in picks],
                )
            except ShapeNotStored as exc:
                notes.append(f"no chronophotograph of the {mode} runs: {exc}")
                continue
            written.append(save_figure(fig, fig_dir / f"chrono-{mode}.png", dpi=130))
        if rep.curve is not None:
            from fibersweep.config import setting_column

            key = rep.key
            ans = rep.answers[-1].answer if rep.answers else None
            unit = setting_column(key)[1]
            fig = pd_.critical_figure(rep.curve, key, unit, ans, rep.target, rep.critical)
            written.append(save_figure(fig, fig_dir / f"critical-{key.rsplit('.', 1)[-1]}.png"))
    for n in notes:
        log.info("sort report: %s", n)
    return written, notes


# --------------------------------------------------------------------------- discrepancy


def refuse_array(cfg: Config, command: str) -> None:
    """The discrepancy workflow is the channel's: refuse a pillar array, naming what to use.

    Raises
    ------
    InputError
        ``cfg`` has ``flow.array``.
    """
    from fibersweep.errors import InputError

    if cfg.flow.array is not None:
        raise InputError(
            f"{command}: the discrepancy workflow compares fibers measured past one pillar in "
            "a channel (class, δ, contact, exit position); a pillar array (flow.array) has "
            "none of these observables. For an array: fibersweep run CONFIG, then fibersweep "
            "sort-report RESULTS (migration, critical lengths, outlets)"
        )


def sweep_box(cfg: Config) -> dict[str, tuple[float, float]]:
    """The range of the config's start axes: theta0 [deg], y0 [h_obs], length [l_obs]."""
    from fibersweep.config import axis_values

    box = {}
    for name in ("theta0", "y0", "length"):
        v = axis_values(getattr(cfg.sweep, name))
        box[name] = (float(v.min()), float(v.max()))
    return box


def declared_candidates(cfg: Config, candidates: Sequence[str] | None) -> tuple:
    """Declared candidates: the config's ``discrepancy.candidates``, then ``candidates``
    (``--candidate`` texts: ``KEY=LO..HI``, ``KEY=VALUE``, or a switch with its parameter)."""
    from fibersweep.discrepancy.declared import parse_candidates

    texts = list(cfg.discrepancy.candidates)
    where = [f"discrepancy.candidates[{i}]:" for i in range(len(texts))]
    texts += list(candidates or [])
    where += ["--candidate"] * len(candidates or [])
    return tuple(parse_candidates(texts, cfg.fiber, cfg.flow, where))


@dataclass(frozen=True)
class DiscrepancyPlan:
    """What :func:`discrepancy` is about to run (handed to its ``on_plan``).

    Attributes
    ----------
    fibers : int
        Measured fibers.
    settings : DiscrepancySettings
        The workflow's settings (its budget plan:
        :func:`fibersweep.discrepancy.settings.plan_budget`).
    followup : int or None
        Follow-up fibers, if given.
    """

    fibers: int
    settings: DiscrepancySettings
    followup: int | None = None


@dataclass(frozen=True)
class DiscrepancyReport:
    """The discrepancy workflow's result and the report written (:func:`discrepancy`).

    Attributes
    ----------
    result : DiscrepancyResult
        Everything the report is made of: the verdict, the gap, the fits...
    summary : dict
        The report's JSON summary (``summary.json``): ``verdict`` (``kind``,
        ``text``), ``simulations``, ``seconds`` [s], ``updated_configs``...
    path : Path
        The report folder (``report.md``, ``summary.json``, figures, updated configs).
    """

    result: DiscrepancyResult = attr(repr=False)
    summary: dict[str, Any] = attr(repr=False)
    path: Path = Path("report")

    @property
    def verdict(self) -> dict[str, Any]:
        """``kind`` (named, ambiguous, no gap, unexplained...) and ``text``."""
        return self.summary["verdict"]

    @property
    def files(self) -> tuple[Path, ...]:
        """The report and summary, and the updated configs written."""
        return (self.path / "report.md", self.path / "summary.json",
                *(self.path / c for c in self.summary.get("updated_configs", [])))  # fmt: skip


def discrepancy(
    measured: str | Path,
    config: str | Path | Config,
    *overrides: str,
    output: str | Path = "report",
    budget: int | None = None,
    seed: int = 0,
    copies: int = 8,
    effects: Sequence[str] | None = None,
    candidates: Sequence[str] = (),
    alpha: float = 0.05,
    pairs: int = 3,
    power: bool = True,
    propose_next: bool = True,
    trajectories: str | Path | None = None,
    followup: str | Path | None = None,
    ignore_extra_columns: bool = False,
    workers: int | None = None,
    progress: bool = False,
    on_plan: Callable[[DiscrepancyPlan], None] | None = None,
) -> DiscrepancyReport:
    """Where the model disagrees with fibers measured past one pillar, which effects
    explain it, and the gap left (``fibersweep discrepancy``); writes the report.

    With ``followup``, ``measured`` is analysed as without it (same seed, same
    verdict), then the two hypotheses the verdict leaves are tested on the
    follow-up fibers.

    Parameters
    ----------
    measured : str or Path
        Measured fibers (.parquet or .csv; ``docs/reference/columns.md``).
    config : str, Path or Config
        The model's config (one pillar in a channel).
    *overrides : str
        ``KEY=VALUE`` settings.
    output : str or Path
        Report folder.
    budget : int, optional
        Most simulations in total.
    seed : int
        Random seed.
    copies : int
        Jittered baseline copies per fiber.
    effects : sequence of str, optional
        Library effects to consider [default: all].
    candidates : sequence of str
        Settings as candidate explanations: ``KEY=LO..HI`` (fitted), ``KEY=VALUE``, or a
        switch with its parameter; the config's ``discrepancy.candidates`` too.
    alpha : float
        Family-wise error rate.
    pairs : int
        Pairs of effects tried (0: single effects only).
    power : bool
        Power analysis when the verdict is no gap or unexplained.
    propose_next : bool
        Propose starts that separate two candidates when undecided.
    trajectories : str or Path, optional
        Measured tracks of every fiber (``docs/trajectories.md``).
    followup : str or Path, optional
        Fibers measured after a first analysis (same schema).
    ignore_extra_columns : bool
        Ignore columns the schema does not know.
    workers : int, optional
        Worker processes [default: ``run.workers``].
    progress : bool
        Show a progress bar over the simulations.
    on_plan : callable, optional
        Called with the :class:`DiscrepancyPlan` before anything runs.

    Returns
    -------
    DiscrepancyReport
    """
    from fibersweep.discrepancy.measured import load_measured
    from fibersweep.discrepancy.report import write_report
    from fibersweep.discrepancy.workflow import DiscrepancySettings, run_discrepancy
    from fibersweep.flow.cache import get_flow_field

    cfg = load_config(config, *overrides)
    refuse_array(cfg, "discrepancy")
    data = load_measured(
        measured, trajectories, ignore_extra=ignore_extra_columns,
        geometry=cfg.flow.geometry.to_geometry(),
    )  # fmt: skip
    more = (
        load_measured(followup, ignore_extra=ignore_extra_columns)
        if followup is not None
        else None
    )
    settings = DiscrepancySettings(
        copies=copies, budget=budget, seed=seed, alpha=alpha, pairs=pairs,
        power_fibers=40 if power else 0, next_copies=2 if propose_next else 0,
        workers=workers or cfg.run.workers,
        executor=cfg.run.executor, scheduler=cfg.run.scheduler,
        effects=tuple(effects) if effects else None,
        declared=declared_candidates(cfg, candidates),
    )  # fmt: skip
    plan = DiscrepancyPlan(len(data), settings, None if more is None else len(more))
    if on_plan is not None:
        on_plan(plan)
    field_, _ = get_flow_field(cfg.flow, cfg.run.cache_dir)
    res = run_discrepancy(data, field_, cfg.fiber, settings, progress=progress, flow=cfg.flow,
                          cache_dir=cfg.run.cache_dir, followup=more)  # fmt: skip
    out = Path(output)
    summary = write_report(res, out, cfg.model_dump(mode="json"))
    log.info("discrepancy: %s (%d simulations) -> %s", summary["verdict"]["kind"],
             summary["simulations"], out)  # fmt: skip
    return DiscrepancyReport(res, summary, out)


# --------------------------------------------------------------------------- load


def load(results: str | Path, trajectories: bool = True) -> Results:
    """A sweep's output folder in one call: runs, trajectories, settings and units.

    Parameters
    ----------
    results : str or Path
        The output folder (``run.output``).
    trajectories : bool
        Also read the trajectories (the larger table).

    Returns
    -------
    Results
        ``.runs`` and ``.trajectories`` (pandas), ``.settings`` (the resolved config),
        ``.units`` and ``.docs`` (per column), ``.provenance``; see
        :func:`fibersweep.results.load_results`.
    """
    from fibersweep.results import load_results

    return load_results(results, trajectories)
