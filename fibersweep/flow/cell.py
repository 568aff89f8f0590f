"""Steady flow in one unit cell of a tilted pillar array (shifted periodic boundaries).

The unit cell is a lattice (:class:`~fibersweep.flow.lattice.Grid`) stepped by
the channel's steppers (:mod:`fibersweep.flow.steppers`, AA in place by
default), collision and pillar-wall schemes (:mod:`fibersweep.flow.schemes`)
and time loop with its convergence test (:func:`fibersweep.flow.lbm.run_stepper`);
the free-slip midplane and the midplane IB average are the channel's too. Only
the boundaries of the box differ:

- across the flow (y): plain periodic, the cell is one lateral period λy;
- along the flow (x): *shifted* periodic. What leaves through the downstream
  face x = λx re-enters upstream at x = 0 moved down by the row shift
  s = ε λy, because the next row is the same cell moved by (λx, ε λy):
  u(x + λx, y + s) = u(x, y). The lattice's links across the face reach the
  node s cells away in y (:meth:`~fibersweep.flow.lattice.Grid.wrap`), so s
  must be a whole number of cells
  (:meth:`fibersweep.geometry.array.PillarArray.check_lattice` says so and
  proposes the nearest valid ε); there is no interpolation across the face.

Driving: a uniform body force along +x (the flow axis, normal to the rows), as
in the channel. In a periodic cell nothing forces the mean flow to be exactly
along x: it follows the cell's permeability tensor. By default
(``flow.array.mean_flow: x``) the cell is solved a second time with the force
along y (the kernels' turned frame, :data:`fibersweep.flow.lattice.FRAMES`) and
the two fields are combined so that the mean lateral velocity vanishes, as a
device's side walls make it; the field's ``meta["mean_flow_angle_deg"]`` says
what is left.

Start: the empty slit's plane Poiseuille profile across the depth, at rest in
the pillar and scaled by the open fraction, at equilibrium (no gradient term).

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
from dataclasses import asdict, dataclass

import numpy as np

from fibersweep.config.flow import FlowSettings
from fibersweep.errors import SolverError
from fibersweep.flow.cuts import Cuts, pillar_cuts
from fibersweep.flow.ghost import extend_into_wall
from fibersweep.flow.lattice import Grid
from fibersweep.flow.lbm import (
    DEFAULT_KERNEL,
    LatticeSolution,
    choose_tau,
    rates,
    run_stepper,
    wall_kind,
)
from fibersweep.flow.midplane import full_depth, midplane_average
from fibersweep.flow.schemes import get_wall_scheme
from fibersweep.flow.steppers import make_stepper
from fibersweep.geometry.array import PillarArray

__all__ = [
    "CELL_SOLVER_VERSION",
    "CellField",
    "CellSolve",
    "cell_grid",
    "cell_solution",
    "field_of",
    "first_streamline_width",
    "solve_block",
    "solve_cell",
]

log = logging.getLogger(__name__)

# 2: the channel's steppers (AA in place), collision schemes and time loop
CELL_SOLVER_VERSION = "cell-d3q19-2"


@dataclass(frozen=True)
class CellSolve:
    """A converged lattice solution of a cell or block.

    Attributes
    ----------
    u : ndarray, shape (3, nz, ny, nx)
        Lattice velocity [lattice units].
    grid : Grid
    shift_cells : int
        Row shift in cells (0 for a block).
    steps, seconds, residual, converged, tau :
        What the time loops did (steps and seconds summed over the solves).
    reports : tuple of SolveReport
        One per solve (force along x, then along y if the mean flow was set along x).
    """

    u: np.ndarray
    grid: Grid
    shift_cells: int
    steps: int
    seconds: float
    residual: float
    converged: bool
    tau: float
    reports: tuple = ()


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
    u3d : ndarray, shape (3, nz_full, ny, nx), optional
        The whole depth [µm/s], kept with ``flow.keep_3d``.
    """

    array: PillarArray
    ux: np.ndarray
    uy: np.ndarray
    dx: float
    meta: dict
    u3d: np.ndarray | None = None

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
def _box(shapes: list, nx: int, ny: int, settings: FlowSettings, closed: bool,
         shift: int) -> Grid:  # fmt: skip
    """A box periodic in y, x faces shifted by ``shift`` cells; ``shapes`` [µm] are solid."""
    dx = settings.dx
    x = (np.arange(nx) + 0.5) * dx
    y = (np.arange(ny) + 0.5) * dx
    X, Y = np.meshgrid(x, y, indexing="ij")
    solid = np.zeros((nx, ny), dtype=bool)
    for sh in shapes:
        solid |= sh.inside(X, Y, margin=1e-9 * dx) if closed else sh.inside(X, Y)
    nz_full = int(round(settings.array.depth / dx))
    nz = nz_full // 2 if settings.symmetry else nz_full
    return Grid(nx, ny, nz, nz_full, settings.symmetry, float(dx), solid, periodic_y=True,
                shift=shift)  # fmt: skip


def cell_grid(settings: FlowSettings) -> Grid:
    """The unit cell's lattice of ``settings`` (with ``array``; checked by the settings)."""
    array, dx = settings.array.to_array(), settings.dx
    closed = get_wall_scheme(settings.pillar_boundary).sub_grid
    nx, ny = int(round(array.period_x / dx)), int(round(array.period_y / dx))
    return _box([array.shape], nx, ny, settings, closed, array.check_lattice(dx))


def _solve(settings: FlowSettings, grid: Grid, cuts: Cuts | None, axis: int, kernel: str,
           threads: int | None) -> LatticeSolution:  # fmt: skip
    """Steady flow of ``grid`` driven along x (``axis`` 0) or y (1), from the slit's profile."""
    solve_rates = tau, omega_p, omega_m, force = rates(settings, grid)
    nu = (tau - 0.5) / 3.0
    h = grid.nz_full
    z = np.arange(grid.nz) + 0.5
    prof = force / (2.0 * nu) * z * (h - z)
    u0 = np.zeros((3, grid.nz, grid.ny, grid.nx))
    u0[axis] = prof[:, None, None] * (~grid.solid.T)[None, :, :] * (1.0 - grid.solid.mean())
    rho0 = np.zeros(u0.shape[1:])
    grad = np.zeros((3, 3, *u0.shape[1:]), dtype=np.float32)
    stepper = make_stepper(kernel, grid, u0, rho0, grad, force, omega_p, omega_m, cuts=cuts,
                           dtype=np.dtype(settings.precision), axis=axis)  # fmt: skip
    return run_stepper(settings, grid, stepper, solve_rates, wall_kind(grid, cuts), threads)


def cell_solution(settings: FlowSettings, axis: int = 0, *, kernel: str = DEFAULT_KERNEL,
                  threads: int | None = None) -> LatticeSolution:  # fmt: skip
    """The unit cell of ``settings`` driven by a body force along x (``axis`` 0) or y (1)."""
    grid = cell_grid(settings)
    cuts = pillar_cuts(grid, settings.array.to_array().shape, settings.pillar_boundary)
    return _solve(settings, grid, cuts, axis, kernel, threads)


def _cell_solve(u: np.ndarray, sols: list[LatticeSolution]) -> CellSolve:
    reports = tuple(s.report for s in sols)
    return CellSolve(
        u, sols[0].grid, sols[0].grid.shift, sum(r.steps for r in reports),
        sum(r.seconds for r in reports), max(r.residual for r in reports),
        all(r.converged for r in reports), reports[0].tau, reports,
    )  # fmt: skip


def solve_cell(settings: FlowSettings, *, kernel: str = DEFAULT_KERNEL,
               threads: int | None = None) -> CellSolve:  # fmt: skip
    """Steady lattice flow of the unit cell of ``settings`` (a FlowSettings with ``array``).

    With ``array.mean_flow == "x"`` (default) the mean flow is made to run
    exactly along x, as the side walls of a device make it: Stokes flow is
    linear in the body force, so the cell is solved with a force along x and
    with one along y, and the two fields are combined so that the mean lateral
    velocity is zero (one solve where the cell is mirror symmetric in y and not
    shifted: no lateral mean flow arises). With ``"force"`` the force is along
    x only and the mean flow takes the direction the cell's permeability gives
    it (reported by :func:`field_of`).

    ``kernel``: the stepper (:data:`fibersweep.flow.steppers.STEPPERS`);
    ``threads``: Numba threads (default as :func:`~fibersweep.flow.lbm.run_stepper`).
    """
    if settings.array is None:
        raise ValueError("solve_cell needs flow settings with an array")
    along = cell_solution(settings, 0, kernel=kernel, threads=threads)
    solid = along.grid.solid
    mirror = along.grid.shift == 0 and np.array_equal(solid, solid[:, ::-1])
    if settings.array.mean_flow == "force" or mirror:
        return _cell_solve(along.u, [along])
    across = cell_solution(settings, 1, kernel=kernel, threads=threads)
    alpha = -float(along.u[1].sum()) / float(across.u[1].sum())
    log.info("unit cell: lateral force %.4g x the axial one sets the mean flow along x", alpha)
    return _cell_solve(along.u + alpha * across.u, [along, across])


def solve_block(settings: FlowSettings, rows: int, axis: int = 0, *,
                kernel: str = DEFAULT_KERNEL) -> CellSolve:  # fmt: skip
    """Explicit block of ``rows`` rows (λx·rows × λy), plain periodic ends, staircase pillars.

    Validation of :func:`solve_cell` (with ``rows`` ε = 1 the block is periodic
    on its own): solved with the settings' collision, precision and
    convergence test, τ that of the unit cell, the body force along ``axis``.
    Staircase walls, because the block's pillars may straddle its lateral edge.
    """
    array = settings.array.to_array()
    tau = settings.tau if settings.tau is not None else choose_tau(cell_grid(settings))
    block = settings.model_copy(update={"tau": tau})
    nx = int(round(rows * array.period_x / settings.dx))
    ny = int(round(array.period_y / settings.dx))
    grid = _box(array.block_shapes(rows), nx, ny, block, closed=False, shift=0)
    sol = _solve(block, grid, None, axis, kernel, None)
    return _cell_solve(sol.u, [sol])


# ----------------------------------------------------------------- field
def field_of(settings: FlowSettings, sol: CellSolve) -> CellField:
    """Scale a cell solution to µm/s and build the :class:`CellField`.

    The depth-averaged superficial velocity becomes ⅔ ``fluid.u_center`` (the
    flux of an empty channel of that midplane speed); ``fluid.viscosity`` is
    kept with the field for the fibers that move in it.
    """
    array, grid = settings.array.to_array(), sol.grid
    # superficial velocity: flux through a face / (λy H), here the half depth
    ux_mean = float(sol.u[0].sum()) / (grid.nx * grid.ny * grid.nz)
    uy_mean = float(sol.u[1].sum()) / (grid.nx * grid.ny * grid.nz)
    if not (math.isfinite(ux_mean) and ux_mean > 0):
        raise SolverError(f"unit cell carries no flow (mean ux = {ux_mean!r})")
    u_center = settings.fluid.u_center
    scale = (2.0 / 3.0) * u_center / ux_mean
    ux, uy = midplane_average(sol.u, grid) * scale
    if get_wall_scheme(settings.pillar_boundary).sub_grid:
        ux, uy = extend_into_wall(ux, uy, grid.solid, array.shape, grid.dx)
    meta = {
        "solver_version": CELL_SOLVER_VERSION,
        "settings": settings.model_dump(mode="json"),
        "u_center": float(u_center),
        "viscosity": float(settings.fluid.viscosity),
        "shift_cells": sol.shift_cells,
        "steps": sol.steps,
        "seconds": sol.seconds,
        "residual": sol.residual,
        "converged": sol.converged,
        "tau": sol.tau,
        "reports": [{**asdict(r), "grid": list(r.grid)} for r in sol.reports],
        "scale_um_per_s_per_lattice": scale,
        "mean_flow_angle_deg": math.degrees(math.atan2(uy_mean, ux_mean)),
        "grid": [grid.nx, grid.ny, grid.nz, grid.nz_full],
    }
    u3d = full_depth(sol.u, grid) * scale if settings.keep_3d else None
    return CellField(array, np.ascontiguousarray(ux), np.ascontiguousarray(uy), grid.dx, meta,
                     u3d)  # fmt: skip


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
