"""``pillar_hydro``: hydrodynamic drag of the pillar on the fiber (value = k >= 0; 1 = Faxén).

The baseline neglects fiber-pillar hydrodynamic interactions (the fiber only
slows because the interpolated flow vanishes at the pillar). This effect adds
the leading-order wall drag on each bead relative to its local fluid,
ζ = k · 6πμa · β/(1 − β) · exp(−(h − a)/H_ch), β = (9/16) a/h, h the bead
centre's distance to the pillar outline: the first-reflection (Faxén) drag
increase of a sphere beside a plane wall, screened beyond the channel depth.
k = 1 is that estimate. See :mod:`fibersweep.fiber.hydro.first_reflection` for the exact
rigid-body and bead-spring forms. The source estimated that fiber-pillar
interactions slow the fiber by about 10 % near contact and turn it a little
more.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from fibersweep.fiber.effects.base import DynamicsContext, Effect
from fibersweep.fiber.effects.registry import register
from fibersweep.fiber.hydro.first_reflection import (
    mobility_with_wall_drag,
    rigid_wall_velocity,
    wall_drag,
)
from fibersweep.fiber.kernel.hooks import implements

__all__ = ["PillarHydro", "PillarHydroKernel"]


class PillarHydroKernel(NamedTuple):
    """Kernel record: multiplier k on the Faxén drag [-], its screening length [µm],
    the bead radius a [µm], the viscosity μ [pN·s/µm²], and scratch: the beads'
    drag coefficients ζ (n,) [pN s/µm] and the modified body mobility N' (3, 3)."""

    strength: float
    length: float
    a: float
    mu: float
    zeta: np.ndarray
    nm_eff: np.ndarray


@register
@dataclass(frozen=True)
class PillarHydro(Effect):
    name = "pillar_hydro"
    unit = "multiplier k >= 0 on the Faxén drag of a bead beside the pillar (1 = the estimate)"

    def validate(self) -> None:
        self._require(0.0 <= self.value <= 20.0, "must be in [0, 20]")

    def kernel(self, ctx: DynamicsContext) -> PillarHydroKernel:
        return PillarHydroKernel(
            float(self.value),
            float(ctx.depth),
            float(ctx.bead_radius),
            float(ctx.viscosity),
            np.zeros(ctx.n_beads),
            np.zeros((3, 3)),
        )


@implements("rigid_mobility", PillarHydroKernel)
def rigid_mobility(e, body, w, c, sn, vbx, vby, om, nm_eff):
    """Rigid model: V = A⁻¹ V₀ and N' = A⁻¹ N
    (see :mod:`fibersweep.fiber.hydro.first_reflection`)."""
    if wall_drag(w.dist, e.a, e.strength, e.length, e.mu, e.zeta) > 0:
        vbx, vby, om = rigid_wall_velocity(body.s, nm_eff, e.zeta, vbx, vby, om, e.nm_eff)
        return vbx, vby, om, e.nm_eff
    return vbx, vby, om, nm_eff


@implements("bead_mobility", PillarHydroKernel)
def bead_mobility(e, w, bw):
    """Bead-spring model: M -> (M⁻¹ + Z)⁻¹ and u -> (I + M Z)⁻¹ u (Woodbury)."""
    if wall_drag(w.dist, e.a, e.strength, e.length, e.mu, e.zeta) > 0:
        mobility_with_wall_drag(bw.mob, e.zeta, bw.f)
