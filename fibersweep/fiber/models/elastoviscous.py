"""The elasto-viscous number of a bead-spring fiber in the pillar flow.

μ̄ = 8π μ γ̇ L⁴ / (B c) compares the viscous forces on a fiber of length L with its
bending forces: B = E π a⁴ / 4 is the bending stiffness of a rod of radius a (the
bead-spring model's, :mod:`fibersweep.fiber.models.rod`), c = −ln(ε² e) with
ε = a / L the logarithm of the slender-body drag 8πμ / c, and γ̇ a shear rate of
the flow. A filament in simple shear buckles above μ̄ = 306.4 (Becker & Shelley
2001); in a planar compressional flow along it, above 153.2 (Young & Shelley 2007;
``tests/validation/test_fiber_flexible.py`` checks the bead chain's threshold).

The shear rate of the pillar flow is taken as U_center / h: the centreline speed
far from the pillar over the pillar's size (h_obs for the single pillar,
``flow.array.pillar_size`` for an array), the length over which the flow turns
round a pillar. μ̄ is not a setting: it follows from E, L, a and the flow.
"""

from __future__ import annotations

import math

from fibersweep.config.flow import FlowSettings
from fibersweep.fiber.models.rod import rod

__all__ = ["bending_stiffness", "elastoviscous_number", "pillar_shear_rate"]


def bending_stiffness(young_modulus: float, bead_radius_um: float) -> float:
    """B = E π a⁴ / 4 [N m²] of a fiber of Young's modulus E [Pa] and radius a [µm]."""
    return rod(young_modulus, bead_radius_um * 1e-6).bend


def elastoviscous_number(
    viscosity: float,
    shear_rate: float,
    length_um: float,
    young_modulus: float,
    bead_radius_um: float,
) -> float:
    """μ̄ = 8π μ γ̇ L⁴ / (B c), dimensionless.

    Parameters
    ----------
    viscosity : float
        Dynamic viscosity μ [Pa s].
    shear_rate : float
        Shear rate γ̇ [1/s].
    length_um : float
        Fiber length L [µm].
    young_modulus : float
        E [Pa].
    bead_radius_um : float
        Fiber radius a [µm] (the bead radius).
    """
    if not length_um > 2.0 * bead_radius_um:
        raise ValueError(f"length {length_um} µm must exceed the fiber's diameter")
    eps = bead_radius_um / length_um
    c = -math.log(eps**2 * math.e)
    length = length_um * 1e-6
    b = bending_stiffness(young_modulus, bead_radius_um)
    return 8.0 * math.pi * viscosity * shear_rate * length**4 / (b * c)


def pillar_shear_rate(flow: FlowSettings) -> float:
    """γ̇ = U_center / h [1/s] of a config's flow (h: the pillar's size)."""
    size = flow.array.pillar_size if flow.array is not None else flow.geometry.pillar_height
    return flow.fluid.u_center / size
