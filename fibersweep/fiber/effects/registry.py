"""Registry of effects: name -> Effect subclass, and the set applied to one run."""

from __future__ import annotations

import difflib
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from fibersweep.errors import InputError
from fibersweep.fiber.effects.base import DynamicsContext, Effect

if TYPE_CHECKING:  # pragma: no cover
    from fibersweep.fiber.result import FiberStart, RunResult
    from fibersweep.flow.field import FlowField
    from fibersweep.units import Geometry

__all__ = ["EFFECTS", "EffectSet", "build_effects", "get_effect", "register"]

EFFECTS: dict[str, type[Effect]] = {}


def register(cls: type[Effect]) -> type[Effect]:
    """Class decorator adding an Effect subclass under ``cls.name``."""
    if not cls.name:
        raise TypeError(f"{cls.__name__} has no name")
    if cls.name in EFFECTS and EFFECTS[cls.name] is not cls:
        raise TypeError(f"effect name {cls.name!r} registered twice")
    EFFECTS[cls.name] = cls
    return cls


def get_effect(name: str) -> type[Effect]:
    """The Effect class for ``name``; InputError listing the valid names otherwise."""
    try:
        return EFFECTS[name]
    except KeyError:
        valid = ", ".join(sorted(EFFECTS))
        close = difflib.get_close_matches(name, list(EFFECTS), n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise InputError(f"effects: unknown effect {name!r}{hint}; valid names: {valid}") from None


@dataclass(frozen=True)
class EffectSet:
    """The active effects of one run (inactive ones are dropped: they cost nothing)."""

    effects: tuple[Effect, ...] = ()

    def field(self, field: FlowField) -> FlowField:
        for e in self.effects:
            field = e.transform_field(field)
        return field

    def sample_flow(self, flow: Any, bead_radius: float) -> Any:
        """The node velocities the beads sample (:meth:`Effect.sample_flow`, in order)."""
        for e in self.effects:
            flow = e.sample_flow(flow, bead_radius)
        return flow

    def start(self, start: FiberStart, rng: np.random.Generator) -> FiberStart:
        for e in self.effects:
            start = e.transform_start(start, rng)
        return start

    def result(self, result: RunResult, start: FiberStart, geometry: Geometry) -> RunResult:
        """The effects' report hooks, last effect first (``geometry``: the run's channel)."""
        for e in reversed(self.effects):
            result = e.transform_result(result, start, geometry)
        return result

    def kernel(self, ctx: DynamicsContext) -> tuple:
        """The kernel records of the effects that act in the integrators, sorted by name.

        The order is canonical, so one set of effects always gives one tuple type
        (one compiled specialisation of each integrator).
        """
        recs = ((e.name, e.kernel(ctx)) for e in self.effects)
        return tuple(r for _, r in sorted(recs, key=lambda nr: nr[0]) if r is not None)

    @property
    def random(self) -> bool:
        """Whether a kernel stage draws from Numba's random generator."""
        return any(e.random for e in self.effects)

    def check_model(self, model: str) -> None:
        """InputError naming the first effect that does not work in ``model``."""
        for e in self.effects:
            if model not in e.models:
                raise InputError(
                    f"effects.{e.name}: not available in the {model} model "
                    f"(only {', '.join(e.models)})"
                )


def build_effects(spec: Mapping[str, float] | None) -> EffectSet:
    """Validate ``FiberSettings.effects`` (name -> value) into an :class:`EffectSet`.

    Raises
    ------
    InputError
        Unknown name (listing the valid ones) or a value out of range.
    """
    made = []
    for name, value in (spec or {}).items():
        cls = get_effect(name)
        eff = cls(float(value))
        if eff.active:
            made.append(eff)
    return EffectSet(tuple(made))
