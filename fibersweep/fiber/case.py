"""What a run's case hands the one run path of :mod:`fibersweep.fiber.run`.

A fiber runs past the single pillar in its channel (:mod:`fibersweep.fiber.channel`)
or through a tilted pillar array (:mod:`fibersweep.fiber.array_run`). Both are
the same path (:func:`fibersweep.fiber.run.simulate`): resolve the integrator,
*place* the fiber, seed the effects' randomness, integrate, *measure*. A case
supplies only the two steps in italics, and says which fields it takes:

``accepts(field) -> bool``
    Whether ``field`` is this case's (the path asks the cases in turn).
``place(field, settings, start, rng, *, mode, t_stop) -> Placed``
    Check the start in the case's units (InputError naming the parameter),
    place the fiber, and build its :class:`~fibersweep.fiber.kernel.bundles.Kernel`
    in the case's frame (:mod:`fibersweep.fiber.frame`) with the case's stop
    rule: mode 0 stops past the pillar (channel) or after the configured rows
    (array); mode 1 at ``t_stop`` [s]. ``rng`` is the run's generator
    (``numpy.random.default_rng(rng_seed)``), fresh: the case draws from it
    only what its effects draw at the start.
``measure(placed, field, settings, start, outcome) -> RunResult``
    The run's report from its record (``field`` and ``start`` as the caller
    passed them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple, Protocol

import numpy as np

from fibersweep.config.fiber import FiberSettings
from fibersweep.fiber.kernel.bundles import Kernel
from fibersweep.fiber.models.registry import Integrator
from fibersweep.fiber.result import FiberStart, RunResult

__all__ = ["Case", "Outcome", "Placed"]


@dataclass(frozen=True)
class Placed:
    """A checked run, ready to integrate.

    Attributes
    ----------
    kernel : Kernel
        Every input of the integrator (frame, stop rule, effects).
    x0, y0 : float
        Start centre [µm].
    th0 : float
        Directed angle of the axis towards bead n-1, the head [rad].
    n : int
        Beads.
    random : bool
        Whether an effect draws from Numba's generator (the path seeds it).
    state : Any
        What the case's ``measure`` reads besides the record (the channel: its
        :class:`~fibersweep.fiber.setup.Setup`; an array: its pillar).
    """

    kernel: Kernel
    x0: float
    y0: float
    th0: float
    n: int
    random: bool
    state: Any


class Outcome(NamedTuple):
    """What the integrator returned.

    ``rec`` the record rows (:data:`fibersweep.fiber.kernel.record.COLS`), ``beads``
    the bead positions (rows, n, 2) [µm] or None (rigid), ``code`` the stop code,
    ``wall`` the seconds from the call to the end of the integration.
    """

    integrator: Integrator
    rec: np.ndarray
    beads: np.ndarray | None
    code: int
    wall: float


class Case(Protocol):
    """One case of the run path (see the module docstring)."""

    name: str

    def accepts(self, field: Any) -> bool: ...

    def place(
        self,
        field: Any,
        settings: FiberSettings,
        start: FiberStart,
        rng: np.random.Generator,
        *,
        mode: int = 0,
        t_stop: float = math.nan,
    ) -> Placed: ...

    def measure(
        self, placed: Placed, field: Any, settings: FiberSettings, start: FiberStart, out: Outcome
    ) -> RunResult: ...
