"""Dask executor: runs sent in chunks to a Dask cluster, outcomes reported run by run.

Runs travel in chunks (several runs per Dask task, see :func:`chunk_sizes`);
the scheduler re-runs a dead worker's chunk elsewhere (up to
``distributed.scheduler.allowed-failures``, default 3). A chunk that still
fails (``KilledWorker``, or an exception after Dask's ``retries``) has its runs
re-run alone, one at a time, as the local pool does, so a run that kills its
worker is reported failed alone, not with its chunk-mates. (The scheduler also
gives a strike to every task assigned to a worker that dies, running or
waiting, so a single-run task that shares a worker with a crashing one
``allowed-failures + 1`` times is reported failed too.) A run that raises is
caught inside its chunk (:func:`run_chunk`), its chunk-mates are unaffected,
and it is re-run alone up to ``retries`` times. Each outcome is yielded once,
by the client (:class:`_Dispatch`), so a run is never recorded twice. See
:mod:`fibersweep.sweep.executors` for the interface it shares with the local pool.

Dask is an optional extra: this module imports it only inside
:class:`DaskExecutor`'s methods, so importing it never needs Dask.
:func:`run_chunk` is sent to the workers and must stay a top-level function.
"""

from __future__ import annotations

import logging
import math
from collections import Counter, deque
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any

from pydantic import Field

from fibersweep.errors import InputError, RunBug
from fibersweep.sweep.executor_base import (
    ExecutorOptions,
    Outcome,
    WorkerSetupError,
    _describe,
    _Keyed,
    _setup_failed,
    guarded_call,
)

__all__ = [
    "CHUNKS_PER_SLOT",
    "MAX_CHUNK",
    "DaskExecutor",
    "DaskOptions",
    "chunk_sizes",
    "run_chunk",
]

log = logging.getLogger(__name__)


CHUNKS_PER_SLOT = 2
"""Automatic chunks: each takes 1/(slots * CHUNKS_PER_SLOT) of the runs not yet chunked."""
MAX_CHUNK = 16
"""Largest automatic chunk (runs lost to a worker death or a Ctrl-C, progress granularity)."""


def chunk_sizes(
    n_tasks: int,
    slots: int,
    chunk_size: int | None = None,
    *,
    per_slot: int = CHUNKS_PER_SLOT,
    largest: int = MAX_CHUNK,
) -> list[int]:
    """Sizes of the consecutive chunks that ``n_tasks`` runs are sent in.

    Why chunks: a Dask task costs a few milliseconds of scheduler, client and
    transfer work (2-16 ms measured on a shared 2-core machine), against runs of
    about 80 ms; sending ``k`` runs per task divides that cost by ``k``. Chunks
    that are too large cost too: at the end of a sweep a worker still busy with
    a long chunk leaves the others idle, a worker death or a Ctrl-C loses a whole
    chunk's finished runs, and progress arrives in bursts.

    How the size is chosen (``chunk_size`` None): guided, as OpenMP's
    ``schedule(guided)``. Each chunk takes ``ceil(remaining / (slots * per_slot))``
    of the runs not yet chunked, clipped to ``[1, largest]``. The first chunk is
    ``ceil(n_tasks / (slots * per_slot))``; sizes then shrink to 1, so the last
    tasks of a sweep are single runs and the workers finish together (a fixed
    size would leave, on average, half a chunk of idle time at the end). Dask
    runs tasks roughly in submission order, so large chunks go first. A large
    sweep is sent almost entirely in chunks of ``largest``; it ends with about
    ``slots * per_slot`` single runs. With ``per_slot = 2`` a 100-run sweep on 2
    workers is 15 tasks (16, 16, 16, 13, 10, ..., 1), as many as a fixed
    ``ceil(100 / (2 * 8)) = 7`` would give, but without the idle tail; each chunk
    is at most half a slot's share of the work left, which keeps the balance when
    run times differ (runs over the pillar take ~3x those that miss it).

    Parameters
    ----------
    n_tasks : int
        Runs to send (>= 0).
    slots : int
        Tasks the cluster runs at once (worker threads), >= 1.
    chunk_size : int, optional
        Fixed size instead (the last chunk takes the rest); 1 gives one Dask task
        per run.
    per_slot : int
        Divisor of the guided rule: a chunk takes ``1 / (slots * per_slot)`` of
        the runs left.
    largest : int
        Upper clip of the guided rule.

    Returns
    -------
    list of int
        Positive sizes summing to ``n_tasks``, non-increasing.
    """
    if n_tasks < 0:
        raise InputError(f"n_tasks must be >= 0, got {n_tasks}")
    if slots < 1 or per_slot < 1 or largest < 1:
        raise InputError(
            f"slots, per_slot and largest must be >= 1: {slots}, {per_slot}, {largest}"
        )
    if chunk_size is not None:
        if chunk_size < 1:
            raise InputError(f"chunk_size must be >= 1, got {chunk_size}")
        full, rest = divmod(n_tasks, chunk_size)
        return [chunk_size] * full + ([rest] if rest else [])
    sizes: list[int] = []
    remaining = n_tasks
    while remaining:
        size = min(largest, max(1, math.ceil(remaining / (slots * per_slot))))
        sizes.append(size)
        remaining -= size
    return sizes


def _split(tasks: Sequence[_Keyed], sizes: Sequence[int]) -> list[list[_Keyed]]:
    """Consecutive slices of ``tasks`` of the given sizes."""
    chunks, start = [], 0
    for size in sizes:
        chunks.append(list(tasks[start : start + size]))
        start += size
    return chunks


@contextmanager
def _quiet_dask() -> Iterator[None]:
    """Dask logs every worker start and stop at INFO: keep a plain run quiet.

    Only while the executor runs; the ``distributed`` logger's level is restored
    afterwards, so the caller's logging is left as it was.
    """
    logger = logging.getLogger("distributed")
    old = logger.level
    if not log.isEnabledFor(logging.INFO):
        logger.setLevel(logging.WARNING)
    try:
        yield
    finally:
        logger.setLevel(old)


def run_chunk(fn: Callable[[Any], Any], tasks: Sequence[_Keyed]) -> list[Outcome]:
    """Run several tasks in one Dask task: one :class:`Outcome` per task, in order.

    An exception of one task becomes that task's outcome (``error`` set); the
    others still run. Only :class:`WorkerSetupError` escapes, failing the whole
    chunk, since every task on this worker would fail the same way.
    """
    outcomes = []
    for t in tasks:
        try:
            value = guarded_call(fn, t)
        except (WorkerSetupError, RunBug):
            raise
        except Exception as exc:
            log.debug("run %s raised", t.key, exc_info=True)
            outcomes.append(Outcome(t.key, None, _describe(exc)))
        else:
            outcomes.append(Outcome(t.key, value))
    return outcomes


def _chunk_key(chunk: Sequence[_Keyed], attempt: int) -> str:
    """Dask key of a chunk: its first run's id, its size, and the try (unique per submission)."""
    first = chunk[0].key
    base = (
        f"fibersweep-run-{first}" if len(chunk) == 1 else f"fibersweep-chunk-{first}-x{len(chunk)}"
    )
    return base if attempt == 1 else f"{base}-try{attempt}"


class _Dispatch:
    """Client-side book of one Dask run: chunks in flight, runs to re-run, tries per run.

    Two kinds of re-run, both as single-run tasks:

    * a run that raised inside its chunk is re-run at once while it has retries
      left (the chunk-mates' outcomes stand);
    * the runs of a chunk that failed as a whole (``KilledWorker`` once the
      scheduler gave up on it after ``allowed-failures`` worker deaths, or an
      exception after Dask's retries) become suspects, re-run alone and one at a
      time, as the local pool does, so that a run that kills its worker cannot
      take a fellow suspect with it. A single-run task that fails so is reported
      failed with the reason.
    """

    def __init__(self, client: Any, fn: Callable[[Any], Any], retries: int) -> None:
        self.client = client
        self.fn = fn
        self.retries = retries
        self.tries: Counter[str] = Counter()  # times each run was submitted
        self.chunks: dict[str, list[_Keyed]] = {}  # Dask key -> its runs, while in flight
        self.again: list[_Keyed] = []  # raised: re-run at once
        self.suspects: deque = deque()  # of a failed chunk: re-run alone, one at a time
        self.suspect: str | None = None  # Dask key of the suspect in flight
        self.submitted = 0

    def submit(self, chunk: list[_Keyed]) -> Any:
        """Send one chunk as one Dask task; returns its future."""
        for t in chunk:
            self.tries[t.key] += 1
        key = _chunk_key(chunk, max(self.tries[t.key] for t in chunk))
        self.chunks[key] = chunk
        self.submitted += 1
        return self.client.submit(
            run_chunk, self.fn, chunk, key=key, retries=self.retries, pure=False
        )

    def settle(self, fut: Any) -> list[Outcome]:
        """Outcomes to report from one completed chunk; queues what must run again.

        A failed worker set-up stops the sweep (:class:`SolverError`).
        """
        chunk = self.chunks.pop(fut.key)
        if fut.key == self.suspect:
            self.suspect = None
        try:
            outcomes: list[Outcome] = fut.result()
        except Exception as exc:  # KilledWorker, or an exception after retries
            _setup_failed(exc)
            if len(chunk) > 1:
                log.warning(
                    "a Dask task of %d runs failed (%s); re-running each run alone",
                    len(chunk),
                    _describe(exc),
                )
                self.suspects.extend(chunk)
                return []
            t = chunk[0]
            return [Outcome(t.key, None, _describe(exc), self.tries[t.key])]
        report = []
        for t, oc in zip(chunk, outcomes, strict=True):
            if oc.error and self.tries[t.key] <= self.retries:
                log.info("run %s raised (%s); re-running it", t.key, oc.error)
                self.again.append(t)
            else:
                report.append(Outcome(oc.key, oc.value, oc.error, self.tries[t.key]))
        return report

    def resubmit(self) -> list[Any]:
        """Futures of the re-runs due now: raised runs at once, the next suspect if none runs."""
        new = [self.submit([t]) for t in self.again]
        self.again.clear()
        if self.suspect is None and self.suspects:
            fut = self.submit([self.suspects.popleft()])
            self.suspect = fut.key
            new.append(fut)
        return new


def local_cluster(workers: int) -> Any:
    """A loopback LocalCluster of ``workers`` single-threaded processes, serving no web pages.

    Dask's scheduler and workers always open an HTTP port (with ``dashboard_address=None``
    the scheduler still serves its dashboard routes on 127.0.0.1:8787). Here every HTTP
    route is switched off and the ports are OS-chosen on 127.0.0.1: nothing answers there.
    """
    import dask
    from distributed import LocalCluster

    no_pages = {"distributed.scheduler.http.routes": [], "distributed.worker.http.routes": []}
    with dask.config.set(no_pages):
        return LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address=None,
            scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"},
            worker_dashboard_address=None,
            silence_logs=logging.ERROR,
        )


class DaskOptions(ExecutorOptions):
    """Options of the Dask executor (see :class:`DaskExecutor`)."""

    scheduler: str | None = Field(
        None, description="address of a running scheduler, e.g. tcp://10.0.0.5:8786"
    )
    chunk_size: int | None = Field(
        None, ge=1, description="runs per Dask task (None: chosen from the runs and threads)"
    )


class DaskExecutor:
    """Runs tasks on a Dask cluster: an existing one, or a loopback LocalCluster.

    Runs are sent in chunks, several per Dask task, to amortise Dask's per-task
    cost (see :func:`chunk_sizes`); outcomes are still yielded one per run, as
    each chunk completes.

    Parameters
    ----------
    workers : int
        Worker processes of the LocalCluster (ignored with ``scheduler``).
    scheduler : str or None
        Address of a running scheduler, e.g. ``tcp://10.0.0.5:8786``.
    retries : int
        Dask ``retries=`` of each chunk (exceptions that fail a whole chunk, such
        as a failed worker set-up), and how many times a run that raised is re-run.
    chunk_size : int or None
        Runs per Dask task; None chooses them from the number of runs and worker
        threads (:func:`chunk_sizes`), 1 sends one task per run.
    keep : bool
        Keep the client (and the LocalCluster) between :meth:`run` calls; the
        worker set-up runs again only when the initializer or its arguments
        change. Call :meth:`close`, or use the executor as a context manager.

    Attributes
    ----------
    chunks_submitted : int
        Dask tasks submitted by the last :meth:`run` (re-runs included).
    """

    def __init__(
        self,
        workers: int = 2,
        scheduler: str | None = None,
        retries: int = 2,
        chunk_size: int | None = None,
        keep: bool = False,
    ) -> None:
        if workers < 1:
            raise InputError(f"workers must be >= 1, got {workers}")
        if chunk_size is not None and chunk_size < 1:
            raise InputError(f"chunk_size must be >= 1, got {chunk_size}")
        self.workers = workers
        self.scheduler = scheduler
        self.retries = retries
        self.chunk_size = chunk_size
        self.keep = keep
        self.chunks_submitted = 0
        self._session: tuple[Any, Any] | None = None  # (client, cluster) kept
        self._plugin_ident: tuple | None = None

    name = "dask"
    Options = DaskOptions
    #: Options :func:`~fibersweep.sweep.executors.make_executor` may pass.
    OPTIONS = frozenset(DaskOptions.model_fields)
    #: Dask workers keep their own signal handling; the client only stops waiting.
    parent_handles_ctrl_c = False

    def __enter__(self) -> DaskExecutor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Close a kept client and its LocalCluster (nothing to do otherwise)."""
        if self._session is None:
            return
        client, cluster = self._session
        self._session = None
        self._plugin_ident = None
        with _quiet_dask():
            client.close()
            if cluster is not None:
                cluster.close()

    def _client(self) -> tuple[Any, Any]:
        try:
            from distributed import Client
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
        cluster = local_cluster(self.workers)
        return Client(cluster), cluster

    def _slots(self, client: Any) -> int:
        """Worker threads of the cluster now (``workers`` if none has joined yet)."""
        return sum(client.nthreads().values()) or self.workers

    def run(
        self,
        fn: Callable[[Any], Any],
        tasks: Sequence[_Keyed],
        initializer: Callable[..., None] | None = None,
        initargs: tuple = (),
    ) -> Iterator[Outcome]:
        """Yield one :class:`Outcome` per task, in completion order (chunk by chunk)."""
        from fibersweep.sweep.dask_plugin import InitPlugin

        if len({t.key for t in tasks}) != len(tasks):
            raise InputError("task keys must be unique (they name the Dask tasks)")
        self.chunks_submitted = 0
        with _quiet_dask():
            if self._session is None:
                self._session = self._client()
            client, _ = self._session
            clean = False
            try:
                ident = (initializer, tuple(id(a) for a in initargs))
                if ident != self._plugin_ident:
                    client.register_plugin(
                        InitPlugin(initializer, initargs), name="fibersweep-init"
                    )
                    self._plugin_ident = ident
                yield from self._run_chunks(client, fn, tasks)
                clean = True
            finally:
                if not (self.keep and clean):
                    self.close()

    def _run_chunks(
        self, client: Any, fn: Callable[[Any], Any], tasks: Sequence[_Keyed]
    ) -> Iterator[Outcome]:
        """Submit the chunks; settle each as it completes (see :class:`_Dispatch`)."""
        from distributed import as_completed

        sizes = chunk_sizes(len(tasks), self._slots(client), self.chunk_size)
        if sizes:
            log.info(
                "Dask: %d runs in %d tasks of %d..%d", len(tasks), len(sizes), sizes[-1], sizes[0]
            )
        book = _Dispatch(client, fn, self.retries)
        pending = as_completed([book.submit(c) for c in _split(tasks, sizes)])
        for fut in pending:
            report = book.settle(fut)
            fut.release()
            for new in book.resubmit():
                pending.add(new)
            self.chunks_submitted = book.submitted
            yield from report
