"""``friction``: Coulomb friction on the pillar surface (value = coefficient μ_f ≥ 0).

Each fiber bead in contact gets, besides its repulsion F_n, a tangential force
opposing its tangential velocity, of magnitude min(μ_f |F_n|, the force that
stops the tangential motion of that bead) — so strong friction sticks instead
of reversing the motion. Works on both pillars; on the rough pillar it adds to
the roughness the discrete pillar beads already give.
"""

from __future__ import annotations

from dataclasses import dataclass

from fibersweep.fiber.effects.base import DynamicsContext, DynamicsParams, Effect
from fibersweep.fiber.effects.registry import register


@register
@dataclass(frozen=True)
class Friction(Effect):
    name = "friction"
    unit = "friction coefficient tangential/normal force, >= 0"

    def validate(self) -> None:
        self._require(self.value >= 0.0, "must be >= 0")

    def dynamics(self, params: DynamicsParams, ctx: DynamicsContext) -> DynamicsParams:
        return params.with_(friction=self.value)
