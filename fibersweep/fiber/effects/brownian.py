"""``brownian``: thermal noise (value = multiplier on k_B·295 K; 1 = room temperature).

Translational and rotational noise from the rigid body mobility N (lab frame),
Euler–Maruyama: Δq += sqrt(2 kT Δt) · chol(N) ξ, ξ ~ N(0, I₃), seeded by
``simulate(rng_seed=...)``. No drift correction is needed: without walls the
divergence of N(θ) vanishes. In the bead-spring model each bead gets
sqrt(2 kT Δt) · chol(M) ξ. The glycerol-ethanol viscosity makes the effect tiny
(D_rot ~ 1e-4 rad²/s for L = l_obs), which is why the baseline omits it.
"""

from __future__ import annotations

from dataclasses import dataclass

from fibersweep.fiber.effects.base import DynamicsContext, DynamicsParams, Effect
from fibersweep.fiber.effects.registry import register

BOLTZMANN_PN_UM = 1.380649e-5  # k_B in pN·µm/K (1.380649e-23 J/K)
ROOM_TEMPERATURE = 295.0  # K


@register
@dataclass(frozen=True)
class Brownian(Effect):
    name = "brownian"
    unit = "multiplier on kT at 295 K, >= 0"

    def validate(self) -> None:
        self._require(self.value >= 0.0, "must be >= 0")

    def dynamics(self, params: DynamicsParams, ctx: DynamicsContext) -> DynamicsParams:
        return params.with_(kT=self.value * BOLTZMANN_PN_UM * ROOM_TEMPERATURE)
