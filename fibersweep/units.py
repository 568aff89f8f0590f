"""Physical scales, the pillar geometry and lattice conversion.

Unit system used everywhere below the CLI
-----------------------------------------
length: micrometre (µm); time: second (s); force: piconewton (pN).
In this system a viscosity in Pa·s has the same numerical value in
pN·s/µm² (1 Pa·s = 1 N·s/m² = 1e12 pN·s / 1e12 µm²), so the model's numbers
are used as they stand: μ = 0.340, U_center = 600 µm/s, a = 2 µm,
E = 26e6 Pa = 26 pN/µm².
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

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
class Geometry:
    """Channel and equilateral triangular pillar, all lengths in µm.

    The channel spans x ∈ [0, length) (periodic), y ∈ [0, width], z ∈ [0, depth].
    The pillar's base is parallel to x, its apex points to +y, and it spans
    the full depth.

    Parameters
    ----------
    width, depth, length : float
        Channel width W_ch (y), depth H_ch (z) and periodic length L_ch (x) [µm].
    pillar_height : float
        Height h_obs of the triangle, base to apex [µm].
    pillar_x : float or None
        x of the base centre [µm]; None means L_ch / 2.
    pillar_y_base : float or None
        y of the base line [µm]; None means the model's decision: centroid on the
        centreline, y_base = W_ch/2 − h_obs/3.
    """

    width: float = 800.0
    depth: float = 40.0
    length: float = 2400.0
    pillar_height: float = 75.0
    pillar_x: float | None = None
    pillar_y_base: float | None = None

    @property
    def pillar_base_length(self) -> float:
        """Side of the equilateral triangle l_obs = 2 h_obs / √3 [µm]."""
        return 2.0 * self.pillar_height / math.sqrt(3.0)

    @property
    def base_center(self) -> tuple[float, float]:
        """(x, y) of the centre of the base [µm]."""
        x = self.length / 2.0 if self.pillar_x is None else self.pillar_x
        yb = (
            self.width / 2.0 - self.pillar_height / 3.0
            if self.pillar_y_base is None
            else self.pillar_y_base
        )
        return float(x), float(yb)

    @property
    def vertices(self) -> np.ndarray:
        """Triangle vertices, shape (3, 2) [µm]: base-left, base-right, apex (CCW)."""
        xc, yb = self.base_center
        half = self.pillar_base_length / 2.0
        return np.array(
            [[xc - half, yb], [xc + half, yb], [xc, yb + self.pillar_height]], dtype=np.float64
        )

    @property
    def centroid(self) -> tuple[float, float]:
        """(x, y) of the pillar centroid [µm]."""
        xc, yb = self.base_center
        return xc, yb + self.pillar_height / 3.0

    @property
    def x_far(self) -> float:
        """x [µm] farthest from the pillar along the periodic channel (half a period away)."""
        return (self.base_center[0] + self.length / 2.0) % self.length

    def y_from_base(self, y_over_h: float) -> float:
        """Absolute y [µm] of a lateral position quoted as y/h_obs from the base line."""
        return self.base_center[1] + y_over_h * self.pillar_height

    def y_over_h(self, y: np.ndarray | float) -> np.ndarray | float:
        """Lateral position(s) y [µm] quoted as y/h_obs from the base line."""
        return (np.asarray(y) - self.base_center[1]) / self.pillar_height

    def inside_pillar(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Boolean mask of points strictly inside the triangle.

        Parameters
        ----------
        x, y : ndarray
            Coordinates [µm], any broadcastable shapes.
        """
        v = self.vertices
        inside = np.ones(np.broadcast(x, y).shape, dtype=bool)
        for k in range(3):
            ax, ay = v[k]
            bx, by = v[(k + 1) % 3]
            # CCW vertices: interior is on the left of every edge.
            cross = (bx - ax) * (y - ay) - (by - ay) * (x - ax)
            inside &= cross > 0.0
        return inside

    def fits(self) -> bool:
        """True if the pillar lies strictly inside the channel."""
        v = self.vertices
        return bool(
            v[:, 0].min() > 0.0
            and v[:, 0].max() < self.length
            and v[:, 1].min() > 0.0
            and v[:, 1].max() < self.width
        )


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
