"""``off_midplane``: fiber centred at z = H/2 + Δz (value = Δz / H_ch).

The field is the midplane velocity, already z-averaged with the IB kernel.
Far from the side walls the duct profile is the Hele-Shaw parabola
p(ζ) = 1 − 4ζ²/H² (ζ = z − H/2); its average over a kernel of second moment
σ² (σ² = (4/3 − 8/π²) Δx² for the 4-point cosine kernel) is
1 − 4(ζ² + σ²)/H². Every background velocity is scaled by the ratio of that
average at ζ = Δz to the one at ζ = 0. The bead must stay inside the channel:
|Δz| < H/2 − a.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from fibersweep.errors import InputError
from fibersweep.fiber.effects.base import DynamicsContext, Effect
from fibersweep.fiber.effects.registry import register
from fibersweep.fiber.kernel.hooks import implements

KERNEL_SECOND_MOMENT = 4.0 / 3.0 - 8.0 / math.pi**2  # in Δx², of φ(r) = ¼(1 + cos(πr/2))


class OffMidplaneKernel(NamedTuple):
    """Kernel record: factor on every bead's background velocity [-]."""

    scale: float


def layer_factor(dz_over_h: float, dx: float, depth: float) -> float:
    """Velocity of the layer at Δz relative to the midplane (kernel-averaged parabola)."""
    s2 = KERNEL_SECOND_MOMENT * (dx / depth) ** 2
    return (1.0 - 4.0 * (dz_over_h**2 + s2)) / (1.0 - 4.0 * s2)


@register
@dataclass(frozen=True)
class OffMidplane(Effect):
    name = "off_midplane"
    unit = "offset of the fiber from the midplane / channel depth"

    def validate(self) -> None:
        self._require(abs(self.value) < 0.5, "|value| must be < 0.5")

    def kernel(self, ctx: DynamicsContext) -> OffMidplaneKernel:
        if abs(self.value) * ctx.depth >= 0.5 * ctx.depth - ctx.bead_radius:
            raise InputError(
                f"effects.off_midplane: {self.value} puts the bead (radius "
                f"{ctx.bead_radius} µm) through a wall of the {ctx.depth} µm channel"
            )
        return OffMidplaneKernel(layer_factor(self.value, ctx.dx, ctx.depth))


@implements("background", OffMidplaneKernel)
def background(e, w, u):
    """Both models: scale the interpolated midplane velocities to the fiber's layer."""
    for i in range(u.shape[0]):
        u[i, 0] *= e.scale
        u[i, 1] *= e.scale
