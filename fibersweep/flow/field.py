"""FlowField: the steady midplane velocity a fiber feels, with IB interpolation.

Grid convention (half-way bounce-back): node (i, j) sits at
x_i = (i + 1/2) Δx, y_j = (j + 1/2) Δx, i = 0..nx-1 (periodic in x, nx Δx = L_ch),
j = 0..ny-1 (walls at y = 0 and y = ny Δx = W_ch). Nodes outside 0..ny-1 in y
carry zero velocity (no-slip walls).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numba as nb
import numpy as np

from fibersweep.geometry import Geometry
from fibersweep.units import Fluid

__all__ = ["FlowField", "interpolate_ib", "ib_phi"]


@nb.njit(cache=True, inline="always")
def ib_phi(r: float) -> float:
    """1D cosine IB kernel φ(r) for r in lattice units (support |r| ≤ 2).

    φ(r) = ¼ (1 + cos(π r / 2)); the 4-point stencil sums to exactly 1.
    """
    ar = abs(r)
    if ar >= 2.0:
        return 0.0
    return 0.25 * (1.0 + math.cos(0.5 * math.pi * ar))


@nb.njit(cache=True)
def interpolate_ib(
    ux: np.ndarray,
    uy: np.ndarray,
    dx: float,
    px: np.ndarray,
    py: np.ndarray,
    out: np.ndarray,
) -> None:
    """Interpolate (ux, uy) at points with the 4-point cosine kernel (2D, z pre-averaged).

    Parameters
    ----------
    ux, uy : ndarray, shape (nx, ny)
        Node velocities [any unit]; x periodic, zero outside 0..ny-1 in y.
    dx : float
        Node spacing [µm].
    px, py : ndarray, shape (n,)
        Point coordinates [µm].
    out : ndarray, shape (n, 2)
        Written with the interpolated velocities.
    """
    nx, ny = ux.shape
    inv = 1.0 / dx
    for p in range(px.shape[0]):
        gx = px[p] * inv - 0.5
        gy = py[p] * inv - 0.5
        i0 = int(math.floor(gx)) - 1
        j0 = int(math.floor(gy)) - 1
        sx = 0.0
        sy = 0.0
        for a in range(4):
            i = i0 + a
            wx = ib_phi(gx - i)
            if wx == 0.0:
                continue
            ii = i % nx
            for b in range(4):
                j = j0 + b
                if j < 0 or j >= ny:
                    continue
                w = wx * ib_phi(gy - j)
                sx += w * ux[ii, j]
                sy += w * uy[ii, j]
        out[p, 0] = sx
        out[p, 1] = sy


@dataclass(frozen=True)
class FlowField:
    """Steady in-plane velocity on the midplane, already z-averaged with the IB kernel.

    Attributes
    ----------
    ux, uy : ndarray, shape (nx, ny), float64
        Velocity components [µm/s] at the nodes (i + 1/2, j + 1/2) Δx.
    dx : float
        Node spacing Δx [µm].
    geometry : Geometry
        Channel and pillar the field was computed for.
    fluid : Fluid
        Fluid properties; ``fluid.u_center`` is the scale the field was set to.
    solid : ndarray, shape (nx, ny), bool
        True on pillar nodes (velocity is zero there).
    meta : Mapping
        Solver settings, convergence record, version and cache key.
    u3d : ndarray or None
        Optional full field, shape (3, nz, ny, nx) [µm/s] (z from the bottom wall).
    """

    ux: np.ndarray
    uy: np.ndarray
    dx: float
    geometry: Geometry
    fluid: Fluid
    solid: np.ndarray
    meta: Mapping = field(default_factory=dict)
    u3d: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.ux.shape != self.uy.shape or self.ux.ndim != 2:
            raise ValueError(
                f"ux and uy must be equal 2D arrays, got {self.ux.shape}, {self.uy.shape}"
            )
        if self.solid.shape != self.ux.shape:
            raise ValueError("solid mask must have the shape of ux")

    @property
    def shape(self) -> tuple[int, int]:
        """(nx, ny) node counts."""
        return self.ux.shape  # type: ignore[return-value]

    @property
    def x_nodes(self) -> np.ndarray:
        """Node x coordinates [µm], shape (nx,)."""
        return (np.arange(self.shape[0]) + 0.5) * self.dx

    @property
    def y_nodes(self) -> np.ndarray:
        """Node y coordinates [µm], shape (ny,)."""
        return (np.arange(self.shape[1]) + 0.5) * self.dx

    def velocity(self, points: np.ndarray) -> np.ndarray:
        """Background velocity at points with the IB kernel.

        Parameters
        ----------
        points : ndarray, shape (n, 2)
            (x, y) [µm].

        Returns
        -------
        ndarray, shape (n, 2)
            (ux, uy) [µm/s].
        """
        pts = np.ascontiguousarray(points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 2:
            raise ValueError(f"points must have shape (n, 2), got {pts.shape}")
        out = np.empty_like(pts)
        interpolate_ib(
            np.ascontiguousarray(self.ux, dtype=np.float64),
            np.ascontiguousarray(self.uy, dtype=np.float64),
            float(self.dx),
            np.ascontiguousarray(pts[:, 0]),
            np.ascontiguousarray(pts[:, 1]),
            out,
        )
        return out

    def scaled(self, factor: float) -> FlowField:
        """The same field times ``factor`` (Stokes flow is linear in the forcing)."""
        return FlowField(
            ux=self.ux * factor,
            uy=self.uy * factor,
            dx=self.dx,
            geometry=self.geometry,
            fluid=Fluid(self.fluid.viscosity, self.fluid.density, self.fluid.u_center * factor),
            solid=self.solid,
            meta={**dict(self.meta), "scaled_by": factor},
            u3d=None if self.u3d is None else self.u3d * factor,
        )

    def reversed(self) -> FlowField:
        """The field with the flow reversed (Stokes flow: u → −u)."""
        return self.scaled(-1.0)

    @classmethod
    def from_function(
        cls,
        fn: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]],
        geometry: Geometry,
        dx: float,
        fluid: Fluid | None = None,
        with_pillar: bool = False,
        meta: Mapping | None = None,
    ) -> FlowField:
        """Sample an analytic field on the grid (for tests and idealised studies).

        Parameters
        ----------
        fn : callable
            ``fn(X, Y) -> (UX, UY)`` with X, Y of shape (nx, ny) [µm], returning µm/s.
        geometry : Geometry
            Channel (and pillar, if ``with_pillar``).
        dx : float
            Node spacing [µm].
        with_pillar : bool
            If True, zero the velocity on nodes inside the pillar.
        """
        nx = int(round(geometry.length / dx))
        ny = int(round(geometry.width / dx))
        x = (np.arange(nx) + 0.5) * dx
        y = (np.arange(ny) + 0.5) * dx
        X, Y = np.meshgrid(x, y, indexing="ij")
        ux, uy = fn(X, Y)
        ux = np.array(np.broadcast_to(ux, X.shape), dtype=np.float64)
        uy = np.array(np.broadcast_to(uy, X.shape), dtype=np.float64)
        solid = geometry.inside_pillar(X, Y) if with_pillar else np.zeros(X.shape, dtype=bool)
        ux[solid] = 0.0
        uy[solid] = 0.0
        return cls(
            ux=ux,
            uy=uy,
            dx=float(dx),
            geometry=geometry,
            fluid=fluid or Fluid(),
            solid=solid,
            meta=dict(meta or {"source": "analytic"}),
        )
