"""Base class of the effects and the numeric parameters they hand to the dynamics kernels."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from fibersweep.errors import InputError

if TYPE_CHECKING:  # pragma: no cover
    from fibersweep.fiber.result import FiberStart, RunResult
    from fibersweep.fiber.settings import FiberSettings
    from fibersweep.flow.field import FlowField
    from fibersweep.flow.settings import FlowSettings

__all__ = ["DynamicsContext", "DynamicsParams", "Effect"]


@dataclass(frozen=True)
class DynamicsContext:
    """What an effect may need to know to set its dynamics parameters.

    Attributes
    ----------
    bead_radius : float
        a [µm].
    dx : float
        Flow-field node spacing [µm].
    depth : float
        Channel depth H_ch [µm].
    """

    bead_radius: float
    dx: float
    depth: float


@dataclass(frozen=True)
class DynamicsParams:
    """Floats the Numba kernels read; the defaults are the baseline (no effect, no cost).

    Attributes
    ----------
    velocity_scale : float
        Factor on every bead's background velocity (off-midplane layers) [-].
    friction : float
        Coulomb friction coefficient on the pillar (tangential/normal force) [-].
    hydro_strength : float
        Multiplier on the Faxén drag of a bead beside the pillar (0 = no pillar hydrodynamics) [-].
    hydro_length : float
        Screening length of that drag [µm].
    kT : float
        Thermal energy for Brownian motion [pN·µm]; 0 = deterministic.
    """

    velocity_scale: float = 1.0
    friction: float = 0.0
    hydro_strength: float = 0.0
    hydro_length: float = 1.0
    kT: float = 0.0

    def with_(self, **changes: float) -> DynamicsParams:
        """A copy with some fields changed."""
        return replace(self, **changes)


@dataclass(frozen=True)
class Effect:
    """One optional physical or nuisance effect, set by a single float (0 = off).

    Subclasses set the class attributes ``name`` (the key in
    ``FiberSettings.effects``), ``unit`` (what the value means, for help texts)
    and override only the hooks they need; every hook defaults to identity, so
    an inactive effect costs nothing.

    Hooks, in the order :func:`fibersweep.fiber.run.simulate` applies them:

    ``transform_flow(flow_settings)``
        Change the flow problem (e.g. pillar size); used by callers that build
        the field (the sweep / CLI), since ``simulate`` receives a field.
    ``transform_field(field)``
        Change the FlowField a run sees (e.g. inlet-speed scale).
    ``transform_settings(settings)``
        Change the FiberSettings of a run (e.g. contact parameters).
    ``transform_start(start, rng)``
        Change the initial condition (e.g. start noise), with a seeded
        ``numpy.random.Generator``.
    ``dynamics(params, ctx)``
        Change the numeric :class:`DynamicsParams` the Numba kernels read.
    ``transform_result(result, start)``
        Change the finished run's report (e.g. back to nominal units), given
        the start the caller asked for.
    """

    name: ClassVar[str] = ""
    unit: ClassVar[str] = ""

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

    def transform_flow(self, flow: FlowSettings) -> FlowSettings:
        return flow

    def transform_field(self, field: FlowField) -> FlowField:
        return field

    def transform_settings(self, settings: FiberSettings) -> FiberSettings:
        return settings

    def transform_start(self, start: FiberStart, rng: np.random.Generator) -> FiberStart:
        return start

    def dynamics(self, params: DynamicsParams, ctx: DynamicsContext) -> DynamicsParams:
        return params

    def transform_result(self, result: RunResult, start: FiberStart) -> RunResult:
        return result
