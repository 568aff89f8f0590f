"""Blocked kernels of the resolved lattice: vectorisable TRT collision and row-wise streaming.

The same step as :func:`fibersweep.resolved.kernels.collide` and
:func:`~fibersweep.resolved.kernels.stream` (which stay as the reference the
tests and ``scripts/benchmarks/bench_resolved.py`` compare against), laid out
as the production flow kernels are:

* the collision copies ``CHUNK`` consecutive nodes into a local (19, CHUNK)
  block with compile-time strides, collides it with the production kernel's
  TRT pair update (:func:`fibersweep.flow.kernels._pair`, imported; the force
  here has three components, so the block loop is written for that) and writes
  back the fluid nodes only;
* streaming pulls whole rows: interior node i of row (k, j) takes population q
  from ``start + i − e_qx`` of the row the table :func:`row_table` names (or
  bounces the whole row off a y or z wall), and only the two end nodes of each
  row go through the node-wise pull table (the shifted periodic x faces).

Populations are unshifted ``f[q, n]`` (float64); ``_pair`` works on shifted
ones g = f − w, and takes the density deviation d for its even equilibrium
w (d + ρ(…)): passing d = ρ gives the unshifted w ρ (1 + …).
"""

from __future__ import annotations

import numba as nb
import numpy as np

from fibersweep.flow.kernels import CHUNK, _pair
from fibersweep.flow.lattice import OPP, E, W

__all__ = ["collide_blocked", "stream_rows", "row_table", "CHUNK"]

# the hard-coded pairs below follow the project's D3Q19 order (fibersweep.flow.lattice.E)
_PAIRS = ((1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (1, -1, 0), (1, 0, 1), (1, 0, -1),
          (0, 1, 1), (0, 1, -1))  # fmt: skip
if not all(tuple(E[2 * k + 1]) == p and tuple(E[2 * k + 2]) == tuple(-np.array(p))
           for k, p in enumerate(_PAIRS)):  # fmt: skip
    raise ImportError("fibersweep.flow.lattice.E is not in the order kernels_blocked assumes")

_E = np.ascontiguousarray(E.astype(np.int64))
_EF = np.ascontiguousarray(E.astype(np.float64))
_OPP = np.ascontiguousarray(OPP.astype(np.int64))
_W = np.ascontiguousarray(W.astype(np.float64))
W0, W1, W2 = float(W[0]), float(W[1]), float(W[7])


@nb.njit(inline="always", fastmath=True)
def _collide_xyz(b, n, fx, fy, fz, wp, wm, sp, sm):
    """Collide the first ``n`` nodes of a (19, CHUNK) block in place (force (fx, fy, fz))."""
    for i in range(n):
        f0 = b[0, i]
        f1 = b[1, i]
        f2 = b[2, i]
        f3 = b[3, i]
        f4 = b[4, i]
        f5 = b[5, i]
        f6 = b[6, i]
        f7 = b[7, i]
        f8 = b[8, i]
        f9 = b[9, i]
        f10 = b[10, i]
        f11 = b[11, i]
        f12 = b[12, i]
        f13 = b[13, i]
        f14 = b[14, i]
        f15 = b[15, i]
        f16 = b[16, i]
        f17 = b[17, i]
        f18 = b[18, i]
        rho = (f0 + f1 + f2 + f3 + f4 + f5 + f6 + f7 + f8 + f9
               + f10 + f11 + f12 + f13 + f14 + f15 + f16 + f17 + f18)  # fmt: skip
        inv = 1.0 / rho
        jx = f1 - f2 + f7 - f8 + f9 - f10 + f11 - f12 + f13 - f14
        jy = f3 - f4 + f7 - f8 - f9 + f10 + f15 - f16 + f17 - f18
        jz = f5 - f6 + f11 - f12 - f13 + f14 + f15 - f16 - f17 + f18
        ux = (jx + 0.5 * fx) * inv
        uy = (jy + 0.5 * fy) * inv
        uz = (jz + 0.5 * fz) * inv
        usq15 = 1.5 * (ux * ux + uy * uy + uz * uz)
        uf3 = 3.0 * (ux * fx + uy * fy + uz * fz)
        b[0, i] = f0 - wp * (f0 - W0 * rho * (1.0 - usq15)) - sp * W0 * uf3  # S_0 = −3 w_0 u·F
        b[1, i], b[2, i] = _pair(f1, f2, W1, ux, fx, rho, rho, usq15, uf3, wp, wm, sp, sm)
        b[3, i], b[4, i] = _pair(f3, f4, W1, uy, fy, rho, rho, usq15, uf3, wp, wm, sp, sm)
        b[5, i], b[6, i] = _pair(f5, f6, W1, uz, fz, rho, rho, usq15, uf3, wp, wm, sp, sm)
        b[7, i], b[8, i] = _pair(f7, f8, W2, ux + uy, fx + fy, rho, rho, usq15, uf3, wp, wm,
                                 sp, sm)  # fmt: skip
        b[9, i], b[10, i] = _pair(f9, f10, W2, ux - uy, fx - fy, rho, rho, usq15, uf3, wp, wm,
                                  sp, sm)  # fmt: skip
        b[11, i], b[12, i] = _pair(f11, f12, W2, ux + uz, fx + fz, rho, rho, usq15, uf3, wp, wm,
                                   sp, sm)  # fmt: skip
        b[13, i], b[14, i] = _pair(f13, f14, W2, ux - uz, fx - fz, rho, rho, usq15, uf3, wp, wm,
                                   sp, sm)  # fmt: skip
        b[15, i], b[16, i] = _pair(f15, f16, W2, uy + uz, fy + fz, rho, rho, usq15, uf3, wp, wm,
                                   sp, sm)  # fmt: skip
        b[17, i], b[18, i] = _pair(f17, f18, W2, uy - uz, fy - fz, rho, rho, usq15, uf3, wp, wm,
                                   sp, sm)  # fmt: skip


@nb.njit(cache=True, parallel=True, fastmath=True)
def collide_blocked(f, flags, force, omega_p, omega_m):
    """TRT collision with Guo forcing, in place on the fluid nodes (flags == 0).

    As :func:`fibersweep.resolved.kernels.collide` (equal to round-off: the sums
    are ordered differently). ``f`` (19, N) float64, ``flags`` (N,) int8,
    ``force`` (3,) [lattice units], ω± the even/odd rates.
    """
    N = f.shape[1]
    fx, fy, fz = force[0], force[1], force[2]
    sp = 1.0 - 0.5 * omega_p
    sm = 1.0 - 0.5 * omega_m
    nblk = (N + CHUNK - 1) // CHUNK
    for blk in nb.prange(nblk):
        b = np.empty((19, CHUNK))
        off = np.uint64(blk * CHUNK)  # unsigned: no wraparound test, the loops vectorise
        n = np.uint64(min(CHUNK, N - blk * CHUNK))
        for q in range(19):
            fq = f[q]
            bq = b[q]
            for i in range(n):
                bq[i] = fq[off + i]
        _collide_xyz(b, n, fx, fy, fz, omega_p, omega_m, sp, sm)
        for q in range(19):
            fq = f[q]
            bq = b[q]
            for i in range(n):
                fq[off + i] = bq[i] if flags[off + i] == 0 else fq[off + i]


def row_table(src: np.ndarray, nx: int) -> np.ndarray:
    """Per row and population: where its interior nodes pull from.

    Parameters
    ----------
    src : ndarray, shape (19, N), int64
        The node-wise pull table (:func:`fibersweep.resolved.box.pull_table`).
    nx : int
        Nodes per row.

    Returns
    -------
    ndarray, shape (N // nx, 19), int64
        ``>= 0``: the flat index (q_src N + row start) of the row that interior node i
        (0 < i < nx − 1) pulls from, at ``start + i − e_qx``; ``< 0``: the whole row
        bounces off a wall with that code (−1 static, −2 / −3 the moving z walls).
        Pillar sources inside a row are pulled as they are: the pillar's links
        overwrite them (:func:`fibersweep.resolved.kernels.static_links`).

    Raises
    ------
    ValueError
        If a row's interior pulls are not one shifted row (a table this layout cannot
        express), or the rows are shorter than 3 nodes.
    """
    if nx < 3:
        raise ValueError(f"rows of {nx} nodes have no interior: use the node-wise kernels")
    Q, N = src.shape
    nrows = N // nx
    out = np.empty((nrows, Q), dtype=np.int64)
    i = np.arange(1, nx - 1)
    for q in range(Q):
        ex = int(E[q, 0])
        s = src[q].reshape(nrows, nx)[:, 1 : nx - 1]
        start = s[:, 0] - (1 - ex)
        wall = s.min(axis=1) <= -2
        wall |= (s == -1).all(axis=1)
        want = start[:, None] + i[None, :] - ex
        ok = (s == want) | (s == -1)
        if not np.all(ok[~wall]):
            raise ValueError(f"population {q}: a row's interior does not pull from one row")
        # a row that starts inside the pillar: take the start from a node outside it
        for r in np.flatnonzero(~wall & (s[:, 0] == -1)):
            m = int(np.flatnonzero(s[r] >= 0)[0])
            start[r] = s[r, m] - (m + 1) + ex
        out[:, q] = np.where(wall, np.where(s.min(axis=1) <= -2, s.min(axis=1), -1), start)
    return out


@nb.njit(cache=True, parallel=True, fastmath=True)
def stream_rows(f, fn, rows, src, wall_velocity):
    """Pull streaming f → fn, row by row (:func:`row_table`); row ends through ``src``.

    As :func:`fibersweep.resolved.kernels.stream` on every fluid node, except that
    the links into the pillar are left to be overwritten by the pillar's links, and
    nodes that are not fluid receive values too (nothing reads them).
    """
    N = f.shape[1]
    nrows = rows.shape[0]
    nx = N // nrows
    flat = f.ravel()
    for r in nb.prange(nrows):
        n0 = r * nx
        for q in range(19):
            s = rows[r, q]
            o = _OPP[q]
            fnq = fn[q]
            if s < 0:  # the whole row bounces off a wall
                add = 0.0
                if s <= -2:
                    w = -2 - s
                    add = 6.0 * _W[q] * (_EF[q, 0] * wall_velocity[w, 0]
                                         + _EF[q, 1] * wall_velocity[w, 1])  # fmt: skip
                fo = f[o]
                for i in range(1, nx - 1):
                    fnq[n0 + i] = fo[n0 + i] + add
            else:
                base = np.uint64(s + 1 - _E[q, 0])
                dst = np.uint64(n0 + 1)
                for i in range(np.uint64(nx - 2)):
                    fnq[dst + i] = flat[base + i]
            for i in (0, nx - 1):  # the row's ends: wrapped and shifted through the node table
                n = n0 + i
                t = src[q, n]
                if t >= 0:
                    fnq[n] = flat[t]
                else:
                    v = f[o, n]
                    if t <= -2:
                        w = -2 - t
                        v += 6.0 * _W[q] * (_EF[q, 0] * wall_velocity[w, 0]
                                            + _EF[q, 1] * wall_velocity[w, 1])  # fmt: skip
                    fnq[n] = v
