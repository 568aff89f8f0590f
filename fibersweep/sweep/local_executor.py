"""Local executor: a pool of spawned processes that survives its workers' crashes.

When a worker dies the pool breaks (``BrokenProcessPool``); the tasks that were
in flight get a strike and are re-run one at a time in a fresh pool, so an
innocent task is never blamed for a neighbour's crash; a task that kills its
worker more than ``retries`` times is reported as failed. See
:mod:`fibersweep.sweep.executors` for the interface it shares with Dask.
"""

from __future__ import annotations

import logging
import multiprocessing as mp
import os
from collections import defaultdict, deque
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from pydantic import Field

from fibersweep.errors import InputError, SolverError
from fibersweep.sweep.executor_base import (
    ExecutorOptions,
    Outcome,
    _describe,
    _Keyed,
    _setup_failed,
    guarded_call,
    guarded_init,
)
from fibersweep.sweep.lifeline import tie_to_parent

__all__ = ["LocalExecutor", "LocalOptions"]

log = logging.getLogger(__name__)

#: Seconds to wait for a stopped pool's worker (after SIGTERM, then SIGKILL) and thread.
_STOP_S = 5.0


def _pool_init(parent_pid: int, initializer: Callable[..., None] | None, initargs: tuple) -> None:
    """Worker start: end with the parent (even on SIGKILL), then the guarded set-up."""
    tie_to_parent(parent_pid)
    guarded_init(initializer, initargs)


class LocalOptions(ExecutorOptions):
    """Options of the local pool (see :class:`LocalExecutor`)."""

    inline: bool = Field(
        False,
        description="with one worker, run the tasks in this process (no pool to start, no "
        "crash isolation)",
    )


#: Thread counts of the BLAS libraries numpy may use, read when a process loads numpy.
BLAS_THREAD_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def _one_blas_thread_per_worker() -> None:
    """Spawned workers start with one BLAS thread each, unless the user chose a count.

    Each worker is one core's share of the pool: a BLAS call that spreads over every
    core (the bead-spring integrators' W = M J product does from 51 beads up) competes
    with the other workers, and such runs took 13-50 s against 1 s with one thread.
    The variables are read by a worker when it loads numpy, so they are set here, in
    the environment the workers inherit, before the pool starts them.
    """
    for var in BLAS_THREAD_VARS:
        os.environ.setdefault(var, "1")


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
    keep : bool
        Keep the pool between :meth:`run` calls with the same initializer and
        arguments (many small batches pay the worker start-up once); call
        :meth:`close`, or use the executor as a context manager.
    inline : bool
        With one worker, run the tasks in this process: the initializer once per
        distinct set-up, then each task (no pool to start; a run that kills the
        process kills the caller).
    """

    name = "local"
    Options = LocalOptions
    #: Options :func:`~fibersweep.sweep.executors.make_executor` may pass.
    OPTIONS = frozenset(LocalOptions.model_fields)
    #: The parent stops the pool on Ctrl-C; workers ignore SIGINT.
    parent_handles_ctrl_c = True

    def __init__(
        self,
        workers: int = 2,
        retries: int = 2,
        inflight_per_worker: int = 2,
        keep: bool = False,
        inline: bool = False,
    ) -> None:
        if workers < 1:
            raise InputError(f"workers must be >= 1, got {workers}")
        self.workers = workers
        self.inline = inline and workers == 1
        self._inline_ident: tuple | None = None
        self.retries = retries
        self.cap = max(1, inflight_per_worker) * workers
        self.keep = keep
        self.pools_started = 0
        self._kept: tuple[tuple, ProcessPoolExecutor] | None = None

    def __enter__(self) -> LocalExecutor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Stop a kept pool (nothing to do otherwise)."""
        if self._kept is not None:
            self._stop(self._kept[1])
            self._kept = None

    def _acquire(
        self, initializer: Callable[..., None] | None, initargs: tuple
    ) -> ProcessPoolExecutor:
        """The kept pool if it was set up the same way, else a new one."""
        ident = (initializer, tuple(id(a) for a in initargs))
        if self._kept is not None and self._kept[0] == ident:
            pool = self._kept[1]
            self._kept = None
            return pool
        self.close()
        pool = self._pool(initializer, initargs)
        if self.keep:
            self._ident = ident
        return pool

    def _pool(
        self, initializer: Callable[..., None] | None, initargs: tuple
    ) -> ProcessPoolExecutor:
        self.pools_started += 1
        _one_blas_thread_per_worker()
        # spawn: no inherited locks or threads from the parent (fork is unsafe with threads).
        return ProcessPoolExecutor(
            max_workers=self.workers,
            mp_context=mp.get_context("spawn"),
            initializer=_pool_init,
            initargs=(os.getpid(), initializer, initargs),
        )

    def _run_inline(
        self,
        fn: Callable[[Any], Any],
        tasks: Sequence[_Keyed],
        initializer: Callable[..., None] | None,
        initargs: tuple,
    ) -> Iterator[Outcome]:
        """Run the tasks in this process, in order; a task's exception stops the caller."""
        ident = (initializer, tuple(id(a) for a in initargs))
        if initializer is not None and ident != self._inline_ident:
            initializer(*initargs)
            self._inline_ident = ident
        for t in tasks:
            try:
                value = fn(t)
            except Exception as exc:
                _setup_failed(exc)  # a bug in a run stops the caller, as in the pool
                raise
            yield Outcome(t.key, value)

    @staticmethod
    def _stop(pool: ProcessPoolExecutor) -> None:
        """Stop ``pool`` now: cancel what waits, end its workers, let its manager thread finish.

        Its workers are ended, not asked: a worker left blocked (for instance on the
        task queue's lock, held by a worker that was killed) would keep the pool's
        manager thread, and so interpreter shutdown, waiting for ever.
        """
        manager = getattr(pool, "_executor_manager_thread", None)  # shutdown() forgets it
        pool.shutdown(wait=False, cancel_futures=True)
        procs = list((getattr(pool, "_processes", None) or {}).values())
        terminate = getattr(pool, "terminate_workers", None)  # Python >= 3.14
        if terminate is not None:
            terminate()
        else:
            for proc in procs:
                if proc.is_alive():
                    proc.terminate()
        for proc in procs:
            proc.join(timeout=_STOP_S)
            if proc.is_alive():  # SIGTERM did not do it
                proc.kill()
                proc.join(timeout=_STOP_S)
        if manager is not None:
            manager.join(timeout=_STOP_S)
            if manager.is_alive():
                log.warning("a stopped worker pool's manager thread is still running")

    def run(
        self,
        fn: Callable[[Any], Any],
        tasks: Sequence[_Keyed],
        initializer: Callable[..., None] | None = None,
        initargs: tuple = (),
    ) -> Iterator[Outcome]:
        """Yield one :class:`Outcome` per task, in completion order."""
        if self.inline:
            yield from self._run_inline(fn, tasks, initializer, initargs)
            return
        fresh: deque = deque(tasks)
        suspects: deque = deque()  # in flight when a worker died: re-run alone
        strikes: dict[str, int] = defaultdict(int)
        barren = 0  # consecutive pools that broke without finishing anything
        while fresh or suspects:
            pool = (
                self._acquire(initializer, initargs)
                if self.keep
                else self._pool(initializer, initargs)
            )
            inflight: dict[Future, Any] = {}
            progressed = False
            crashed: list[Any] = []
            broken = False  # submit() found the pool already broken
            clean = False  # the loop ended by itself (no error, not abandoned)
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
                    except (BrokenProcessPool, BrokenPipeError, ConnectionResetError):
                        # BrokenPipeError: submit() also starts workers, and one killed
                        # while it was being started breaks the pipe that feeds it.
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
                clean = True
            finally:
                # A kept pool must be whole and idle; anything else is stopped.
                if self.keep and clean and not (crashed or broken or inflight):
                    self._kept = (self._ident, pool)
                else:
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
