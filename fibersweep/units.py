"""Physical scales and lattice conversion (the channel's geometry: :mod:`fibersweep.geometry`).

Unit system used everywhere below the CLI
-----------------------------------------
length: micrometre (µm); time: second (s); force: piconewton (pN).
In this system a viscosity in Pa·s has the same numerical value in
pN·s/µm² (1 Pa·s = 1 N·s/m² = 1e12 pN·s / 1e12 µm²), so the model's numbers
are used as they stand: μ = 0.340, U_center = 600 µm/s, a = 2 µm,
E = 26e6 Pa = 26 pN/µm².
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fibersweep.geometry.channel import Geometry  # re-exported: many callers import it here

__all__ = ["Fluid", "Geometry", "LatticeScale"]


@dataclass(frozen=True)
class Fluid:
    """Fluid properties and the flow speed scale.

    Parameters
    ----------
    viscosity : float
        Dynamic viscosity μ [Pa·s == pN·s/µm²].
    density : float
        Density ρ [kg/m³] (only used for the Reynolds number).
    u_center : float
        Midplane centreline speed far from the pillar [µm/s].
    """

    viscosity: float = 0.340
    density: float = 1190.0
    u_center: float = 600.0

    def reynolds(self, length_um: float) -> float:
        """Reynolds number ρ U ℓ / μ for a length ``length_um`` [µm]."""
        return self.density * (self.u_center * 1e-6) * (length_um * 1e-6) / self.viscosity


@dataclass(frozen=True)
class LatticeScale:
    """Conversion between lattice and physical units for a Stokes solution.

    The lattice velocity field is rescaled after solving (Stokes flow is linear
    in the forcing), so only lengths and the velocity scale are needed.

    Parameters
    ----------
    dx : float
        Lattice spacing [µm].
    velocity_scale : float
        Physical velocity [µm/s] per lattice velocity unit.
    """

    dx: float
    velocity_scale: float = field(default=1.0)

    def nodes(self, length_um: float) -> int:
        """Number of lattice nodes spanning ``length_um`` (half-way walls)."""
        return int(round(length_um / self.dx))

    def to_physical_velocity(self, u_lattice: np.ndarray) -> np.ndarray:
        """Lattice velocity to µm/s."""
        return np.asarray(u_lattice) * self.velocity_scale
