"""Steady flow in one unit cell of a tilted pillar array (shifted periodic boundaries).

The lattice, collision, sub-grid pillar wall, free-slip midplane and the
midplane IB average are those of the single-pillar channel
(:mod:`fibersweep.flow.lbm`); only the boundaries of the box differ:

- across the flow (y): plain periodic, the cell is one lateral period λy;
- along the flow (x): *shifted* periodic. What leaves through the downstream
  face x = λx re-enters upstream at x = 0 moved down by the row shift
  s = ε λy, because the next row is the same cell moved by (λx, ε λy):
  u(x + λx, y + s) = u(x, y). The shift is applied by copying whole lattice
  columns into the ghost layer, so s must be a whole number of cells
  (:meth:`fibersweep.geometry.array.PillarArray.check_lattice` says so and
  proposes the nearest valid ε); there is no interpolation across the face.

Driving: a uniform body force along +x (the flow axis, normal to the rows), as
in the channel. In a periodic cell nothing forces the mean flow to be exactly
along x: it follows the cell's permeability tensor. For pillars symmetric
about the flow axis the off-axis part is tiny; the solver reports the measured
mean-flow angle (``meta["mean_flow_angle_deg"]``), and migration angles are
quoted from the x axis, the direction of the device's side walls.

Scale: Stokes flow is linear in the force, so the lattice field is rescaled
so that the depth-averaged superficial velocity (the flux through a row face
divided by λy H) is ⅔ u_center, i.e. the flux of an empty channel whose
midplane speed is u_center.

An explicit block of several rows with plain periodic ends (shift 0, length
n λx) is solved by the same code (:func:`solve_block`); it validates the
shifted boundary of the cell (tests/validation/test_array_flow.py).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass

import numba as nb
import numpy as np

from fibersweep.errors import InputError, SolverError
from fibersweep.flow import kernels
from fibersweep.flow.cuts import pillar_cuts
from fibersweep.flow.ghost import extend_into_wall
from fibersweep.flow.ibb import pull_interpolated
from fibersweep.flow.lattice import MIRROR_Z, OPP, E, Grid, Q, W
from fibersweep.flow.lbm import MACH_LIMIT
from fibersweep.flow.midplane import midplane_average
from fibersweep.geometry.array import ArrayError, PillarArray

__all__ = [
    "CELL_SOLVER_VERSION",
    "CellField",
    "CellSolve",
    "first_streamline_width",
    "solve_cell",
    "solve_block",
]

log = logging.getLogger(__name__)

CELL_SOLVER_VERSION = "cell-d3q19-trt-guo-1"
U_LATTICE = 1e-5
EDGE_CELLS = 4  # cells between an interpolated pillar wall and the cell's edges (its stencil)


@dataclass(frozen=True)
class CellSolve:
    """A converged lattice solution of a cell or block.

    Attributes
    ----------
    u : ndarray, shape (3, nz, ny, nx)
        Lattice velocity (force fx) [lattice units].
    grid : Grid
    shift_cells : int
        Row shift in cells (0 for a block).
    steps, seconds, residual, converged, tau :
        What the time loop did.
    """

    u: np.ndarray
    grid: Grid
    shift_cells: int
    steps: int
    seconds: float
    residual: float
    converged: bool
    tau: float


@dataclass(frozen=True)
class CellField:
    """Midplane velocity of one unit cell, scaled to µm/s.

    Attributes
    ----------
    array : PillarArray
    ux, uy : ndarray, shape (nx, ny)
        Midplane (IB z-averaged) velocity at nodes ((i + ½) Δx, (j + ½) Δx) [µm/s];
        ghost values inside the pillar near a sub-grid wall (as the channel's field).
    dx : float
    meta : dict
        Settings, solver report, scale, mean-flow angle.
    """

    array: PillarArray
    ux: np.ndarray
    uy: np.ndarray
    dx: float
    meta: dict

    def extended(self, pad: int = 3) -> tuple[np.ndarray, np.ndarray]:
        """(ux, uy) padded by ``pad`` nodes on every side with their periodic images.

        Node (i, j) of the result is cell node (i − pad, j − pad); the x padding
        applies the row shift. The fiber tracker interpolates in this array with
        the plain IB kernel (:func:`fibersweep.flow.field.interpolate_ib`).
        """
        s = int(self.meta["shift_cells"])
        return (_pad(self.ux, pad, s), _pad(self.uy, pad, s))

    @property
    def u_center(self) -> float:
        """Midplane speed of the same flux in an empty channel [µm/s] (the field's scale)."""
        return float(self.meta["u_center"])

    @property
    def viscosity(self) -> float:
        """Dynamic viscosity [Pa s = pN s/µm²]."""
        return float(self.meta["viscosity"])


def _pad(a: np.ndarray, pad: int, s: int) -> np.ndarray:
    nx, ny = a.shape
    i = np.arange(-pad, nx + pad)
    j = np.arange(-pad, ny + pad)
    row = np.floor_divide(i, nx)  # cell node i − row nx holds u at (i, j + row s)
    ii = i - row * nx
    jj = (j[None, :] + row[:, None] * s) % ny
    return np.ascontiguousarray(a[ii[:, None], jj])


# ----------------------------------------------------------------- lattice
def cell_grid(shapes: list, nx: int, ny: int, nz_full: int, dx: float, symmetry: bool,
              closed: bool) -> Grid:  # fmt: skip
    """Grid of a periodic box with the union of ``shapes`` [µm] solid."""
    x = (np.arange(nx) + 0.5) * dx
    y = (np.arange(ny) + 0.5) * dx
    X, Y = np.meshgrid(x, y, indexing="ij")
    solid = np.zeros((nx, ny), dtype=bool)
    for sh in shapes:
        solid |= sh.inside(X, Y, margin=1e-9 * dx) if closed else sh.inside(X, Y)
    nz = nz_full // 2 if symmetry else nz_full
    return Grid(nx, ny, nz, nz_full, symmetry, float(dx), solid)


def periodic_sources(grid: Grid) -> np.ndarray:
    """Pull table (as :func:`fibersweep.flow.lattice.pull_sources`) with y periodic.

    Sources across y = 0 or y = λy read the ghost rows, which
    :func:`fill_ghosts` keeps equal to the opposite interior rows; the bottom
    wall bounces back, the top is the specular midplane (or a wall).
    """
    out = np.zeros((grid.nz * grid.ny, Q, 4), dtype=np.int64)
    for k in range(grid.nz):
        for j in range(grid.ny):
            r = k * grid.ny + j
            for q in range(Q):
                ex, ey, ez = (int(v) for v in E[q])
                ks, js = k - ez, j - ey
                if ks < 0 or (ks >= grid.nz and not grid.symmetry):
                    out[r, q] = (OPP[q], k + 1, j + 1, 1)
                elif ks >= grid.nz:
                    out[r, q] = (MIRROR_Z[q], k + 1, js + 1, 1 - ex)
                else:
                    out[r, q] = (q, ks + 1, js + 1, 1 - ex)
    return out


def periodic_links(grid: Grid) -> tuple[np.ndarray, np.ndarray]:
    """Half-way bounce-back rows of a staircase pillar (as ``boundary_links``), y wrapped.

    Returns (links (n, 4), solid_cells (m,)) in the layout of
    :func:`fibersweep.kernels.fill_pillar`; targets across y = 0 or λy wrap
    to the other side (the value then reaches the ghost row through
    :func:`fill_ghosts`).
    """
    nyp, nxp = grid.ny + 2, grid.nx + 2
    si, sj = np.nonzero(grid.solid)
    rows, cells = [], []
    for k in range(grid.nz):
        base = ((k + 1) * nyp + (sj + 1)) * nxp + (si + 1)
        cells.append(base)
        targets = [(q, q, k + int(E[q][2])) for q in range(1, Q)]
        if grid.symmetry and k == grid.nz - 1:  # the top row pulls e_z < 0 specularly
            targets += [(MIRROR_Z[q], q, k) for q in range(1, Q) if E[q][2] < 0]
        for slot, q, kt in targets:
            if not 0 <= kt < grid.nz:
                continue
            it = (si + int(E[q][0])) % grid.nx
            jt = (sj + int(E[q][1])) % grid.ny
            ok = ~grid.solid[it, jt]
            src = ((kt + 1) * nyp + (jt[ok] + 1)) * nxp + (it[ok] + 1)
            n = int(ok.sum())
            rows.append(np.column_stack([np.full(n, slot), base[ok], np.full(n, OPP[q]), src]))
    links = np.concatenate(rows).astype(np.int64) if rows else np.zeros((0, 4), np.int64)
    return links, np.concatenate(cells).astype(np.int64)


@nb.njit(cache=True)
def fill_ghosts(g: np.ndarray, s: int, t: int) -> None:
    """Ghost columns and rows of a shifted periodic box (one of ``s``, ``t`` is 0).

    ``s``: shift of the x faces in y [cells], u(−1, j) = u(nx − 1, j + s) and
    u(nx, j) = u(0, j − s); ``t``: shift of the y faces in x [cells],
    u(i, −1) = u(i + t, ny − 1) and u(i, ny) = u(i − t, 0) (indices modulo the
    box). Columns are filled first, then whole rows, so the corners come out right.
    """
    nq, nzp, nyp, nxp = g.shape
    nx = nxp - 2
    ny = nyp - 2
    for q in range(nq):
        for z in range(1, nzp - 1):
            for j in range(ny):
                g[q, z, j + 1, 0] = g[q, z, (j + s) % ny + 1, nx]
                g[q, z, j + 1, nx + 1] = g[q, z, (j - s) % ny + 1, 1]
            for i in range(nxp):
                if t == 0:  # whole padded rows: the shifted ghost columns come along
                    g[q, z, 0, i] = g[q, z, ny, i]
                    g[q, z, ny + 1, i] = g[q, z, 1, i]
                else:  # s == 0: x is plainly periodic, wrap the interior
                    g[q, z, 0, i] = g[q, z, ny, (i - 1 + t) % nx + 1]
                    g[q, z, ny + 1, i] = g[q, z, 1, (i - 1 - t) % nx + 1]


class CellStepper:
    """Two-array pull-stream-collide on a periodic box with a shifted x boundary."""

    def __init__(self, grid: Grid, shift: int, u0: np.ndarray, fx: float, omega_p: float,
                 omega_m: float, cuts=None, dtype=np.float32, shift_y: int = 0):  # fmt: skip
        self.fx, self.omega_p, self.omega_m = fx, omega_p, omega_m
        self.shift, self.shift_y = int(shift), int(shift_y)
        self.sources = periodic_sources(grid)
        self.links, self.solid_cells = periodic_links(grid)
        self.table = None
        if cuts is not None:
            self.table = pull_interpolated(grid, cuts, self.sources, omega_p, omega_m)
            self.buf = np.zeros(self.table.dst.size)
        self.e = tuple(np.ascontiguousarray(E[:, k]) for k in range(3))
        self.g = np.zeros(grid.padded_shape, dtype=dtype)
        self.gn = np.zeros_like(self.g)
        grad = np.zeros((3, 3, *u0.shape[1:]), dtype=np.float32)
        rho0 = np.zeros(u0.shape[1:])
        kernels.init_populations(self.g, u0, rho0, grad, omega_p, True, W, *self.e)
        self._fill(self.g)

    def _fill(self, g: np.ndarray) -> None:
        if self.table is None:
            kernels.fill_pillar(g, self.solid_cells, self.links)
        else:
            t = self.table
            kernels.apply_interpolated(g, t.dst, t.src, t.coef, self.buf, self.solid_cells)
        fill_ghosts(g, self.shift, self.shift_y)

    def advance(self, n: int) -> None:
        for _ in range(n):
            kernels.stream_collide(
                self.g, self.gn, self.sources, self.fx, self.omega_p, self.omega_m
            )
            self._fill(self.gn)
            self.g, self.gn = self.gn, self.g

    def moments(self, out: np.ndarray) -> None:
        kernels.moments(self.g, self.sources, self.fx, *self.e, out)


# ----------------------------------------------------------------- solve
def _solve(grid: Grid, shift: int, cuts, tau: float, tolerance: float, max_steps: int,
           check_every: int, dtype, shift_y: int = 0) -> CellSolve:  # fmt: skip
    nu = (tau - 0.5) / 3.0
    h = grid.nz_full
    fx = 8.0 * nu * U_LATTICE / h**2  # plane Poiseuille centre speed U_LATTICE
    omega_p = 1.0 / tau
    omega_m = 1.0 / (3.0 / 16.0 / (tau - 0.5) + 0.5)  # TRT, magic 3/16
    z = np.arange(grid.nz) + 0.5
    prof = fx / (2.0 * nu) * z * (h - z)
    u0 = np.zeros((3, grid.nz, grid.ny, grid.nx))
    u0[0] = prof[:, None, None] * (~grid.solid.T)[None, :, :] * (1.0 - grid.solid.mean())
    st = CellStepper(grid, shift, u0, fx, omega_p, omega_m, cuts, dtype, shift_y)
    fluid = ~grid.solid.T[None, :, :]
    mom = np.zeros((4, grid.nz, grid.ny, grid.nx))
    st.moments(mom)
    prev = mom[1:3] * fluid
    steps, residual, t0 = 0, math.inf, time.perf_counter()
    while steps < max_steps:
        st.advance(check_every)
        steps += check_every
        st.moments(mom)
        u = mom[1:3] * fluid
        vmax = float(np.abs(u).max())
        if not math.isfinite(vmax) or vmax > MACH_LIMIT:
            raise SolverError(f"unit-cell LBM diverged after {steps} steps (|u| = {vmax:.3g})")
        residual = float(np.linalg.norm(u - prev) / max(np.linalg.norm(u), 1e-300))
        prev = u
        if residual < tolerance:
            break
    seconds = time.perf_counter() - t0
    converged = residual < tolerance
    if not converged:
        log.warning("unit cell not converged after %d steps (residual %.2e)", steps, residual)
    log.info("unit cell: %d steps, %.1f s, residual %.1e", steps, seconds, residual)
    return CellSolve(mom[1:4] * fluid, grid, shift, steps, seconds, residual, converged, tau)


def _tau(grid: Grid) -> float:
    """Relaxation time with critically damped pressure waves (as choose_tau), in [0.6, 1.5]."""
    k_min = 2.0 * math.pi / max(grid.nx, grid.ny)
    nu = 2.0 * k_min / math.sqrt(3.0) * grid.nz_full**2 / 12.0
    return float(min(max(3.0 * nu + 0.5, 0.6), 1.5))


def solve_cell(array: PillarArray, dx: float, *, boundary: str = "interpolated",
               symmetry: bool = True, tolerance: float = 1e-6, max_steps: int = 200_000,
               check_every: int = 100, tau: float | None = None,
               precision: str = "float32", mean_flow: str = "x") -> CellSolve:  # fmt: skip
    """Steady lattice flow of one unit cell.

    With ``mean_flow="x"`` (default) the mean flow is made to run exactly along
    x, as the side walls of a device make it: Stokes flow is linear in the
    body force, so the cell is solved twice, with a force along x and (on the
    transposed cell, whose y faces carry the shift) a force along y, and the
    two fields are combined so that the mean lateral velocity is zero. With
    ``mean_flow="force"`` the force is along x only and the mean flow takes
    the direction the cell's permeability gives it (reported by :func:`field_of`).

    Parameters
    ----------
    array : PillarArray
    dx : float
        Lattice spacing [µm]; λx, λy, H and ε λy must be whole multiples.
    boundary : {"interpolated", "staircase", "bfl"}
        Pillar wall (as ``flow.pillar_boundary``).
    symmetry : bool
        Half depth with the free-slip midplane.
    tolerance, max_steps, check_every, tau, precision :
        As :class:`fibersweep.flow.settings.FlowSettings`.
    mean_flow : {"x", "force"}
        What sets the mean flow direction (above).

    Raises
    ------
    InputError
        Lengths or shift not whole in cells, too few depth nodes, or an
        interpolated wall closer than ``EDGE_CELLS`` cells to the cell's edge.
    """
    try:
        shift = array.check_lattice(dx)
    except ArrayError as exc:
        raise InputError(f"array.{exc.field}: {exc}") from None
    nz_full = int(round(array.depth / dx))
    if nz_full < 8 or (symmetry and nz_full % 2):
        raise InputError(
            f"flow.dx: dx = {dx} µm gives {nz_full} nodes across the depth; at least 8 "
            "(an even number with the symmetry plane) are needed"
        )
    nx, ny = int(round(array.period_x / dx)), int(round(array.period_y / dx))
    closed = boundary != "staircase"
    grid = cell_grid([array.shape], nx, ny, nz_full, dx, symmetry, closed)
    x0, y0, x1, y1 = array.shape.bounds
    edge = min(x0, y0, array.period_x - x1, array.period_y - y1) / dx
    if closed and edge < EDGE_CELLS:
        raise InputError(
            f"flow.dx: the pillar is {edge:.1f} cells from the unit cell's edge; the sub-grid "
            f"wall needs {EDGE_CELLS} (refine dx, or widen the gaps)"
        )
    if mean_flow not in ("x", "force"):
        raise InputError(f"flow.mean_flow: {mean_flow!r} is not one of 'x', 'force'")
    cuts = pillar_cuts(grid, array.shape, boundary)
    tau = tau or _tau(grid)
    along = _solve(grid, shift, cuts, tau, tolerance, max_steps, check_every, np.dtype(precision))
    if mean_flow == "force" or shift == 0 and _mirror_symmetric(grid):
        return along
    # the transposed cell (x <-> y): its x faces are plain periodic, its y faces
    # carry the shift, and its force along its x is a force along our y
    shape_t = _transposed(array.shape)
    grid_t = cell_grid([shape_t], ny, nx, nz_full, dx, symmetry, closed)
    cuts_t = pillar_cuts(grid_t, shape_t, boundary)
    across = _solve(grid_t, 0, cuts_t, tau, tolerance, max_steps, check_every,
                    np.dtype(precision), shift_y=shift)  # fmt: skip
    u_y = np.swapaxes(across.u, 2, 3)[[1, 0, 2]]  # back to (ux, uy, uz)[z, y, x]
    alpha = -float(along.u[1].sum()) / float(u_y[1].sum())
    u = along.u + alpha * u_y
    log.info("unit cell: lateral force %.4g x the axial one sets the mean flow along x", alpha)
    return CellSolve(u, grid, shift, along.steps + across.steps,
                     along.seconds + across.seconds, max(along.residual, across.residual),
                     along.converged and across.converged, tau)  # fmt: skip


def _mirror_symmetric(grid: Grid) -> bool:
    """True if the solid mask is symmetric under y -> −y (no lateral mean flow possible)."""
    return bool(np.array_equal(grid.solid, grid.solid[:, ::-1]))


def _transposed(shape):
    """``shape`` mirrored across the line y = x [µm]."""
    from fibersweep.geometry import Circle, ConvexPolygon

    if isinstance(shape, Circle):
        return Circle(shape.cy, shape.cx, shape.radius)
    return ConvexPolygon.from_vertices(shape.vertices[:, ::-1])


def solve_block(array: PillarArray, dx: float, rows: int, *, symmetry: bool = True,
                tolerance: float = 1e-7, max_steps: int = 200_000,
                tau: float | None = None) -> CellSolve:  # fmt: skip
    """Explicit block of ``rows`` rows (λx·rows × λy), plain periodic ends, staircase pillars.

    With ``rows`` ε = 1 the block is periodic on its own; validation of
    :func:`solve_cell` (run with ``boundary="staircase"`` and the same τ).
    """
    array.check_lattice(dx)
    nz_full = int(round(array.depth / dx))
    nx, ny = int(round(rows * array.period_x / dx)), int(round(array.period_y / dx))
    grid = cell_grid(array.block_shapes(rows), nx, ny, nz_full, dx, symmetry, closed=False)
    t = tau or _tau(cell_grid([array.shape], nx // rows, ny, nz_full, dx, symmetry, False))
    return _solve(grid, 0, None, t, tolerance, max_steps, 100, np.float64)


# ----------------------------------------------------------------- field
def field_of(array: PillarArray, sol: CellSolve, u_center: float, boundary: str,
             settings: dict | None = None, viscosity: float = 0.340) -> CellField:  # fmt: skip
    """Scale a cell solution to µm/s and build the :class:`CellField`.

    ``u_center`` [µm/s]: midplane speed of the same flux in an empty channel (the
    depth-averaged superficial velocity is ⅔ of it); ``viscosity`` [Pa s] is kept
    with the field for the fibers that move in it.
    """
    grid = sol.grid
    # superficial velocity: flux through a face / (λy H), here the half depth
    ux_mean = float(sol.u[0].sum()) / (grid.nx * grid.ny * grid.nz)
    uy_mean = float(sol.u[1].sum()) / (grid.nx * grid.ny * grid.nz)
    if not (math.isfinite(ux_mean) and ux_mean > 0):
        raise SolverError(f"unit cell carries no flow (mean ux = {ux_mean!r})")
    scale = (2.0 / 3.0) * u_center / ux_mean
    ux, uy = midplane_average(sol.u, grid) * scale
    if boundary != "staircase":
        ux, uy = extend_into_wall(ux, uy, grid.solid, array.shape, grid.dx)
    meta = {
        "solver_version": CELL_SOLVER_VERSION,
        "settings": settings or {},
        "u_center": float(u_center),
        "viscosity": float(viscosity),
        "shift_cells": sol.shift_cells,
        "steps": sol.steps,
        "seconds": sol.seconds,
        "residual": sol.residual,
        "converged": sol.converged,
        "tau": sol.tau,
        "scale_um_per_s_per_lattice": scale,
        "mean_flow_angle_deg": math.degrees(math.atan2(uy_mean, ux_mean)),
        "grid": [grid.nx, grid.ny, grid.nz, grid.nz_full],
    }
    return CellField(array, np.ascontiguousarray(ux), np.ascontiguousarray(uy), grid.dx, meta)


def first_streamline_width(array: PillarArray, u: np.ndarray, dx: float) -> tuple[float, float]:
    """(β, G) [µm]: width of the first streamline next to a pillar, and the gap.

    From the depth-integrated velocity across the gap above the pillar, at the x
    of its highest point: ∫_0^β ū dy = ε ∫_0^G ū dy (y from the pillar's top),
    the flux a row hands to the next one. ``u``: a cell solution's velocity
    (3, nz, ny, nx) (:attr:`CellSolve.u`), any scale.
    """
    _, _, _, y1 = array.shape.bounds
    outline = array.shape.outline(720)
    x_top = outline[np.argmax(outline[:, 1]), 0]
    prof = u[0].sum(axis=0)[:, int(x_top / dx)]
    y = (np.arange(prof.size) + 0.5) * dx
    gap = array.gap
    d = (y - y1) % array.period_y
    inside = d < gap
    order = np.argsort(d[inside])
    p = prof[inside][order]
    ds = d[inside][order]
    edges = np.concatenate([[0.0], 0.5 * (ds[1:] + ds[:-1]), [gap]])
    q = np.concatenate([[0.0], np.cumsum(p * np.diff(edges))])
    return float(np.interp(array.shift * q[-1], q, edges)), float(gap)
