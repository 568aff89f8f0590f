"""``brownian``: thermal noise (value = multiplier on k_B·295 K; 1 = room temperature).

Translational and rotational noise from the rigid body mobility N (lab frame),
Euler–Maruyama: Δq += sqrt(2 kT Δt) · chol(N) ξ, ξ ~ N(0, I₃), seeded by
``simulate(rng_seed=...)``. No drift correction is needed: without walls the
divergence of N(θ) vanishes. Rigid model only (the bead-spring model names
the effect in an InputError). The glycerol-ethanol viscosity makes the effect tiny
(D_rot ~ 1e-4 rad²/s for L = l_obs), which is why the baseline omits it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from fibersweep.fiber.effects.base import DynamicsContext, Effect
from fibersweep.fiber.effects.registry import register
from fibersweep.fiber.kernel.hooks import implements

BOLTZMANN_PN_UM = 1.380649e-5  # k_B in pN·µm/K (1.380649e-23 J/K)
ROOM_TEMPERATURE = 295.0  # K


class BrownianKernel(NamedTuple):
    """Kernel record: thermal energy kT [pN·µm]."""

    kT: float


@register
@dataclass(frozen=True)
class Brownian(Effect):
    name = "brownian"
    unit = "multiplier on kT at 295 K, >= 0"
    models = ("rigid",)
    random = True

    def validate(self) -> None:
        self._require(self.value >= 0.0, "must be >= 0")

    def kernel(self, ctx: DynamicsContext) -> BrownianKernel:
        return BrownianKernel(self.value * BOLTZMANN_PN_UM * ROOM_TEMPERATURE)


@implements("rigid_noise", BrownianKernel)
def rigid_noise(e, body, dt, c, sn, xc, yc, th):
    """Rigid model: Δq = sqrt(2 kT Δt) chol(N) ξ in the body frame (c, sn: the step's angle)."""
    chol = body.chol
    amp = math.sqrt(2.0 * e.kT * dt)
    g0 = np.random.standard_normal()  # noqa: NPY002 - Numba RNG
    g1 = np.random.standard_normal()  # noqa: NPY002 - Numba RNG
    g2 = np.random.standard_normal()  # noqa: NPY002 - Numba RNG
    q0 = amp * (chol[0, 0] * g0)
    q1 = amp * (chol[1, 0] * g0 + chol[1, 1] * g1)
    q2 = amp * (chol[2, 0] * g0 + chol[2, 1] * g1 + chol[2, 2] * g2)
    return xc + (c * q0 - sn * q1), yc + (sn * q0 + c * q1), th + q2
