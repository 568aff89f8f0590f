"""The lattice box of a resolved-particle run: faces, walls, pillar, and its pull and link tables.

Nodes sit at ((i + ½), (j + ½), (k + ½)) in lattice units, flat index
``n = (k ny + j) nx + i``; populations are stored unshifted as ``f[q, n]``
(float64). The box is periodic in x, with the x faces shifted by ``shift``
cells in y as the unit cell of a tilted pillar array
(:mod:`fibersweep.flow.cell`: node (i + nx, j + shift) is node (i, j)); in y
periodic or bounded by no-slip walls at y = 0 and y = ny; in z periodic,
bounded by walls at z = 0 and z = nz (each may move in its plane), or bounded
below and mirrored at z = nz (the free-slip midplane of a symmetric channel).
A full-depth static obstacle (the pillar) is a set of solid columns whose
links carry the fraction where they cross its outline.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fibersweep.flow.lattice import MIRROR_Z, E, Q

__all__ = ["Box", "pull_table", "pillar_links", "wrap"]

Z_MODES = ("walls", "periodic", "symmetric")


@dataclass(frozen=True)
class Box:
    """A resolved-particle lattice box.

    Attributes
    ----------
    nx, ny, nz : int
        Interior nodes along x, y, z.
    periodic_y : bool
        True: periodic in y; False: no-slip walls at y = 0 and y = ny.
    shift : int
        Row shift of the x faces in cells (needs ``periodic_y`` when nonzero).
    z_mode : str
        "walls" (no-slip at z = 0 and z = nz), "periodic", or "symmetric"
        (wall at z = 0, free-slip mirror at z = nz: half of a channel of depth 2 nz).
    wall_velocity : ndarray, shape (2, 3)
        In-plane velocity of the bottom (row 0) and top (row 1) z walls [lattice units].
    solid : ndarray, shape (nx, ny), bool, optional
        Full-depth static solid columns (the pillar); None: none.
    shape : object, optional
        The pillar's outline in lattice units (with ``link_entry(x, y, ex, ey)``,
        as :class:`fibersweep.geometry.circle.Circle`); links into ``solid`` then
        carry the exact crossing fraction, else ½ (staircase).
    """

    nx: int
    ny: int
    nz: int
    periodic_y: bool = True
    shift: int = 0
    z_mode: str = "periodic"
    wall_velocity: np.ndarray = field(default_factory=lambda: np.zeros((2, 3)))
    solid: np.ndarray | None = None
    shape: object | None = None

    def __post_init__(self) -> None:
        if self.z_mode not in Z_MODES:
            raise ValueError(f"z_mode must be one of {Z_MODES}, got {self.z_mode!r}")
        if self.shift and not self.periodic_y:
            raise ValueError("a row shift of the x faces needs a box periodic in y")
        if min(self.nx, self.ny, self.nz) < 2:
            raise ValueError(f"box too small: {self.nx} x {self.ny} x {self.nz}")
        wv = np.asarray(self.wall_velocity, dtype=np.float64)
        if wv.shape != (2, 3) or np.any(wv[:, 2] != 0):
            raise ValueError("wall_velocity must be (2, 3) with no z component")
        object.__setattr__(self, "wall_velocity", wv)
        if self.solid is not None and np.shape(self.solid) != (self.nx, self.ny):
            raise ValueError(f"solid must have shape ({self.nx}, {self.ny})")

    @property
    def nodes(self) -> int:
        """Number of interior nodes nx ny nz."""
        return self.nx * self.ny * self.nz

    def solid_flags(self) -> np.ndarray:
        """Per node: 0 fluid, 1 static solid; shape (nodes,), int8."""
        flags = np.zeros((self.nz, self.ny, self.nx), dtype=np.int8)
        if self.solid is not None:
            flags[:, self.solid.T] = 1
        return flags.ravel()


def wrap(box: Box, i, j, k):
    """Interior node of lattice position (i, j, k) (int arrays): (flat index, inside).

    x folds with the row shift; y folds (periodic) or is outside beyond a wall;
    z folds (periodic) or is outside beyond [0, nz).
    """
    i, j, k = (np.asarray(v, dtype=np.int64) for v in (i, j, k))
    rows = np.floor_divide(i, box.nx)
    i = i - rows * box.nx
    j = j - rows * box.shift
    inside = np.ones(np.broadcast(i, j, k).shape, dtype=bool)
    if box.periodic_y:
        j = j % box.ny
    else:
        inside &= (j >= 0) & (j < box.ny)
    if box.z_mode == "periodic":
        k = k % box.nz
    else:
        inside &= (k >= 0) & (k < box.nz)
    n = (np.clip(k, 0, box.nz - 1) * box.ny + np.clip(j, 0, box.ny - 1)) * box.nx + i
    return n, inside


def pull_table(box: Box) -> np.ndarray:
    """Where each node pulls each population from.

    Returns
    -------
    ndarray, shape (19, nodes), int64
        ``src[q, n] >= 0``: population q of node n after streaming is
        ``f.ravel()[src]`` (population q of x − e_q; across the symmetric top the
        mirror population of the in-plane neighbour). ``src < 0``: half-way
        bounce-back from a wall, ``-1`` static (y walls, pillar), ``-2`` the bottom
        z wall, ``-3`` the top z wall (moving with ``box.wall_velocity``).
    """
    N = box.nodes
    k, j, i = (a.ravel() for a in np.meshgrid(np.arange(box.nz), np.arange(box.ny),
                                              np.arange(box.nx), indexing="ij"))  # fmt: skip
    flags = box.solid_flags()
    src = np.empty((Q, N), dtype=np.int64)
    for q in range(Q):
        ex, ey, ez = (int(v) for v in E[q])
        ks = k - ez
        qs = np.full(N, q)
        mirror = (box.z_mode == "symmetric") & (ks >= box.nz)
        ks = np.where(mirror, k, ks)
        qs = np.where(mirror, MIRROR_Z[q], qs)
        n_src, inside = wrap(box, i - ex, j - ey, ks)
        s = qs * N + n_src
        s = np.where(inside & (flags[n_src] == 0), s, -1)
        if box.z_mode in ("walls", "symmetric"):
            s = np.where(k - ez < 0, -2, s)
        if box.z_mode == "walls":
            s = np.where(k - ez >= box.nz, -3, s)
        src[q] = s
    return src


def pillar_links(box: Box) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Links from fluid nodes into the static pillar, with where they cross it.

    Returns
    -------
    node, q : ndarray, shape (m,), int64
        The fluid node and the population it pulls from the pillar (from x − e_q).
    t : ndarray, shape (m,), float64
        Fraction of the link x → x − e_q at which the wall lies (½ without a shape).
    beyond : ndarray, shape (m,), int64
        The node x + e_q (flat), or −1 if it is not fluid (interpolation then
        falls back to half-way bounce-back).
    """
    if box.solid is None:
        z = np.zeros(0, dtype=np.int64)
        return z, z, np.zeros(0), z
    flags = box.solid_flags()
    k, j, i = (a.ravel() for a in np.meshgrid(np.arange(box.nz), np.arange(box.ny),
                                              np.arange(box.nx), indexing="ij"))  # fmt: skip
    out = ([], [], [], [])
    fluid = flags == 0
    for q in range(1, Q):
        ex, ey, ez = (int(v) for v in E[q])
        ks = k - ez
        if box.z_mode == "symmetric":  # above the mirror: the column of the image, same link
            ks = np.where(ks >= box.nz, k, ks)
        n_src, inside = wrap(box, i - ex, j - ey, ks)
        hit = fluid & inside & (flags[n_src] == 1)
        if not hit.any():
            continue
        nodes = np.flatnonzero(hit)
        if box.shape is not None:
            t = box.shape.link_entry(i[nodes] + 0.5, j[nodes] + 0.5, -float(ex), -float(ey),
                                     closed=True)  # fmt: skip
            if np.isnan(t).any():
                raise ValueError("a link into the pillar does not cross its outline "
                                 "(does the pillar reach a face of the box?)")  # fmt: skip
            t = np.clip(t, 1e-6, 1.0)
        else:
            t = np.full(nodes.size, 0.5)
        n2, in2 = wrap(box, i[nodes] + ex, j[nodes] + ey, k[nodes] + ez)
        beyond = np.where(in2 & (flags[n2] == 0), n2, -1)
        for lst, v in zip(out, (nodes, np.full(nodes.size, q), t, beyond), strict=True):
            lst.append(v)
    if not out[0]:
        z = np.zeros(0, dtype=np.int64)
        return z, z, np.zeros(0), z
    node, qq, t, beyond = (np.concatenate(v) for v in out)
    return node.astype(np.int64), qq.astype(np.int64), t, beyond.astype(np.int64)
