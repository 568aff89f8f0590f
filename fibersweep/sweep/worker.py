"""What runs inside a worker process, for every batch: the sweep's runs and the
discrepancy workflow's copies.

:func:`init_worker` is the process-pool initializer and the body of the Dask
worker plugin. It keeps one per-process cache of flow fields by cache key
(:func:`field_for`): a field is opened memory-mapped from its cache entry the
first time a task needs it (every worker on a machine shares the same pages)
and kept across tasks, batches and worker specs; a field that has no cache entry
(built in memory) travels once in the spec. It then runs one short fiber so Numba
compiles (or loads its on-disk cache) once per worker, not once per run.

Two task kinds run on it, with one error policy (:func:`run_fiber`): a run
that fails physically (bad input after effects, a numerical failure:
``RUN_ERRORS``) is a failed record with its reason; any other exception is a
bug and stops the caller (:class:`~fibersweep.errors.RunBug`).

* :func:`run_task` (:class:`SweepTask`): one sweep run; returns its row and
  trajectory as plain, picklable data.
* :func:`run_batch` (:class:`RunBatch`): several runs at given starts and seeds
  with extra effects, optionally keeping their trajectories; each record goes
  through the batch's ``reduce`` function (top-level, so it pickles by name)
  and the batch returns ``(position, value)`` pairs.
"""

from __future__ import annotations

import logging
import multiprocessing as mp
import os
import signal
import socket
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from dataclasses import field as _field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from fibersweep.errors import RUN_ERRORS, RunBug

if TYPE_CHECKING:  # pragma: no cover
    from fibersweep.config.fiber import FiberSettings
    from fibersweep.fiber.result import FiberStart, RunResult
    from fibersweep.flow.field import FlowField

__all__ = [
    "RunBatch",
    "SettingSpec",
    "SweepTask",
    "WorkerSpec",
    "failed_row",
    "field_for",
    "init_worker",
    "run_batch",
    "run_fiber",
    "run_task",
    "setting_for_field",
]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class SweepTask:
    """One fiber run to do (picklable, small).

    Attributes
    ----------
    key : str
        Content-addressed run id.
    theta0, y0, length : float
        Start angle [deg], y0/h_obs, L/l_obs.
    settings : str
        Id of the run's settings (:func:`fibersweep.sweep.ids.settings_id`): which
        fiber settings of the :class:`WorkerSpec` it runs with ('' for the spec's
        single one).
    flow_key : str
        Key of the flow field it moves in ('' for the spec's single one).
    values : tuple of (str, Any)
        The swept settings' values (dotted key, value), written as columns.
    round : int
        Refinement round that added the run (0: the grid).
    """

    key: str
    theta0: float
    y0: float
    length: float
    settings: str = ""
    flow_key: str = ""
    values: tuple[tuple[str, Any], ...] = ()
    round: int = 0

    def columns(self) -> dict[str, Any]:
        """Row columns of the run's settings: ``settings``, ``round``, one per swept key."""
        return {"settings": self.settings, "round": self.round, **dict(self.values)}


@dataclass(frozen=True)
class SettingSpec:
    """One settings combination a worker may run (JSON strings: cheap to ship).

    Attributes
    ----------
    settings : str
        Settings id, as named by :attr:`SweepTask.settings`.
    flow_key : str
        The flow field's cache key.
    flow_json : str
        ``FlowSettings`` as JSON.
    field_path : str
        The flow field's cache entry (a directory of .npy files), on a path the
        workers can read; opened memory-mapped, never recomputed by a worker.
    fiber_json : str
        ``FiberSettings`` as JSON.
    field : FlowField or None
        The field itself, for a field that has no cache entry to map (built in
        memory); ``field_path`` is then ''.
    """

    settings: str
    flow_key: str
    flow_json: str
    field_path: str
    fiber_json: str
    field: Any = _field(default=None, compare=False, repr=False)


@dataclass(frozen=True)
class WorkerSpec:
    """Everything a worker needs to set itself up (JSON strings: cheap to ship).

    A sweep of one setting fills the four single-setting fields; a sweep of many
    lists them in ``settings`` (the single-setting fields are then ignored). A
    worker maps each flow field the first time a task needs it and keeps it, so
    it maps each field once however the tasks are dealt.

    Attributes
    ----------
    flow_json, field_path, flow_key, fiber_json : str
        The single setting (see :class:`SettingSpec`); its tasks name settings ''.
    warm : bool
        Run one short fiber at start-up so Numba compiles before the first task
        (once per fiber model of the sweep).
    log_level : int
        Logging level in the worker (its stderr is the parent's).
    settings : tuple of SettingSpec
        Every setting the tasks may name.
    """

    flow_json: str = ""
    field_path: str = ""
    flow_key: str = ""
    fiber_json: str = ""
    warm: bool = True
    log_level: int = logging.WARNING
    settings: tuple[SettingSpec, ...] = ()

    def all_settings(self) -> dict[str, SettingSpec]:
        """Settings id -> its spec (the single setting under '')."""
        if self.settings:
            return {s.settings: s for s in self.settings}
        single = SettingSpec("", self.flow_key, self.flow_json, self.field_path, self.fiber_json)
        return {"": single}


@dataclass(frozen=True)
class RunBatch:
    """Several runs sent to a worker together (picklable; ``key`` names the executor task).

    Attributes
    ----------
    key : str
        Task name, unique within one executor run.
    idx : ndarray, shape (k,), int
        Positions of the runs in the caller's batch (returned with each value).
    starts : ndarray, shape (k, 3)
        theta0 [deg], y0 [/h_obs], length [/l_obs].
    seeds : ndarray, shape (k,), int
        Seed of each run (start noise, Brownian motion).
    effects : dict of str -> float
        Effects switched on in addition to the setting's own (a batch value wins).
    keep_track : bool
        Record each run's trajectory with at least ``samples`` samples (it changes
        no other outcome).
    samples : int
        Fewest trajectory samples kept with ``keep_track``.
    reduce : callable (RunResult, FlowField) -> Any, optional
        Turns each record into what the batch returns (top-level, so it pickles by
        name); None returns ``RunResult.row()``.
    settings : str
        Settings id of the :class:`WorkerSpec` the runs use ('' for its single one).
    setting : SettingSpec or None
        A setting of its own instead (the discrepancy workflow's declared
        candidates: settings made while it runs, so not in the pool's spec); its
        field is mapped once per process like the spec's.
    """

    key: str
    idx: np.ndarray
    starts: np.ndarray
    seeds: np.ndarray
    effects: dict[str, float]
    keep_track: bool = False
    samples: int = 0
    reduce: Callable[[Any, Any], Any] | None = None
    settings: str = ""
    setting: SettingSpec | None = None


#: The worker's set-up: its spec, that spec's settings and parsed fiber settings.
_SETUP: dict[str, Any] = {}
#: Per-process flow-field cache, by cache key: mapped once, kept across specs.
_FIELDS: dict[str, Any] = {}
#: Fiber settings of the batches' own settings (:attr:`RunBatch.setting`), by JSON.
_FIBERS: dict[str, Any] = {}


def _worker_name() -> str:
    return f"{socket.gethostname()}:{os.getpid()}"


def setting_for_field(field: FlowField, fiber: FiberSettings, settings: str = "") -> SettingSpec:
    """A :class:`SettingSpec` for a field the caller holds.

    A field opened memory-mapped from a cache entry is sent as that entry's path
    and key (the workers map it); any other field travels itself, once per worker.
    """
    ux = field.ux
    path = Path(ux.filename).parent if isinstance(ux, np.memmap) and ux.filename else None
    meta = field.meta or {}
    if path is not None and (path / "meta.json").is_file() and "settings" in meta:
        from fibersweep.config.flow import FlowSettings

        flow = FlowSettings.model_validate(meta["settings"])
        key = str(meta.get("cache_key") or path.name)
        return SettingSpec(
            settings, key, flow.model_dump_json(), str(path), fiber.model_dump_json()
        )
    return SettingSpec(
        settings, f"memory-{id(field):x}", "", "", fiber.model_dump_json(), field=field
    )


def field_for(spec: SettingSpec) -> FlowField:
    """The flow field of a setting from this process's cache, mapped on first use."""
    if spec.flow_key not in _FIELDS:
        if spec.field is not None:
            _FIELDS[spec.flow_key] = spec.field
        else:
            from fibersweep.config.flow import FlowSettings
            from fibersweep.flow.cache import load_entry

            flow = FlowSettings.model_validate_json(spec.flow_json)
            if flow.array is not None:  # a pillar array's unit cell: one small .npz
                from fibersweep.flow.cell_cache import load_cell_field

                _FIELDS[spec.flow_key] = load_cell_field(spec.field_path)
            else:
                # The parent verified the entry's checksums; workers only map it.
                _FIELDS[spec.flow_key] = load_entry(
                    spec.field_path, flow, mmap=True, verify=False
                )
            log.debug("worker %s mapped field %s", _worker_name(), spec.flow_key)
    return _FIELDS[spec.flow_key]


def init_worker(spec: WorkerSpec, ignore_sigint: bool = True) -> None:
    """Map the first field, parse the fiber settings and warm Numba, once per process.

    Other fields are mapped when a task first needs them (:func:`field_for`).

    Parameters
    ----------
    spec : WorkerSpec
    ignore_sigint : bool
        Leave Ctrl-C to the parent, which stops the workers cleanly (the
        executor's ``parent_handles_ctrl_c``).
    """
    child = mp.parent_process() is not None  # not the caller's own process (inline runs)
    if ignore_sigint and child:
        try:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        except ValueError:  # not the main thread (e.g. a Dask worker thread)
            pass
    if _SETUP.get("spec") == spec:
        return
    if child and not logging.getLogger().handlers:  # a fresh spawned process: log like the parent
        logging.basicConfig(
            level=spec.log_level,
            format="%(asctime)s %(name)s[%(process)d] %(levelname)s: %(message)s",
        )
    from fibersweep.config.fiber import FiberSettings

    t0 = time.perf_counter()
    specs = spec.all_settings()
    fibers = {sid: FiberSettings.model_validate_json(s.fiber_json) for sid, s in specs.items()}
    _SETUP.clear()
    _SETUP.update(spec=spec, specs=specs, fibers=fibers)
    first = next(iter(specs))
    field, fiber = _setting(first)
    t1 = time.perf_counter()
    if spec.warm:
        warmed: set[tuple[str, str]] = set()
        for sid, f in fibers.items():  # one warm-up per fiber model and integrator (its kernels)
            if (f.model, f.resolved_integrator) not in warmed:
                warmed.add((f.model, f.resolved_integrator))
                _warm(_setting(sid)[0] if f.model != fiber.model else field, f)
    log.info(
        "worker %s ready: field %.2f s, warm-up %.2f s",
        _worker_name(),
        t1 - t0,
        time.perf_counter() - t1,
    )


def _setting(sid: str) -> tuple[Any, Any]:
    """(flow field, fiber settings) of a settings id; the field mapped once per process."""
    if "specs" not in _SETUP:
        raise RuntimeError("worker not initialised: init_worker was not called")
    specs = _SETUP["specs"]
    if sid not in specs and len(specs) == 1:  # a single-setting spec runs every task
        sid = next(iter(specs))
    return field_for(specs[sid]), _SETUP["fibers"][sid]


def _warm(field: Any, fiber: Any) -> None:
    """Compile the fiber kernels by running a short fiber far from the pillar."""
    from fibersweep.fiber.result import FiberStart
    from fibersweep.fiber.run import simulate

    short = fiber.model_copy(
        update={"step": fiber.step.model_copy(update={"t_max": 0.01})}, deep=True
    )
    start = FiberStart(theta0=0.0, y0=2.0, length=0.5)
    if hasattr(field, "array"):  # a pillar array's cell: a short fiber in the widest gap
        beads = 1 if fiber.model == "rigid" else 2  # a bead-spring chain needs two
        start = FiberStart(
            theta0=0.0, y0=_gap_middle(field.array), length=2 * beads * fiber.bead_radius
        )
    try:
        simulate(field, short, start)
    except RUN_ERRORS as exc:  # a warm-up problem must not hide the real runs' errors
        log.warning("warm-up run raised %s: %s", type(exc).__name__, exc)


def _gap_middle(array: Any) -> float:
    """Lateral fraction of period_y in the middle of the gap across the flow (warm-up start)."""
    _, y0, _, y1 = array.shape.bounds
    return float(((y1 + 0.5 * array.gap) / array.period_y) % 1.0)


def failed_row(task: SweepTask, reason: str, attempts: int = 1) -> dict[str, Any]:
    """The row recorded for a run that did not finish: the run record's defaults."""
    from fibersweep.fiber.result import FiberStart, RunResult

    start = FiberStart(theta0=task.theta0, y0=task.y0, length=task.length)
    return {
        "id": task.key,
        **RunResult(start=start, status="failed", reason=reason).row(),
        "worker": "",
        "attempts": attempts,
        "finished_at": time.time(),
        **task.columns(),
    }


def run_fiber(
    field: FlowField,
    fiber: FiberSettings,
    start: FiberStart,
    name: str,
    rng_seed: int | None = None,
) -> RunResult:
    """One run under the one error policy of every batch.

    Returns
    -------
    RunResult
        The run's record; a failed record (``reason`` 'exception NAME: message')
        when it raised one of ``RUN_ERRORS`` (bad input, a failed computation).

    Raises
    ------
    RunBug
        Any other exception: a bug, not a failed run (names ``name`` and the start).
    """
    from fibersweep.fiber.result import RunResult
    from fibersweep.fiber.run import simulate

    try:
        return simulate(field, fiber, start, rng_seed=rng_seed)
    except RUN_ERRORS as exc:  # bad input or a failed computation: a failed run
        log.warning("run %s raised: %s", name, traceback.format_exc(limit=3))
        reason = f"exception {type(exc).__name__}: {exc}"
        return RunResult(
            start=start,
            status="failed",
            reason=reason,
            model=fiber.model,
            integrator=fiber.resolved_integrator,
        )
    except Exception as exc:  # anything else is a bug: stop the caller, say where
        raise RunBug(f"run {name} ({start}):\n{traceback.format_exc()}") from exc


def run_task(task: SweepTask) -> dict[str, Any]:
    """Run one sweep fiber in this worker.

    Returns
    -------
    dict
        ``{"row": dict of scalars, "trajectory": dict of arrays or None}``.
    """
    from fibersweep.fiber.result import FiberStart

    start = FiberStart(theta0=task.theta0, y0=task.y0, length=task.length)
    field, fiber = _setting(task.settings)
    t0 = time.perf_counter()
    c0 = time.process_time()
    res = run_fiber(field, fiber, start, task.key)
    row = res.row()
    row.update(
        id=task.key,
        wall_time=float(row.get("wall_time") or time.perf_counter() - t0),
        worker=_worker_name(),
        attempts=1,
        finished_at=time.time(),
        # CPU seconds of this run: with wall_time, shows whether the machine was shared.
        cpu_time=time.process_time() - c0,
        class_rule=fiber.classify.rule,  # which rule labelled 'class' (mixed folders)
        **task.columns(),
    )
    traj = res.trajectory.columns() if res.trajectory is not None else None
    if traj is not None and res.trajectory.beads is not None:
        traj = {**traj, "beads": res.trajectory.beads}
    return {"row": row, "trajectory": traj}


def batch_settings(
    base: FiberSettings, effects: dict[str, float], keep_track: bool, samples: int
) -> FiberSettings:
    """``base`` with a batch's effects on top, recording trajectories when asked."""
    update: dict[str, Any] = {"effects": {**base.effects, **effects}}
    if keep_track:
        update["record"] = base.record.model_copy(
            update={"trajectories": True, "samples": max(base.record.samples, samples)}
        )
    return base.model_copy(update=update)


def run_batch(task: RunBatch) -> list[tuple[int, Any]]:
    """Run a :class:`RunBatch` in this worker: ``(position, reduce(record, field))`` per run."""
    from fibersweep.fiber.result import FiberStart

    if task.setting is not None:
        from fibersweep.config.fiber import FiberSettings

        spec = task.setting
        if spec.fiber_json not in _FIBERS:
            _FIBERS[spec.fiber_json] = FiberSettings.model_validate_json(spec.fiber_json)
        field, base = field_for(spec), _FIBERS[spec.fiber_json]
    else:
        field, base = _setting(task.settings)
    fiber = batch_settings(base, task.effects, task.keep_track, task.samples)
    out = []
    for i, s, seed in zip(task.idx, task.starts, task.seeds, strict=True):
        start = FiberStart(theta0=float(s[0]), y0=float(s[1]), length=float(s[2]))
        res = run_fiber(field, fiber, start, task.key, rng_seed=int(seed))
        out.append((int(i), task.reduce(res, field) if task.reduce else res.row()))
    return out
