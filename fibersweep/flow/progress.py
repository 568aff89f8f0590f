"""Progress of a flow solve, reported to whoever asked for it (the CLI's bar).

The solver never prints. It calls :func:`report` after every convergence check;
a caller that wants to show progress wraps the solve in :func:`on_progress`::

    with on_progress(lambda p: bar.update(...)):
        get_flow_field(settings, cache_dir)

The callback is held in a context variable, so it reaches the solver through the
cache and the nested (coarse-to-fine) solve without being passed down, and a solve
in another thread or process reports nothing.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass

__all__ = ["SolveProgress", "on_progress", "report"]


@dataclass(frozen=True)
class SolveProgress:
    """State of a lattice solve after a convergence check.

    Attributes
    ----------
    dx : float
        Lattice spacing of the grid being solved [µm] (coarser grids come first).
    steps : int
        LBM steps done on this grid.
    max_steps : int
        Hard limit on the steps (``flow.max_steps``).
    residual : float
        Relative change of the in-plane velocity over the last check interval.
    tolerance : float
        Residual at which the solve stops (``flow.tolerance``).
    cells : int
        Lattice cells of this grid.
    """

    dx: float
    steps: int
    max_steps: int
    residual: float
    tolerance: float
    cells: int

    @property
    def finished(self) -> bool:
        """True on the last report of this grid: converged, or ``max_steps`` reached.

        The solver stops right after such a report (or raises on divergence), so a
        bar can close here instead of when the whole command ends.
        """
        return self.steps > 0 and (self.residual < self.tolerance or self.steps >= self.max_steps)


_CALLBACK: ContextVar[Callable[[SolveProgress], None] | None] = ContextVar(
    "fibersweep_flow_progress", default=None
)


@contextmanager
def on_progress(callback: Callable[[SolveProgress], None]) -> Iterator[None]:
    """Send the progress of every flow solve inside the block to ``callback``."""
    token = _CALLBACK.set(callback)
    try:
        yield
    finally:
        _CALLBACK.reset(token)


def report(progress: SolveProgress) -> None:
    """Hand ``progress`` to the active callback, if any (called by the solver)."""
    callback = _CALLBACK.get()
    if callback is not None:
        callback(progress)
