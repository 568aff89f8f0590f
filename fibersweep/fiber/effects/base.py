"""Base class of the effects and the context they get to build their kernel records."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, NamedTuple

import numpy as np

from fibersweep.errors import InputError

if TYPE_CHECKING:  # pragma: no cover
    from fibersweep.fiber.result import FiberStart, RunResult
    from fibersweep.flow.field import FlowField
    from fibersweep.units import Geometry

__all__ = ["DynamicsContext", "Effect"]


@dataclass(frozen=True)
class DynamicsContext:
    """What an effect may need to know to build its kernel record.

    Attributes
    ----------
    bead_radius : float
        a [µm].
    dx : float
        Flow-field node spacing [µm].
    depth : float
        Channel depth H_ch [µm].
    viscosity : float
        Fluid viscosity μ [pN·s/µm²].
    n_beads : int
        Beads of the fiber (for scratch arrays a kernel record carries).
    pillar : PillarArrays or None
        The run's pillar as the contact kernels read it (an array: the unit cell's
        pillar); None where no pillar is known (an effect then acts on none).
    frame : NamedTuple or None
        The run's frame (:mod:`fibersweep.fiber.frame`): a ``Lattice`` in an array;
        None or ``Channel`` for the single pillar.
    flow : NamedTuple or None
        The background field as the kernels read it (``ux, uy`` (nx, ny) [µm/s] on
        nodes ``dx`` [µm] apart, :class:`~fibersweep.fiber.kernel.bundles.FlowArrays`;
        in an array the padded cell); None where none is known.
    curvature : bool
        ``fiber.contact.curvature`` is ``local``: the near-wall normal resistance
        follows the surface's curvature (a circle's radius, ``corner_radius`` at a
        polygon's corners).
    corner_radius : float
        The pillar's corner radius r_c [µm] (``fiber.contact.corner_radius``).
    """

    bead_radius: float
    dx: float
    depth: float
    viscosity: float = 1.0
    n_beads: int = 1
    pillar: Any = None
    frame: Any = None
    flow: Any = None
    curvature: bool = False
    corner_radius: float = 0.0


@dataclass(frozen=True)
class Effect:
    """One optional physical or nuisance effect, set by a single float (0 = off).

    Subclasses set the class attributes ``name`` (the key in
    ``FiberSettings.effects``), ``unit`` (what the value means, for help texts)
    and override only the hooks they need; every hook defaults to identity, so
    an inactive effect costs nothing.

    Hooks, in the order :func:`fibersweep.fiber.run.simulate` applies them:

    ``transform_field(field)``
        Change the FlowField a run sees (e.g. inlet-speed scale).
    ``transform_start(start, rng)``
        Change the initial condition (e.g. start noise), with a seeded
        ``numpy.random.Generator``.
    ``sample_flow(flow, bead_radius)``
        Change the node velocities the beads' velocity is interpolated from (the
        kernels' ``FlowArrays``; in an array the padded cell), once per run: a
        correction linear in the field (e.g. Faxén's a²/6 ∇²u) costs nothing per
        step there. Other effects' records still see the field itself (``ctx.flow``).
    ``kernel(ctx)``
        An effect that acts inside the Numba integrators returns its *kernel
        record* (a ``typing.NamedTuple`` of floats and scratch arrays, defined in its module) and
        implements the kernel stages it needs for that record type in the same
        module (:func:`fibersweep.fiber.kernel.hooks.implements`); the integrators are
        compiled per set of active effects, so an effect that is off costs nothing.
        ``models`` lists the fiber models whose stages it implements.
    ``transform_result(result, start)``
        Change the finished run's report (e.g. back to nominal units), given
        the start the caller asked for.
    """

    name: ClassVar[str] = ""
    unit: ClassVar[str] = ""
    #: Fiber models the effect works in (its kernel stages exist for them).
    models: ClassVar[tuple[str, ...]] = ("rigid", "bead-spring")
    #: True when its kernel stages draw from Numba's random generator (seeded per run).
    random: ClassVar[bool] = False

    value: float = 0.0

    def __post_init__(self) -> None:
        if not math.isfinite(self.value):
            raise InputError(f"effects.{self.name}: value must be finite, got {self.value!r}")
        self.validate()

    def validate(self) -> None:
        """Check the value's range; raise InputError naming ``effects.<name>``."""

    def _require(self, ok: bool, what: str) -> None:
        if not ok:
            raise InputError(f"effects.{self.name}: {what}, got {self.value!r} ({self.unit})")

    @property
    def active(self) -> bool:
        """False when the value is the baseline 0."""
        return self.value != 0.0

    def transform_field(self, field: FlowField) -> FlowField:
        return field

    def transform_start(self, start: FiberStart, rng: np.random.Generator) -> FiberStart:
        return start

    def sample_flow(self, flow: NamedTuple, bead_radius: float) -> NamedTuple:
        """The ``FlowArrays`` (``ux, uy`` (nx, ny) [µm/s], ``dx`` [µm]) the beads sample."""
        return flow

    def kernel(self, ctx: DynamicsContext) -> NamedTuple | None:
        return None

    def transform_result(
        self, result: RunResult, start: FiberStart, geometry: Geometry
    ) -> RunResult:
        """The report in the units the user asked in (``geometry``: the run's channel)."""
        return result
