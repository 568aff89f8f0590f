"""From the 3D lattice field to what a midplane fiber feels: IB z-average, centreline speed."""

from __future__ import annotations

import math

import numpy as np

from fibersweep.flow.field import ib_phi
from fibersweep.flow.lattice import Grid

__all__ = ["midplane_weights", "midplane_average", "midplane_centre_speed", "full_depth"]


def midplane_weights(grid: Grid) -> list[tuple[int, float]]:
    """(solved z index, IB weight) pairs that average a field at z = H/2.

    Full-depth nodes sit at (k + 1/2) Δx; a node mirrored across the midplane
    (symmetric solve) maps to its image nz_full − 1 − k.
    """
    mid = grid.nz_full / 2.0
    acc: dict[int, float] = {}
    for k in range(grid.nz_full):
        w = ib_phi(k + 0.5 - mid)
        if w == 0.0:
            continue
        ks = k if k < grid.nz else grid.nz_full - 1 - k
        acc[ks] = acc.get(ks, 0.0) + w
    return sorted(acc.items())


def midplane_average(u: np.ndarray, grid: Grid) -> np.ndarray:
    """IB-kernel z-average of the in-plane velocity at z = H/2.

    Parameters
    ----------
    u : ndarray, shape (3, nz, ny, nx)

    Returns
    -------
    ndarray, shape (2, nx, ny)
        (ux, uy) averaged, x-major like FlowField.
    """
    out = np.zeros((2, grid.ny, grid.nx))
    for k, w in midplane_weights(grid):
        out += w * u[0:2, k]
    return out.transpose(0, 2, 1).copy()


def _bilinear_periodic_x(plane: np.ndarray, gx: float, gy: float) -> float:
    """Value of plane (nx, ny) at lattice coordinates (gx, gy) (node i at gx = i)."""
    nx, ny = plane.shape
    i0 = math.floor(gx)
    j0 = min(max(math.floor(gy), 0), ny - 2)
    tx = gx - i0
    ty = gy - j0
    i0 %= nx
    i1 = (i0 + 1) % nx
    return float(
        (1 - tx) * (1 - ty) * plane[i0, j0]
        + tx * (1 - ty) * plane[i1, j0]
        + (1 - tx) * ty * plane[i0, j0 + 1]
        + tx * ty * plane[i1, j0 + 1]
    )


def midplane_centre_speed(u: np.ndarray, grid: Grid, x_far: float, y_mid: float) -> float:
    """ux at (x_far, y_mid, H/2) [positions in µm], from the symmetric z-profile.

    With a node on the midplane it is used directly; otherwise the parabola
    u = a − b ζ² through the nodes at ζ = 1/2 and 3/2 from the midplane gives
    a = (9 u(1/2) − u(3/2)) / 8.
    """
    gx = x_far / grid.dx - 0.5
    gy = y_mid / grid.dx - 0.5
    if grid.nz_full % 2:
        k = grid.nz_full // 2
        return _bilinear_periodic_x(u[0, k].T, gx, gy)
    k1 = grid.nz_full // 2 - 1  # ζ = 1/2, exists in both solves
    k2 = k1 - 1  # ζ = 3/2
    u1 = _bilinear_periodic_x(u[0, k1].T, gx, gy)
    u2 = _bilinear_periodic_x(u[0, k2].T, gx, gy)
    return (9.0 * u1 - u2) / 8.0


def full_depth(u: np.ndarray, grid: Grid) -> np.ndarray:
    """The (3, nz_full, ny, nx) field: the solved half plus its mirror image if symmetric."""
    if not grid.symmetry:
        return u.copy()
    mirror = u[:, ::-1].copy()
    mirror[2] *= -1.0  # u_z is odd across the midplane
    return np.concatenate([u, mirror], axis=1)
