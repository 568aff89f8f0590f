"""D3Q19 lattice constants and the padded grid of a channel or a periodic box with its pillar.

Storage layout
--------------
Populations are stored shifted, ``g_q = f_q - w_q`` (float32 keeps the small
deviations from rest to full precision), as a structure of arrays
``g[q, z, y, x]`` with x innermost, padded with one ghost layer on every side:
interior node (i, j, k) of the channel is ``g[:, k + 1, j + 1, i + 1]``.
Boundaries cost no branch in the bulk loop: the channel walls and the
specular midplane are resolved per row by a pull table (:func:`pull_sources`:
where to read each population of a row), periodic x by ghost columns, and the
pillar by storing in each solid cell the bounce-back value its fluid
neighbour will pull (:func:`boundary_links`). The y and z ghost layers are
never read; they keep the indexing simple.

Box boundaries
--------------
The channel has no-slip walls at y = 0 and y = W and periodic ends in x. The
unit cell of a pillar array (:mod:`fibersweep.flow.cell`) is periodic in y and
*shifted* periodic in x: node (i + nx, j + s) is node (i, j), s the row shift
in cells (:attr:`Grid.shift`, :meth:`Grid.wrap`). Every table below resolves
its neighbours through :meth:`Grid.wrap`, so both boxes are stepped by the
same kernels.

Body force along y
------------------
The collision kernels apply the body force along x. A force along y is the
same collision seen in a frame turned by 90° about z: the kernels read the
populations through a permutation of the directions (:data:`FRAMES`), so that
their x axis is the box's y axis; boundaries, slots and tables stay those of
the box.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fibersweep.config.array import EDGE_CELLS
from fibersweep.geometry import Geometry

__all__ = [
    "U_LATTICE",
    "MACH_LIMIT",
    "EDGE_CELLS",
    "FRAMES",
    "E",
    "W",
    "OPP",
    "MIRROR_Z",
    "Q",
    "CS2",
    "Grid",
    "make_grid",
    "boundary_links",
    "pull_sources",
    "aa_tables",
    "aa_links",
    "table_cells",
]

Q = 19
CS2 = 1.0 / 3.0
U_LATTICE = 1e-5  # empty duct's centre speed in lattice units: Mach ~ 2e-5, lattice Re ~ 2e-3
MACH_LIMIT = 0.1  # |u| in lattice units above this means divergence

# Velocity set: rest, 6 faces, 12 edges; opposite pairs are (1,2), (3,4), ... (17,18).
E = np.array(
    [
        (0, 0, 0),
        (1, 0, 0),
        (-1, 0, 0),
        (0, 1, 0),
        (0, -1, 0),
        (0, 0, 1),
        (0, 0, -1),
        (1, 1, 0),
        (-1, -1, 0),
        (1, -1, 0),
        (-1, 1, 0),
        (1, 0, 1),
        (-1, 0, -1),
        (1, 0, -1),
        (-1, 0, 1),
        (0, 1, 1),
        (0, -1, -1),
        (0, 1, -1),
        (0, -1, 1),
    ],
    dtype=np.int64,
)
W = np.array([1.0 / 3.0] + [1.0 / 18.0] * 6 + [1.0 / 36.0] * 12)


def _index_of(e: np.ndarray) -> int:
    return int(np.flatnonzero((E == e).all(axis=1))[0])


OPP = np.array([_index_of(-E[q]) for q in range(Q)], dtype=np.int64)
MIRROR_Z = np.array([_index_of(E[q] * np.array([1, 1, -1])) for q in range(Q)], dtype=np.int64)
# the direction of E[q] turned by +90° about z, (x, y, z) -> (−y, x, z)
_TURN = np.array([[0, 1, 0], [-1, 0, 0], [0, 0, 1]])  # row vectors: e @ _TURN
_TURN_Z = np.array([_index_of(E[q] @ _TURN) for q in range(Q)], dtype=np.int64)
#: Per force axis (0: x, 1: y), the direction of the box that the kernels' direction q
#: stands for: the kernels collide with the force along their x, the box's axis.
FRAMES = (np.arange(Q, dtype=np.int64), _TURN_Z)


@dataclass(frozen=True)
class Grid:
    """The lattice of one flow problem.

    Attributes
    ----------
    nx, ny, nz : int
        Interior node counts (nz is the solved depth: half the channel with symmetry).
    nz_full : int
        Nodes across the whole channel depth H_ch / Δx.
    symmetry : bool
        True if the top of the solved domain is the free-slip midplane.
    dx : float
        Node spacing [µm].
    solid : ndarray, shape (nx, ny), bool
        Pillar nodes (node centres strictly inside the pillar); full depth.
    periodic_y : bool
        False: no-slip walls at y = 0 and y = ny (the channel); True: periodic in y.
    shift : int
        Row shift of the x faces in cells: node (i + nx, j + shift) is node (i, j)
        (0: plainly periodic in x; nonzero only with ``periodic_y``).
    """

    nx: int
    ny: int
    nz: int
    nz_full: int
    symmetry: bool
    dx: float
    solid: np.ndarray
    periodic_y: bool = False
    shift: int = 0

    def __post_init__(self) -> None:
        if self.shift and not self.periodic_y:
            raise ValueError("a row shift of the x faces needs a box periodic in y")

    @property
    def padded_shape(self) -> tuple[int, int, int, int]:
        """Shape of the population array (Q, nz + 2, ny + 2, nx + 2)."""
        return (Q, self.nz + 2, self.ny + 2, self.nx + 2)

    @property
    def cells(self) -> int:
        """Interior lattice cells updated per step."""
        return self.nx * self.ny * self.nz

    def wrap(self, i, j):
        """The interior node at lattice position (i, j) (ints or int arrays).

        Returns (i', j', inside): x folded into [0, nx) with the row shift, y
        folded (periodic: inside is True) or left as it is (inside is False
        beyond a wall).
        """
        rows = i // self.nx
        i, j = i - rows * self.nx, j - rows * self.shift
        if self.periodic_y:
            return i, j % self.ny, True
        return i, j, (j >= 0) & (j < self.ny)


def make_grid(
    geometry: Geometry, dx: float, symmetry: bool, pillar: bool = True, closed: bool = False
) -> Grid:
    """Lattice for ``geometry`` at spacing ``dx`` [µm] (half-way walls on the channel faces).

    ``closed``: nodes on the pillar outline (within 1e-9 Δx) are solid too, so
    that every link into the pillar meets the wall at 0 < q ≤ 1 (interpolated
    bounce-back); otherwise only nodes strictly inside are (staircase).
    """
    nx = int(round(geometry.length / dx))
    ny = int(round(geometry.width / dx))
    nz_full = int(round(geometry.depth / dx))
    nz = nz_full // 2 if symmetry else nz_full
    x = (np.arange(nx) + 0.5) * dx
    y = (np.arange(ny) + 0.5) * dx
    X, Y = np.meshgrid(x, y, indexing="ij")
    if not pillar:
        solid = np.zeros((nx, ny), dtype=bool)
    elif closed:
        solid = geometry.shape.inside(X, Y, margin=1e-9 * dx)
    else:
        solid = geometry.inside_pillar(X, Y)
    return Grid(nx, ny, nz, nz_full, symmetry, float(dx), solid)


def boundary_links(grid: Grid) -> tuple[np.ndarray, np.ndarray]:
    """Pillar bounce-back links and the list of solid padded cells.

    Returns
    -------
    links : ndarray, shape (n, 4), int64
        Rows (q, dst, q_src, src): after a step, ``g[q].flat[dst] = g[q_src].flat[src]``
        with flat indices into one padded (nz+2, ny+2, nx+2) plane; dst is a solid
        node, src the fluid node t = dst + e_q that will pull it, q_src = opp(q)
        (half-way bounce-back). With a symmetric top, a fluid node of the top row
        pulls population q (e_z < 0) specularly as mirror(q) from the in-plane
        neighbour t − e_q; if that is solid, slot mirror(q) of it gets g[opp q](t).
    solid_cells : ndarray, shape (m,), int64
        Flat padded indices of every interior solid cell (reset to rest each step).
    """
    nyp, nxp = grid.ny + 2, grid.nx + 2
    si, sj = np.nonzero(grid.solid)
    rows = []
    cells = []

    def add_links(slot: int, q: int, base_s: np.ndarray, kt: int) -> None:
        """Rows (slot, solid cell, opp(q), fluid source in layer kt) for fluid in-plane targets."""
        it, jt, inside = grid.wrap(si + E[q][0], sj + E[q][1])
        ok = np.ones(si.shape, dtype=bool) & inside
        ok[ok] = ~grid.solid[it[ok], jt[ok]]
        if not ok.any():
            return
        src = ((kt + 1) * nyp + (jt[ok] + 1)) * nxp + (it[ok] + 1)
        n = int(ok.sum())
        rows.append(np.column_stack([np.full(n, slot), base_s[ok], np.full(n, OPP[q]), src]))

    for k in range(grid.nz):
        base_s = ((k + 1) * nyp + (sj + 1)) * nxp + (si + 1)
        cells.append(base_s)
        for q in range(1, Q):
            kt = k + E[q][2]
            if 0 <= kt < grid.nz:  # otherwise the target is a wall/ghost row, never fluid
                add_links(q, q, base_s, kt)
        if grid.symmetry and k == grid.nz - 1:
            for q in range(1, Q):
                if E[q][2] < 0:
                    add_links(MIRROR_Z[q], q, base_s, k)
    links = np.concatenate(rows).astype(np.int64) if rows else np.zeros((0, 4), np.int64)
    solid_cells = np.concatenate(cells).astype(np.int64) if cells else np.zeros(0, np.int64)
    return links, solid_cells


def _row(grid: Grid, j: int) -> int | None:
    """Interior row of lattice row j, None beyond a wall."""
    _, jj, inside = grid.wrap(0, int(j))
    return jj if inside else None


def pull_sources(grid: Grid) -> np.ndarray:
    """Where each row pulls each population from (walls and midplane resolved).

    Returns
    -------
    ndarray, shape (nz * ny, 19, 4), int64
        For row r = k * ny + j and population q: (q_src, z_src, y_src, x_off), padded
        coordinates, so that population q of interior node i after streaming is
        ``g[q_src, z_src, y_src, x_off + i]``:

        - interior source: (q, k − e_z, j − e_y, −e_x), i.e. a plain pull (rows
          folded in a box periodic in y; across an x face the ghost columns hold
          the shifted row, :func:`fibersweep.flow.kernels.fill_periodic`);
        - source beyond a no-slip wall (y, bottom z, top z without symmetry):
          half-way bounce-back, (opp q, k, j, 0) of the node itself;
        - source above the symmetric top: specular reflection from the mirror
          image of the in-plane neighbour, (mirror q, k, j − e_y, −e_x).

        All entries are offset by +1 for the padding.
    """
    out = np.zeros((grid.nz * grid.ny, Q, 4), dtype=np.int64)
    for k in range(grid.nz):
        for j in range(grid.ny):
            r = k * grid.ny + j
            for q in range(Q):
                ex, ey, ez = E[q]
                ks, js = k - ez, _row(grid, j - ey)
                if js is None or ks < 0 or (ks >= grid.nz and not grid.symmetry):
                    out[r, q] = (OPP[q], k + 1, j + 1, 1)
                elif ks >= grid.nz:
                    out[r, q] = (MIRROR_Z[q], k + 1, js + 1, 1 - ex)
                else:
                    out[r, q] = (q, ks + 1, js + 1, 1 - ex)
    return out


def aa_tables(grid: Grid) -> tuple[np.ndarray, np.ndarray]:
    """Gather and scatter tables of the odd AA step (walls and midplane resolved).

    After an even step, node x holds its post-collision f*_p in its slot opp(p).
    In the odd step node (i, j, k) gathers population q from

    - interior x − e_q: slot opp(q) there, (opp q, k − e_z, j − e_y, 1 − e_x);
    - beyond a no-slip wall: its own f*_{opp q} (bounce-back), slot q of itself;
    - above the symmetric top: the mirror image of the in-plane neighbour,
      f*_{mirror q} at (i − e_x, j − e_y, k), slot opp(mirror q) there;

    and pushes its f*_q to

    - interior x + e_q: slot q there, (q, k + e_z, j + e_y, 1 + e_x);
    - beyond a no-slip wall: back to itself as opp(q), slot opp(q) of itself;
    - above the symmetric top: to (i + e_x, j + e_y, k) as mirror(q).

    Returns
    -------
    gather, scatter : ndarray, shape (nz * ny, 19, 5), int64
        (slot, z, y, x_off, y_across) in padded coordinates for cell 0 of each
        row; y_across is the row the first (x_off 0) or last (x_off 2) cell
        reaches across the x face (y moved by the row shift).
    """
    gather = np.zeros((grid.nz * grid.ny, Q, 5), dtype=np.int64)
    scatter = np.zeros_like(gather)
    for k in range(grid.nz):
        for j in range(grid.ny):
            r = k * grid.ny + j
            for q in range(Q):
                ex, ey, ez = (int(v) for v in E[q])
                for sign, table in ((-1, gather), (1, scatter)):
                    kk, jj = k + sign * ez, _row(grid, j + sign * ey)
                    wall = jj is None or kk < 0 or (kk >= grid.nz and not grid.symmetry)
                    if wall:
                        slot, kk, jj, xo = (q if sign < 0 else OPP[q]), k, j, 1
                    elif kk >= grid.nz:
                        slot = OPP[MIRROR_Z[q]] if sign < 0 else MIRROR_Z[q]
                        kk, xo = k, 1 + sign * ex
                    else:
                        slot, xo = (OPP[q] if sign < 0 else q), 1 + sign * ex
                    across = grid.wrap({0: -1, 1: 0, 2: grid.nx}[xo], jj)[1]
                    table[r, q] = (slot, kk + 1, jj + 1, xo, int(across) + 1)
    return gather, scatter


def table_cells(grid: Grid, table: np.ndarray, rows: np.ndarray, q: int, i: np.ndarray):
    """The cell an AA table's entry q reads or writes for cells ``i`` of ``rows``.

    Returns
    -------
    (slot, z, y, x) : tuple of ndarray
        Padded coordinates, x wrapped into the interior (across an x face the
        row moves by the shift, as the kernels do).
    ii, jj : ndarray
        The cell's interior x and y.
    """
    slot, zs, ys, xo, across = (table[rows, q, c] for c in range(5))
    x = i + xo - 1
    crossed = (x < 0) | (x >= grid.nx)
    ys = np.where(crossed, across, ys)
    ii = x % grid.nx
    return (slot, zs, ys, ii + 1), ii, ys - 1


def aa_links(grid: Grid, gather: np.ndarray, scatter: np.ndarray) -> tuple[np.ndarray, ...]:
    """Pillar bounce-back copies around the odd AA step.

    Returns
    -------
    before : ndarray, shape (n, 4), int64
        Applied after the even step: a fluid node that will gather population q
        from a pillar cell s finds there its own f*_{opp q} (bounce-back), i.e.
        rows (slot, s, q, x) meaning ``g[slot].flat[s] = g[q].flat[x]``.
    after : ndarray, shape (m, 4), int64
        Applied after the odd step: what a fluid node pushed into a pillar cell
        comes back to it as opp(q): rows (opp q, x, slot, s).
    solid_cells : ndarray, shape (p,), int64
        Flat indices (one padded plane) of the pillar cells, reset after ``after``.
    Flat indices are into one padded (nz + 2, ny + 2, nx + 2) plane.
    """
    nyp, nxp = grid.ny + 2, grid.nx + 2
    fi, fj = np.nonzero(~grid.solid)
    before, after = [], []
    for k in range(grid.nz):
        rows = k * grid.ny + fj
        x_flat = ((k + 1) * nyp + (fj + 1)) * nxp + (fi + 1)
        for q in range(Q):
            for table, out in ((gather, before), (scatter, after)):
                (slot, zs, ys, xs), ii, jj = table_cells(grid, table, rows, q, fi)
                hit = grid.solid[ii, jj]
                if not hit.any():
                    continue
                s_flat = (zs[hit] * nyp + ys[hit]) * nxp + xs[hit]
                n = int(hit.sum())
                if out is before:
                    out.append(np.column_stack([slot[hit], s_flat, np.full(n, q), x_flat[hit]]))
                else:
                    out.append(
                        np.column_stack([np.full(n, OPP[q]), x_flat[hit], slot[hit], s_flat])
                    )
    _, solid_cells = boundary_links(grid)

    def stack(parts: list) -> np.ndarray:
        return np.concatenate(parts).astype(np.int64) if parts else np.zeros((0, 4), np.int64)

    return stack(before), stack(after), solid_cells
