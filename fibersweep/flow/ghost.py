"""Ghost velocities inside a sub-grid pillar wall, so that interpolation sees the exact wall.

The lattice solver leaves the velocity at solid nodes at zero. With the
staircase pillar that zero sits half a cell behind the half-way wall for every
boundary node alike. With the interpolated (sub-grid) wall the wall lies at a
fraction q of each link that varies from node to node: a zero at the solid
node then puts the wall, as the 4-point IB kernel of
:meth:`fibersweep.flow.field.FlowField.velocity` sees it, anywhere between the
true wall and the solid node, by an amount that depends on where the pillar
sits relative to the grid. Tracers, the separatrix and fibers near the pillar
feel that lattice pattern.

The fix is the ghost-cell reflection of immersed-boundary methods: every solid
node s within reach of the IB stencil gets u(s) = −u(m), with m = 2 w − s the
mirror image of s through its nearest wall point w and u(m) the bilinear
interpolation of the (extended) nodal field. A no-slip wall has u linear and
odd in the normal distance near it, so the extended field vanishes on the
exact wall to second order. Ghosts whose mirror stencil holds other ghosts are
coupled; the small sparse system (I + W) u_g = −W_f u_f is solved directly.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.ndimage import binary_dilation

from fibersweep.geometry import as_shape

__all__ = ["GHOST_METHOD", "GHOST_REACH", "ghost_stencil", "extend_into_wall"]

GHOST_METHOD = "mirror-1"  # recorded in FlowField.meta['wall_ghosts']
GHOST_REACH = 3  # solid nodes within this many nodes (Chebyshev) of the fluid get a ghost value


def ghost_stencil(
    solid: np.ndarray, vertices: np.ndarray, dx: float
) -> tuple[np.ndarray, sp.csr_matrix, sp.csr_matrix]:
    """The ghost nodes and the reflection weights.

    Parameters
    ----------
    solid : ndarray, shape (nx, ny), bool
        Pillar nodes (x periodic; y = 0 and ny are walls).
    vertices : shape or ndarray, shape (n_v, 2)
        Pillar outline [µm]: a :mod:`fibersweep.geometry` shape (any pillar,
        circles included) or convex polygon corners; node (i, j) at ((i + ½) Δx, (j + ½) Δx).
    dx : float
        Node spacing [µm].

    Returns
    -------
    ghosts : ndarray, shape (m,), int64
        Flat indices (i·ny + j) of the ghost nodes.
    w_ghost : csr_matrix, shape (m, m)
        Bilinear weights of the mirror points on ghost nodes.
    w_fluid : csr_matrix, shape (m, nx·ny)
        Bilinear weights of the mirror points on fluid nodes (other solid nodes hold 0).
    """
    nx, ny = solid.shape
    near = binary_dilation(~solid, np.ones((3, 3), bool), iterations=GHOST_REACH) & solid
    gi, gj = np.nonzero(near)
    ghosts = gi * ny + gj
    gx, gy = (gi + 0.5) * dx, (gj + 0.5) * dx
    w = as_shape(vertices).nearest(gx, gy)[0]
    mx = (2.0 * w[:, 0] - gx) / dx - 0.5  # mirror point in node coordinates
    my = (2.0 * w[:, 1] - gy) / dx - 0.5
    i0 = np.floor(mx).astype(np.int64)
    j0 = np.floor(my).astype(np.int64)
    tx, ty = mx - i0, my - j0
    col_of = -np.ones(nx * ny, dtype=np.int64)
    col_of[ghosts] = np.arange(ghosts.size)
    rows_g, cols_g, vals_g, rows_f, cols_f, vals_f = [], [], [], [], [], []
    for di, dj, wt in ((0, 0, (1 - tx) * (1 - ty)), (1, 0, tx * (1 - ty)),
                       (0, 1, (1 - tx) * ty), (1, 1, tx * ty)):  # fmt: skip
        ii = (i0 + di) % nx
        jj = j0 + dj
        inside = (jj >= 0) & (jj < ny)  # outside the channel u = 0 (walls)
        flat = ii * ny + np.clip(jj, 0, ny - 1)
        is_fluid = inside & ~solid.ravel()[flat]
        is_ghost = inside & (col_of[flat] >= 0)
        r = np.arange(ghosts.size)
        rows_f.append(r[is_fluid])
        cols_f.append(flat[is_fluid])
        vals_f.append(wt[is_fluid])
        rows_g.append(r[is_ghost])
        cols_g.append(col_of[flat[is_ghost]])
        vals_g.append(wt[is_ghost])
    m = ghosts.size
    w_ghost = sp.csr_matrix(
        (np.concatenate(vals_g), (np.concatenate(rows_g), np.concatenate(cols_g))), shape=(m, m)
    )
    w_fluid = sp.csr_matrix(
        (np.concatenate(vals_f), (np.concatenate(rows_f), np.concatenate(cols_f))),
        shape=(m, nx * ny),
    )
    return ghosts, w_ghost, w_fluid


def extend_into_wall(
    ux: np.ndarray, uy: np.ndarray, solid: np.ndarray, vertices: np.ndarray, dx: float
) -> tuple[np.ndarray, np.ndarray]:
    """Copies of (ux, uy) with ghost values u = −u(mirror) on the solid nodes near the wall.

    Parameters
    ----------
    ux, uy : ndarray, shape (nx, ny)
        Nodal velocity (values at solid nodes are ignored).
    solid, vertices, dx :
        As for :func:`ghost_stencil`.

    Returns
    -------
    (ndarray, ndarray), each shape (nx, ny), float64
        Fluid nodes unchanged, ghost nodes filled, deeper solid nodes 0.
    """
    ghosts, w_ghost, w_fluid = ghost_stencil(solid, vertices, dx)
    out = []
    a = (sp.identity(ghosts.size, format="csc") + w_ghost.tocsc()).tocsc()
    lu = spla.splu(a) if ghosts.size else None
    for comp in (ux, uy):
        u = np.array(comp, dtype=np.float64)
        u[solid] = 0.0
        if lu is not None:
            u.ravel()[ghosts] = lu.solve(-(w_fluid @ u.ravel()))
        out.append(u)
    return out[0], out[1]
