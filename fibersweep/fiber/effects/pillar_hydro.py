"""``pillar_hydro``: hydrodynamic drag of the pillar on the fiber (value = k >= 0; 1 = Faxén).

The baseline neglects fiber-pillar hydrodynamic interactions (the fiber only
slows because the interpolated flow vanishes at the pillar). This effect adds
the leading-order wall drag on each bead relative to its local fluid,
ζ = k · 6πμa · β/(1 − β) · exp(−(h − a)/H_ch), β = (9/16) a/h, h the bead
centre's distance to the pillar outline: the first-reflection (Faxén) drag
increase of a sphere beside a plane wall, screened beyond the channel depth.
k = 1 is that estimate. See :mod:`fibersweep.fiber.wallhydro` for the exact
rigid-body and bead-spring forms. The source estimated that fiber-pillar
interactions slow the fiber by about 10 % near contact and turn it a little
more.
"""

from __future__ import annotations

from dataclasses import dataclass

from fibersweep.fiber.effects.base import DynamicsContext, DynamicsParams, Effect
from fibersweep.fiber.effects.registry import register


@register
@dataclass(frozen=True)
class PillarHydro(Effect):
    name = "pillar_hydro"
    unit = "multiplier k >= 0 on the Faxén drag of a bead beside the pillar (1 = the estimate)"

    def validate(self) -> None:
        self._require(0.0 <= self.value <= 20.0, "must be in [0, 20]")

    def dynamics(self, params: DynamicsParams, ctx: DynamicsContext) -> DynamicsParams:
        return params.with_(hydro_strength=self.value, hydro_length=ctx.depth)
