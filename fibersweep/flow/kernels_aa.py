"""In-place (AA-pattern) D3Q19 steps: one population array, 152 bytes per cell update.

The AA pattern (Bailey et al. 2009) alternates two kernels on a single array:

- even step: each node reads its own 19 slots, collides, and writes f*_q into
  its own slot opp(q) (no data moves between nodes);
- odd step: each node gathers f*_q(x − e_q) from slot opp(q) of its neighbour,
  collides, and pushes f*_q into slot q of the neighbour x + e_q.

After an odd step slot q of node x holds the population arriving at x, which is
what the next even step reads. Every slot is read and written by the same node
within a step, so no second array is needed: 76 B read + 76 B written per cell
(the two-array pull moves 228 B with write-allocate).

Boundaries: the odd step gathers and scatters through per-row tables
(:func:`fibersweep.flow.lattice.aa_tables`) that resolve walls and the
symmetric top; periodic x is handled by fixing the two row-end cells (in the
row the tables name, so that a unit cell's shifted x faces cost nothing more); the pillar
by copying bounce-back values into and out of its cells around the odd step
(:func:`fibersweep.flow.lattice.aa_links`, applied with :func:`apply_links`).

The collision is :func:`fibersweep.flow.kernels._collide_block`, inlined here.
Numba's on-disk cache only watches this file: after editing the collision in
kernels.py, touch this file (or clear ``__pycache__``) so these kernels recompile.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from fibersweep.flow.kernels import CHUNK, _collide_block, block_constants

__all__ = ["aa_even", "aa_odd", "apply_links"]


@nb.njit(cache=True, parallel=True, fastmath=True)
def aa_even(
    g: np.ndarray, reads: np.ndarray, writes: np.ndarray, fx: float, omega_p: float,
    omega_m: float,
) -> None:  # fmt: skip
    """Even AA step: collide in place, f*_q stored in the node's slot opp(q).

    Parameters
    ----------
    g : ndarray, shape (19, nz + 2, ny + 2, nx + 2), float32 or float64
        Shifted populations (g = f − w); ghost layers are not used.
    reads, writes : ndarray, shape (19,), int64
        Slot that population q of the collision is read from, and the slot its
        f*_q goes to: (identity, opposite directions), or with the force along y
        the turned frame and its opposites (:data:`fibersweep.flow.lattice.FRAMES`).
    fx : float
        Body force density along x [lattice units].
    omega_p, omega_m : float
        Relaxation rates of the even and odd moments.
    """
    nz, ny, nx = g.shape[1] - 2, g.shape[2] - 2, g.shape[3] - 2
    F, half_f, wp, wm, sp, sm, w0, w1, w2 = block_constants(g, fx, omega_p, omega_m)
    for r in nb.prange(nz * ny):
        z = r // ny + 1
        y = r - (z - 1) * ny + 1
        b = np.empty((19, CHUNK), dtype=g.dtype)
        for c0 in range(0, nx, CHUNK):
            n = np.uint64(min(CHUNK, nx - c0))  # unsigned: no wraparound test
            o = np.uint64(1 + c0)
            for q in range(19):
                src = g[reads[q], z, y]
                bq = b[q]
                for i in range(n):
                    bq[i] = src[o + i]
            _collide_block(b, n, F, half_f, wp, wm, sp, sm, w0, w1, w2)
            for q in range(19):
                dst = g[writes[q], z, y]
                bq = b[q]
                for i in range(n):
                    dst[o + i] = bq[i]


@nb.njit(cache=True, parallel=True, fastmath=True)
def aa_odd(
    g: np.ndarray,
    gather: np.ndarray,
    scatter: np.ndarray,
    fx: float,
    omega_p: float,
    omega_m: float,
) -> None:
    """Odd AA step: gather from neighbours, collide, push to neighbours.

    Parameters
    ----------
    g : ndarray, shape (19, nz + 2, ny + 2, nx + 2), float32 or float64
    gather, scatter : ndarray, shape (nz * ny, 19, 5), int64
        Per row and population: (slot, z, y, x_off, y_across) in padded
        coordinates; cell i of the row reads ``g[slot, z, y, x_off + i]`` and
        writes its f*_q to ``g[slot', z', y', x_off' + i]``. x_off is 0, 1 or 2
        (shift −1, 0, +1); shifts that leave the row are wrapped here, to the
        other end of row y_across (the row itself, or moved by the shifted
        periodic x faces of a unit cell).
    fx, omega_p, omega_m : float
        As in :func:`aa_even`.
    """
    nx = g.shape[3] - 2
    F, half_f, wp, wm, sp, sm, w0, w1, w2 = block_constants(g, fx, omega_p, omega_m)
    last = np.uint64(nx)
    for r in nb.prange(gather.shape[0]):
        b = np.empty((19, CHUNK), dtype=g.dtype)
        for c0 in range(0, nx, CHUNK):
            n = np.uint64(min(CHUNK, nx - c0))
            ends_row = c0 + CHUNK >= nx
            for q in range(19):
                src = g[gather[r, q, 0], gather[r, q, 1], gather[r, q, 2]]
                xo = gather[r, q, 3]
                off = np.uint64(xo + c0)
                bq = b[q]
                for i in range(n):
                    bq[i] = src[off + i]
                if c0 == 0 and xo == 0:  # cell 0 reads x = −1: the last cell
                    bq[0] = g[gather[r, q, 0], gather[r, q, 1], gather[r, q, 4], last]
                if ends_row and xo == 2:  # last cell reads x = nx: cell 0
                    bq[n - np.uint64(1)] = g[gather[r, q, 0], gather[r, q, 1], gather[r, q, 4], 1]
            _collide_block(b, n, F, half_f, wp, wm, sp, sm, w0, w1, w2)
            for q in range(19):
                dst = g[scatter[r, q, 0], scatter[r, q, 1], scatter[r, q, 2]]
                xo = scatter[r, q, 3]
                off = np.uint64(xo + c0)
                bq = b[q]
                for i in range(n):
                    dst[off + i] = bq[i]
                if c0 == 0 and xo == 0:  # cell 0 pushes to x = −1: the last cell
                    g[scatter[r, q, 0], scatter[r, q, 1], scatter[r, q, 4], last] = bq[0]
                if ends_row and xo == 2:  # last cell pushes to x = nx: cell 0
                    g[scatter[r, q, 0], scatter[r, q, 1], scatter[r, q, 4], 1] = bq[
                        n - np.uint64(1)
                    ]


@nb.njit(cache=True)
def apply_links(g: np.ndarray, links: np.ndarray, reset_cells: np.ndarray) -> None:
    """Copy ``g[q].flat[dst] = g[q_src].flat[src]`` for rows (q, dst, q_src, src), then zero cells.

    Parameters
    ----------
    g : ndarray, shape (19, nz + 2, ny + 2, nx + 2), float32 or float64
    links : ndarray, shape (n, 4), int64
        From :func:`fibersweep.flow.lattice.aa_links`.
    reset_cells : ndarray, shape (m,), int64
        Flat indices (one padded plane) zeroed in every slot after the copies.
    """
    plane = g.shape[1] * g.shape[2] * g.shape[3]
    flat = g.reshape(g.shape[0] * plane)
    for n in range(links.shape[0]):
        flat[links[n, 0] * plane + links[n, 1]] = flat[links[n, 2] * plane + links[n, 3]]
    for q in range(g.shape[0]):
        for c in range(reset_cells.shape[0]):
            flat[q * plane + reset_cells[c]] = 0.0
