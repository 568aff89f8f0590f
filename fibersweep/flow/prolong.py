"""Initial guess for a fine lattice from a solution on a twice coarser one.

Trilinear interpolation of velocity and density deviation, with ghost nodes that
keep the boundary conditions: antisymmetric across no-slip walls (the value
interpolates to zero on the half-way wall), symmetric in-plane and antisymmetric
for u_z across the free-slip midplane, periodic in x.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import map_coordinates

from fibersweep.flow.lattice import Grid

__all__ = ["prolong"]


def _pad(a: np.ndarray, sign_y: float, sign_z_bottom: float, sign_z_top: float) -> np.ndarray:
    """Pad (nz, ny, nx) with one ghost layer: scaled mirror in z, y; periodic in x."""
    a = np.concatenate([a[:, :, -1:], a, a[:, :, :1]], axis=2)
    a = np.concatenate([sign_y * a[:, :1], a, sign_y * a[:, -1:]], axis=1)
    return np.concatenate([sign_z_bottom * a[:1], a, sign_z_top * a[-1:]], axis=0)


def _coords(n_fine: int, ratio: float) -> np.ndarray:
    """Coarse padded index of each fine node centre (ghost layer at index 0)."""
    return (np.arange(n_fine) + 0.5) / ratio - 0.5 + 1.0


def prolong(
    u: np.ndarray, rho: np.ndarray, coarse: Grid, fine: Grid, density_scale: float
) -> tuple[np.ndarray, np.ndarray]:
    """Interpolate a coarse lattice solution onto a fine grid of the same channel.

    Parameters
    ----------
    u : ndarray, shape (3, nz_c, ny_c, nx_c)
        Coarse lattice velocity.
    rho : ndarray, shape (nz_c, ny_c, nx_c)
        Coarse density deviation δρ.
    coarse, fine : Grid
        The two grids (same geometry and symmetry).
    density_scale : float
        Factor on δρ (pressure differences scale with force x nodes).

    Returns
    -------
    u_f : ndarray, shape (3, nz_f, ny_f, nx_f)
        Zero on the fine pillar nodes.
    rho_f : ndarray, shape (nz_f, ny_f, nx_f)
        Mean-free δρ.
    """
    ratio = coarse.dx / fine.dx
    zc = _coords(fine.nz, ratio)
    yc = _coords(fine.ny, ratio)
    xc = _coords(fine.nx, ratio)
    Z, Y, X = np.meshgrid(zc, yc, xc, indexing="ij")
    pts = np.array([Z.ravel(), Y.ravel(), X.ravel()])
    top_wall = not coarse.symmetry
    out = np.empty((3, fine.nz, fine.ny, fine.nx))
    for c in range(3):
        sign_top = -1.0 if (top_wall or c == 2) else 1.0
        padded = _pad(u[c], -1.0, -1.0, sign_top)
        out[c] = map_coordinates(padded, pts, order=1, mode="nearest").reshape(out[c].shape)
    r = rho - rho.mean()
    rho_f = map_coordinates(_pad(r, 1.0, 1.0, 1.0), pts, order=1, mode="nearest")
    rho_f = rho_f.reshape(fine.nz, fine.ny, fine.nx) * density_scale
    out[:, :, fine.solid.T] = 0.0
    return out, rho_f - rho_f.mean()
