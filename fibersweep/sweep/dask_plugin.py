"""Dask worker plugin that runs the sweep's worker initializer once per worker.

Imported only by the Dask executor (Dask is an optional extra). A worker that
joins later, or one the nanny restarts after a crash, runs ``setup`` too, so
every worker opens the cached flow field (memory-mapped, from a path the
workers can read) and warms Numba exactly once.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from distributed.diagnostics.plugin import WorkerPlugin

from fibersweep.sweep.executor_base import guarded_init

__all__ = ["InitPlugin"]


class InitPlugin(WorkerPlugin):
    """Calls ``initializer(*initargs)`` in every worker process when it starts.

    Errors are kept (see :func:`~fibersweep.sweep.executor_base.guarded_init`) and
    reported by the first task, which stops the sweep with the reason.

    Parameters
    ----------
    initializer : callable
        Picklable module-level function (e.g. :func:`fibersweep.sweep.worker.init_worker`).
    initargs : tuple
        Its arguments.
    """

    name = "fibersweep-init"

    def __init__(self, initializer: Callable[..., None] | None, initargs: tuple = ()) -> None:
        self.initializer = initializer
        self.initargs = initargs

    def setup(self, worker: Any) -> None:  # noqa: D102 (WorkerPlugin API)
        guarded_init(self.initializer, self.initargs)
