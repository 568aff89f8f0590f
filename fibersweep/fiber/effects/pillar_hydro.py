"""``pillar_hydro``: hydrodynamic slow-down near the pillar (value = s in [0, 1)).

The baseline neglects fiber-pillar hydrodynamic interactions. This effect
models them as a per-bead factor on the background velocity,
f(h) = 1 − s·exp(−h/a), with h ≥ 0 the gap between the bead surface and the
pillar outline and a the bead radius (the decay length). A bead touching the
pillar moves a fraction s slower; since only the beads near the pillar slow
down, the fiber also turns a little more. The source estimated ~10 % near
contact: s = 0.1.
"""

from __future__ import annotations

from dataclasses import dataclass

from fibersweep.fiber.effects.base import DynamicsContext, DynamicsParams, Effect
from fibersweep.fiber.effects.registry import register


@register
@dataclass(frozen=True)
class PillarHydro(Effect):
    name = "pillar_hydro"
    unit = "fractional slow-down of a bead touching the pillar, in [0, 1)"

    def validate(self) -> None:
        self._require(0.0 <= self.value < 1.0, "must be in [0, 1)")

    def dynamics(self, params: DynamicsParams, ctx: DynamicsContext) -> DynamicsParams:
        return params.with_(hydro_strength=self.value, hydro_length=ctx.bead_radius)
