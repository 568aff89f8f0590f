"""What runs inside a worker process: open each field once, then run fibers.

:func:`init_worker` is the process-pool initializer and the body of the Dask
worker plugin: it opens the cached flow field memory-mapped (every worker on a
machine shares the same pages; a sweep over flow settings has several fields,
each mapped the first time a task needs it and kept) and runs one short fiber so Numba compiles (or
loads its on-disk cache) once per worker, not once per run. :func:`run_task`
then runs one fiber and returns plain, picklable data. Any exception in a run
becomes a failed row with its reason: one bad run never stops a sweep.
"""

from __future__ import annotations

import logging
import os
import signal
import socket
import time
import traceback
from dataclasses import dataclass
from typing import Any

from fibersweep.errors import RUN_ERRORS, RunBug

__all__ = ["SettingSpec", "SweepTask", "WorkerSpec", "init_worker", "run_task", "failed_row"]

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
    """

    settings: str
    flow_key: str
    flow_json: str
    field_path: str
    fiber_json: str


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


_STATE: dict[str, Any] = {}


def _worker_name() -> str:
    return f"{socket.gethostname()}:{os.getpid()}"


def init_worker(spec: WorkerSpec, ignore_sigint: bool = True) -> None:
    """Map the first cached field, parse the fiber settings and warm Numba, once per process.

    Other fields are mapped when a task first needs them (:func:`_setting`).

    Parameters
    ----------
    spec : WorkerSpec
    ignore_sigint : bool
        Leave Ctrl-C to the parent, which stops the pool cleanly.
    """
    if ignore_sigint:
        try:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        except ValueError:  # not the main thread (e.g. a Dask worker thread)
            pass
    if _STATE.get("spec") == spec:
        return
    if not logging.getLogger().handlers:  # a fresh spawned process: log like the parent
        logging.basicConfig(
            level=spec.log_level,
            format="%(asctime)s %(name)s[%(process)d] %(levelname)s: %(message)s",
        )
    from fibersweep.fiber.settings import FiberSettings

    t0 = time.perf_counter()
    specs = spec.all_settings()
    fibers = {sid: FiberSettings.model_validate_json(s.fiber_json) for sid, s in specs.items()}
    _STATE.clear()
    _STATE.update(spec=spec, specs=specs, fibers=fibers, fields={}, n_tasks=0)
    first = next(iter(specs))
    field, fiber = _setting(first)
    _STATE.update(field=field, fiber=fiber)
    t1 = time.perf_counter()
    if spec.warm:
        warmed: set[str] = set()
        for sid, f in fibers.items():  # one warm-up per fiber model (its kernels)
            if f.model not in warmed:
                warmed.add(f.model)
                _warm(_setting(sid)[0] if f.model != fiber.model else field, f)
    log.info(
        "worker %s ready: field %.2f s, warm-up %.2f s",
        _worker_name(),
        t1 - t0,
        time.perf_counter() - t1,
    )


def _setting(sid: str) -> tuple[Any, Any]:
    """(flow field, fiber settings) of a settings id; the field mapped once per worker."""
    if "specs" not in _STATE:  # set up by hand (tests): the single field and fiber
        return _STATE["field"], _STATE["fiber"]
    specs = _STATE["specs"]
    if sid not in specs and len(specs) == 1:  # a single-setting spec runs every task
        sid = next(iter(specs))
    spec = specs[sid]
    fields = _STATE["fields"]
    if spec.flow_key not in fields:
        from fibersweep.flow.cache import load_entry
        from fibersweep.flow.settings import FlowSettings

        flow = FlowSettings.model_validate_json(spec.flow_json)
        # The parent verified the entry's checksums; workers only map it.
        fields[spec.flow_key] = load_entry(spec.field_path, flow, mmap=True, verify=False)
        log.debug("worker %s mapped field %s", _worker_name(), spec.flow_key)
    return fields[spec.flow_key], _STATE["fibers"][sid]


def _warm(field: Any, fiber: Any) -> None:
    """Compile the fiber kernels by running a short fiber far from the pillar."""
    from fibersweep.fiber.result import FiberStart
    from fibersweep.fiber.run import simulate

    short = fiber.model_copy(
        update={"step": fiber.step.model_copy(update={"t_max": 0.01})}, deep=True
    )
    try:
        simulate(field, short, FiberStart(theta0=0.0, y0=2.0, length=0.5))
    except RUN_ERRORS as exc:  # a warm-up problem must not hide the real runs' errors
        log.warning("warm-up run raised %s: %s", type(exc).__name__, exc)


def failed_row(task: SweepTask, reason: str, attempts: int = 1) -> dict[str, Any]:
    """The row recorded for a run that did not finish."""
    return {
        "id": task.key,
        "theta0": task.theta0,
        "y0": task.y0,
        "length": task.length,
        "class": "",
        "status": "failed",
        "reason": reason,
        "contact": False,
        "n_steps": 0,
        "wall_time": 0.0,
        "worker": "",
        "attempts": attempts,
        "finished_at": time.time(),
        **task.columns(),
    }


def run_task(task: SweepTask) -> dict[str, Any]:
    """Run one fiber in this worker.

    Returns
    -------
    dict
        ``{"row": dict of scalars, "trajectory": dict of arrays or None}``.
    """
    if not _STATE:
        raise RuntimeError("worker not initialised: init_worker was not called")
    from fibersweep.fiber.result import FiberStart
    from fibersweep.fiber.run import simulate

    start = FiberStart(theta0=task.theta0, y0=task.y0, length=task.length)
    field, fiber = _setting(task.settings)
    t0 = time.perf_counter()
    c0 = time.process_time()
    try:
        res = simulate(field, fiber, start)
    except RUN_ERRORS as exc:  # bad input or a failed computation: a failed run
        log.warning("run %s raised: %s", task.key, traceback.format_exc(limit=3))
        row = failed_row(task, f"exception {type(exc).__name__}: {exc}")
        row.update(wall_time=time.perf_counter() - t0, worker=_worker_name())
        return {"row": row, "trajectory": None}
    except Exception as exc:  # anything else is a bug: stop the sweep, say where
        raise RunBug(f"run {task.key} ({start}):\n{traceback.format_exc()}") from exc
    _STATE["n_tasks"] += 1
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
