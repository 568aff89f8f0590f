"""``friction``: Coulomb friction on the pillar surface (value = coefficient μ_f ≥ 0).

Each fiber bead in contact gets, besides its repulsion F_n, a tangential force
F_t with |F_t| ≤ μ_f |F_n| that opposes its tangential motion and at most stops
it (stick) — never reverses it. Rigid model: the tangential forces of all
contacting beads are solved together (projected Gauss-Seidel on the rigid-body
mobility, normal forces fixed). Bead-spring model: the same solve for the rigid
body the (nearly rigid) fiber moves as, body axis from tail to head. Works on
both pillars; on the rough pillar it adds to the roughness the discrete pillar
beads already give. The source's trapping example needs μ_f ≈ 0.3 at dx = 4 µm.
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
