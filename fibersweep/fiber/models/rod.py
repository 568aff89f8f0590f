"""The elastic rod the bead chain models: its stretching and bending stiffnesses, written once.

A cylinder of Young's modulus E and radius a has the stretching stiffness
EA = E π a² and the bending stiffness EI = E π a⁴ / 4. The bead-spring model's
springs (:mod:`fibersweep.fiber.models.elastic`, through
:func:`fibersweep.fiber.kernel.bundles.make_params`), its tension observable
(:mod:`fibersweep.fiber.models.deformation`) and the elasto-viscous number
(:mod:`fibersweep.fiber.models.elastoviscous`) all read them from
:func:`rod`, so the three agree by construction.

The expressions are evaluated exactly as written, ``E * pi * a**2`` and
``E * pi * a**4 / 4``, left to right: the kernels' constants are bit for bit
those of every run made before this module existed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Rod", "rod"]


@dataclass(frozen=True)
class Rod:
    """Stiffnesses of a uniform elastic cylinder.

    Attributes
    ----------
    stretch : float
        EA = E π a² (the model's S): [pN] for E [Pa = pN/µm²] and a [µm];
        [N] for a in [m].
    bend : float
        EI = E π a⁴ / 4 (the model's B): [pN µm²] for a [µm]; [N m²] for a in [m].
    """

    stretch: float
    bend: float


def rod(young_modulus: float, radius: float) -> Rod:
    """EA and EI of a cylinder of Young's modulus E [Pa] and radius a (units: see :class:`Rod`).

    Parameters
    ----------
    young_modulus : float
        E [Pa] (= pN/µm² = N/m²).
    radius : float
        a, the fiber's radius (the bead radius) [µm], or [m] for SI stiffnesses.
    """
    return Rod(
        stretch=young_modulus * math.pi * radius**2,
        bend=young_modulus * math.pi * radius**4 / 4.0,
    )
