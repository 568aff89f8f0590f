"""The contract every sweep executor keeps: outcomes, the protocol, worker set-up guards.

An executor takes a picklable function, tasks with a ``key`` attribute, and an
optional per-worker initializer, and yields an :class:`Outcome` per task as
tasks finish (see :mod:`fibersweep.sweep.executors`). The initializer runs
under :func:`guarded_init` in each worker; its error is kept there and raised
by :func:`guarded_call` in place of every task on that worker, so the client
stops the sweep with the reason (:func:`_setup_failed`) instead of watching
workers die one by one.

Both guards share this module's state (``_SETUP_ERROR``), so they must stay
together here, top-level and picklable.
"""

from __future__ import annotations

import logging
import os
import socket
import traceback
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

from pydantic import BaseModel, ConfigDict, Field

from fibersweep.errors import RunBug, SolverError

__all__ = [
    "Executor",
    "ExecutorOptions",
    "Outcome",
    "WorkerSetupError",
    "guarded_call",
    "guarded_init",
]

log = logging.getLogger(__name__)


class _Keyed(Protocol):
    key: str


@dataclass(frozen=True)
class Outcome:
    """Result of one task.

    Attributes
    ----------
    key : str
    value : Any
        What the function returned (None on error).
    error : str
        Why the task failed ('' on success).
    attempts : int
        How many times the task was started.
    """

    key: str
    value: Any
    error: str = ""
    attempts: int = 1


class ExecutorOptions(BaseModel):
    """Options every executor takes; an executor's own options model extends it.

    :func:`~fibersweep.sweep.executors.make_executor` validates what it is given
    against the chosen executor's model (an unknown option fails naming the
    executors that take it), so a new option is one field here or in the
    executor's module, and the config's ``run.options`` passes it through.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    retries: int = Field(2, ge=0, description="re-runs of a task whose worker died")
    keep: bool = Field(
        False, description="keep the workers between run() calls (close() stops them)"
    )


class Executor(Protocol):
    """Runs ``fn(task)`` for every task, yielding outcomes as they finish.

    An executor declares what the callers need to know instead of being told
    apart by name:

    * ``name``: its key in :data:`~fibersweep.sweep.executors.EXECUTORS`;
    * ``Options``: its options model (an :class:`ExecutorOptions`);
    * ``parent_handles_ctrl_c``: True when the calling process handles Ctrl-C
      and stops the workers (the workers should then ignore SIGINT, as the
      local pool's do); False when the workers keep their own handling (Dask's).
    """

    name: ClassVar[str]
    Options: ClassVar[type[ExecutorOptions]]
    parent_handles_ctrl_c: ClassVar[bool]
    workers: int

    def run(
        self,
        fn: Callable[[Any], Any],
        tasks: Sequence[_Keyed],
        initializer: Callable[..., None] | None = None,
        initargs: tuple = (),
    ) -> Iterator[Outcome]: ...


def _describe(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}"


class WorkerSetupError(RuntimeError):
    """The per-worker initializer failed; every task on that worker would fail the same way."""


_SETUP_ERROR: list[str] = []


def guarded_init(initializer: Callable[..., None] | None, initargs: tuple) -> None:
    """Run the initializer in a worker, keeping its error instead of killing the process."""
    _SETUP_ERROR.clear()
    if initializer is None:
        return
    try:
        initializer(*initargs)
    except Exception as exc:
        log.error("worker set-up failed:\n%s", traceback.format_exc(limit=6))
        _SETUP_ERROR.append(f"{type(exc).__name__}: {exc}")


def guarded_call(fn: Callable[[Any], Any], task: Any) -> Any:
    """Run one task, unless this worker's set-up failed (then say why)."""
    if _SETUP_ERROR:
        raise WorkerSetupError(f"worker {socket.gethostname()}:{os.getpid()}: {_SETUP_ERROR[-1]}")
    return fn(task)


def _setup_failed(exc: BaseException | None) -> None:
    """Stop the sweep on errors no retry can fix: a failed worker set-up, a bug in a run."""
    if isinstance(exc, RunBug):
        raise SolverError(f"a run hit a bug, not a physical failure; stopping:\n{exc}") from exc
    if isinstance(exc, WorkerSetupError):
        raise SolverError(f"worker set-up failed ({exc}); no run can succeed, stopping") from exc
