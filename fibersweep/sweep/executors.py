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
* Dask: the scheduler re-runs a dead worker's tasks elsewhere (up to
  ``distributed.scheduler.allowed-failures``) and ``retries`` covers exceptions;
  each task has its run id as key, so it can never be computed twice into the
  table.
"""

from __future__ import annotations

import logging
import multiprocessing as mp
import os
import socket
import traceback
from collections import defaultdict, deque
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any, Protocol

from fibersweep.errors import InputError, SolverError

__all__ = [
    "EXECUTORS",
    "DaskExecutor",
    "Executor",
    "LocalExecutor",
    "Outcome",
    "WorkerSetupError",
    "guarded_call",
    "guarded_init",
    "make_executor",
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


class Executor(Protocol):
    """Runs ``fn(task)`` for every task, yielding outcomes as they finish."""

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
    if isinstance(exc, WorkerSetupError):
        raise SolverError(f"worker set-up failed ({exc}); no run can succeed, stopping") from exc


class LocalExecutor:
    """``concurrent.futures.ProcessPoolExecutor`` (spawned processes) with crash recovery.

    Parameters
    ----------
    workers : int
        Worker processes.
    retries : int
        Times a task may be caught in a worker crash before it is reported failed.
    inflight_per_worker : int
        Tasks queued per worker (small, so a crash touches few tasks).
    """

    def __init__(self, workers: int = 2, retries: int = 2, inflight_per_worker: int = 2) -> None:
        if workers < 1:
            raise InputError(f"workers must be >= 1, got {workers}")
        self.workers = workers
        self.retries = retries
        self.cap = max(1, inflight_per_worker) * workers
        self.pools_started = 0

    def _pool(
        self, initializer: Callable[..., None] | None, initargs: tuple
    ) -> ProcessPoolExecutor:
        self.pools_started += 1
        # spawn: no inherited locks or threads from the parent (fork is unsafe with threads).
        return ProcessPoolExecutor(
            max_workers=self.workers,
            mp_context=mp.get_context("spawn"),
            initializer=guarded_init,
            initargs=(initializer, initargs),
        )

    @staticmethod
    def _stop(pool: ProcessPoolExecutor) -> None:
        pool.shutdown(wait=False, cancel_futures=True)
        terminate = getattr(pool, "terminate_workers", None)  # Python >= 3.14
        if terminate is not None:
            terminate()
            return
        for proc in list((getattr(pool, "_processes", None) or {}).values()):
            if proc.is_alive():
                proc.terminate()

    def run(
        self,
        fn: Callable[[Any], Any],
        tasks: Sequence[_Keyed],
        initializer: Callable[..., None] | None = None,
        initargs: tuple = (),
    ) -> Iterator[Outcome]:
        """Yield one :class:`Outcome` per task, in completion order."""
        fresh: deque = deque(tasks)
        suspects: deque = deque()  # in flight when a worker died: re-run alone
        strikes: dict[str, int] = defaultdict(int)
        barren = 0  # consecutive pools that broke without finishing anything
        while fresh or suspects:
            pool = self._pool(initializer, initargs)
            inflight: dict[Future, Any] = {}
            progressed = False
            crashed: list[Any] = []
            broken = False  # submit() found the pool already broken
            try:
                while (fresh or suspects or inflight) and not (crashed or broken):
                    # A task leaves its queue only once submit() accepted it: a worker
                    # that died since the last wait makes submit() raise, and the task,
                    # which never started, stays queued for the next pool, without a strike.
                    try:
                        if suspects:
                            if not inflight:
                                inflight[pool.submit(guarded_call, fn, suspects[0])] = suspects[0]
                                suspects.popleft()
                        else:
                            while fresh and len(inflight) < self.cap:
                                inflight[pool.submit(guarded_call, fn, fresh[0])] = fresh[0]
                                fresh.popleft()
                    except BrokenProcessPool:
                        broken = True
                    if not inflight:
                        break
                    done, _ = wait(list(inflight), return_when=FIRST_COMPLETED)
                    if broken or any(isinstance(f.exception(), BrokenProcessPool) for f in done):
                        wait(list(inflight))  # the rest fail at once (or had finished)
                        done = set(inflight)
                    for f in done:
                        t = inflight.pop(f)
                        exc = f.exception()
                        if isinstance(exc, BrokenProcessPool):
                            crashed.append(t)
                        elif exc is not None:
                            _setup_failed(exc)
                            yield Outcome(t.key, None, _describe(exc), strikes[t.key] + 1)
                        else:
                            progressed = True
                            yield Outcome(t.key, f.result(), "", strikes[t.key] + 1)
            finally:
                self._stop(pool)
            if not (crashed or broken):
                continue
            alone = len(crashed) == 1
            barren = 0 if progressed else barren + 1
            log.warning(
                "a worker process died with %d task(s) in flight; restarting the pool",
                len(crashed),
            )
            for t in crashed:
                strikes[t.key] += 1
                if strikes[t.key] > self.retries:
                    why = "alone" if alone else f"with {len(crashed) - 1} other task(s)"
                    yield Outcome(
                        t.key,
                        None,
                        f"worker process died (BrokenProcessPool) {strikes[t.key]} times, "
                        f"last {why}",
                        strikes[t.key],
                    )
                else:
                    suspects.append(t)
            if barren > self.retries + 2:
                raise SolverError(
                    f"worker processes keep dying without finishing any task ({barren} pools in a "
                    "row); is the worker set-up failing? Run with -v for worker logs."
                )


class DaskExecutor:
    """Runs tasks on a Dask cluster: an existing one, or a loopback LocalCluster.

    Parameters
    ----------
    workers : int
        Worker processes of the LocalCluster (ignored with ``scheduler``).
    scheduler : str or None
        Address of a running scheduler, e.g. ``tcp://10.0.0.5:8786``.
    retries : int
        Dask ``retries=`` of each task.
    """

    def __init__(self, workers: int = 2, scheduler: str | None = None, retries: int = 2) -> None:
        if workers < 1:
            raise InputError(f"workers must be >= 1, got {workers}")
        self.workers = workers
        self.scheduler = scheduler
        self.retries = retries

    def _client(self) -> tuple[Any, Any]:
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise InputError(
                "--executor dask needs Dask distributed: pip install 'fibersweep[dask]'"
            ) from None
        if self.scheduler:
            try:
                return Client(self.scheduler, timeout="20s"), None
            except OSError as exc:
                raise InputError(
                    f"cannot reach the Dask scheduler at {self.scheduler}: {exc}"
                ) from None
        if not log.isEnabledFor(logging.INFO):
            # Dask logs every worker start and stop at INFO; keep a plain run quiet.
            logging.getLogger("distributed").setLevel(logging.WARNING)
        cluster = LocalCluster(
            n_workers=self.workers,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address=None,
            silence_logs=logging.ERROR,
        )
        return Client(cluster), cluster

    def run(
        self,
        fn: Callable[[Any], Any],
        tasks: Sequence[_Keyed],
        initializer: Callable[..., None] | None = None,
        initargs: tuple = (),
    ) -> Iterator[Outcome]:
        """Yield one :class:`Outcome` per task, in completion order."""
        from distributed import as_completed

        from fibersweep.sweep.dask_plugin import InitPlugin

        client, cluster = self._client()
        try:
            client.register_plugin(InitPlugin(initializer, initargs), name="fibersweep-init")
            by_key = {}
            futures = []
            for t in tasks:
                key = f"fibersweep-run-{t.key}"
                by_key[key] = t
                futures.append(
                    client.submit(guarded_call, fn, t, key=key, retries=self.retries, pure=False)
                )
            for fut in as_completed(futures):
                t = by_key[fut.key]
                try:
                    value = fut.result()
                except Exception as exc:  # KilledWorker, or an exception after retries
                    _setup_failed(exc)
                    yield Outcome(t.key, None, _describe(exc))
                else:
                    yield Outcome(t.key, value)
                fut.release()
        finally:
            client.close()
            if cluster is not None:
                cluster.close()


EXECUTORS: dict[str, type] = {"local": LocalExecutor, "dask": DaskExecutor}


def make_executor(
    name: str, workers: int, scheduler: str | None = None, retries: int = 2
) -> LocalExecutor | DaskExecutor:
    """Executor by name; unknown names fail listing the valid ones."""
    if name not in EXECUTORS:
        raise InputError(f"unknown executor {name!r}; valid: {', '.join(EXECUTORS)}")
    if name == "local":
        if scheduler:
            raise InputError("--scheduler needs --executor dask")
        return LocalExecutor(workers, retries=retries)
    return DaskExecutor(workers, scheduler=scheduler, retries=retries)
