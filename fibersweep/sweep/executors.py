"""Two ways to run many independent tasks, one interface: a local process pool and Dask.

Both take a picklable function, tasks with a ``key`` attribute, and an optional
per-worker initializer, and yield an :class:`Outcome` per task as tasks finish,
in completion order. Everything else (what to run, what to write, resume and
retry) is the caller's, so the bookkeeping is the same for both.

Worker death
------------
* local: the pool breaks (``BrokenProcessPool``); the tasks that were in flight
  get a strike and are re-run one at a time in a fresh pool, so an innocent
  task is never blamed for a neighbour's crash; a task that kills its worker
  more than ``retries`` times is reported as failed.
* Dask: runs travel in chunks (several runs per Dask task, see
  :func:`chunk_sizes`); the scheduler re-runs a dead worker's chunk elsewhere
  (up to ``distributed.scheduler.allowed-failures``, default 3). A chunk that
  still fails (``KilledWorker``, or an exception after Dask's ``retries``) has
  its runs re-run alone, one at a time, as the local pool does, so a run that
  kills its worker is reported failed alone, not with its chunk-mates. (The
  scheduler also gives a strike to every task assigned to a worker that dies,
  running or waiting, so a single-run task that shares a worker with a crashing
  one ``allowed-failures + 1`` times is reported failed too, as every task was
  before chunks.)
  A run that raises is caught inside its chunk, its chunk-mates are unaffected,
  and it is re-run alone up to ``retries`` times. Each outcome is yielded once,
  by the client, so a run is never recorded twice.

The pieces live in their own modules; every public name is importable from here:

* :mod:`fibersweep.sweep.executor_base`: :class:`Outcome`, the :class:`Executor`
  protocol, :class:`WorkerSetupError` and the worker set-up guards
  :func:`guarded_init` and :func:`guarded_call`;
* :mod:`fibersweep.sweep.local_executor`: :class:`LocalExecutor`;
* :mod:`fibersweep.sweep.dask_executor`: :class:`DaskExecutor` and its chunking
  (:func:`chunk_sizes`, :func:`run_chunk`). It imports Dask only when it runs,
  so importing this module never needs Dask.
"""

from __future__ import annotations

from typing import Any

from pydantic import ValidationError

from fibersweep.errors import InputError
from fibersweep.sweep.dask_executor import DaskExecutor, DaskOptions, chunk_sizes, run_chunk
from fibersweep.sweep.executor_base import (
    Executor,
    ExecutorOptions,
    Outcome,
    WorkerSetupError,
    guarded_call,
    guarded_init,
)
from fibersweep.sweep.local_executor import LocalExecutor, LocalOptions

__all__ = [
    "EXECUTORS",
    "DaskExecutor",
    "DaskOptions",
    "Executor",
    "ExecutorOptions",
    "LocalExecutor",
    "LocalOptions",
    "Outcome",
    "WorkerSetupError",
    "chunk_sizes",
    "executor_for_run",
    "guarded_call",
    "guarded_init",
    "make_executor",
    "run_chunk",
]


#: Executor classes by name. Each declares ``name``, its ``Options`` model and
#: ``parent_handles_ctrl_c`` (:class:`~fibersweep.sweep.executor_base.Executor`);
#: a new executor is one module and one entry here.
EXECUTORS: dict[str, type] = {cls.name: cls for cls in (LocalExecutor, DaskExecutor)}

# How some options are spelled on the command line / in the config, for messages
# (any other option is spelled run.options.NAME).
_OPTION_NAMES = {
    "scheduler": "--scheduler (run.scheduler)",
    "retries": "run.retries",
}


def _spelled(key: str) -> str:
    return _OPTION_NAMES.get(key, key)


def make_executor(
    name: str,
    workers: int,
    scheduler: str | None = None,
    retries: int = 2,
    **options: Any,
) -> Executor:
    """Executor by name from :data:`EXECUTORS`, with options checked by its ``Options`` model.

    Options left at None or False are not passed (the model's default holds). An
    unknown name fails listing the valid ones; an option the executor does not take
    fails naming the executors that do; a bad value fails naming the option.

    Raises
    ------
    InputError
    """
    if name not in EXECUTORS:
        raise InputError(f"unknown executor {name!r}; valid: {', '.join(EXECUTORS)}")
    cls = EXECUTORS[name]
    given = {"retries": retries, "scheduler": scheduler, **options}
    given = {k: v for k, v in given.items() if v is not None and v is not False}
    for key in given:
        if key not in cls.Options.model_fields:
            takers = [n for n, c in EXECUTORS.items() if key in c.Options.model_fields]
            where = f"the {' or '.join(takers)} executor only" if takers else "no executor"
            raise InputError(f"{_spelled(key)} applies to {where}, not {name!r}")
    try:
        opts = cls.Options(**given)
    except ValidationError as exc:
        err = exc.errors()[0]
        key = ".".join(str(p) for p in err["loc"])
        raise InputError(f"{_spelled(key)}: {err['msg']} (executor {name!r})") from None
    return cls(workers, **opts.model_dump())


def executor_for_run(run: Any, workers: int | None = None, **options: Any) -> Executor:
    """The executor a config's ``run`` section asks for, with extra ``options`` on top.

    Parameters
    ----------
    run : RunSettings
        ``executor``, ``workers``, ``scheduler``, ``retries`` and ``options``.
    workers : int, optional
        Replaces ``run.workers``.
    **options
        Options the caller sets (e.g. ``keep``); they win over ``run.options``.
    """
    merged = {**run.options, **options}
    return make_executor(run.executor, workers or run.workers, run.scheduler, run.retries, **merged)
