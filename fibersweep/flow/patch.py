"""A finer grid around the pillar, nested one way in the channel's steady solution.

Far from the pillar the flow is Hele-Shaw flow with the channel's parabolic depth
profile; the pillar's 3D disturbance decays over a few channel depths. So the
whole channel is solved at ``settings.dx`` and only a box around the pillar
(the *patch*, ``settings.patch``) at the finer ``patch.dx``:

* the patch is the pillar's bounding box grown by ``patch.margin`` and rounded
  out to whole channel cells, over the full depth, so its nodes sit exactly where
  a full fine grid's would (the same sub-cell placement of the pillar);
* its outermost ring of nodes (the *frame*) is held, every step, at the
  post-collision populations of the channel solution there: equilibrium of
  (δρ, u) plus the Chapman-Enskog non-equilibrium part from the velocity
  gradient (:func:`fibersweep.flow.kernels.init_populations`). In-plane the
  channel solution is interpolated bilinearly, in depth its profile is fitted by
  the Poiseuille parabola (exact at the frame up to the decayed disturbance and
  the channel grid's error), pressures scale with force times nodes;
* Stokes flow is steady and linear, so nothing flows back: the frame must sit
  where the fine solution would not change the coarse one (the patch-size study
  in docs/fidelity.md measures how far that is);
* the stored field is the whole channel at ``patch.dx``: the patch's midplane
  field inside the box, the channel's field interpolated bilinearly outside
  (rescaled for the thinner layer the finer grid's midplane average spans,
  :func:`depth_factor`).
  Fibers and the separatrix analysis read it like any single-grid field.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time

import numpy as np
from scipy.ndimage import map_coordinates

from fibersweep.config.flow import FlowSettings
from fibersweep.flow.channel_field import field_from_solution
from fibersweep.flow.cuts import pillar_cuts
from fibersweep.flow.field import FlowField
from fibersweep.flow.ghost import GHOST_METHOD, extend_into_wall
from fibersweep.flow.initial import velocity_gradient
from fibersweep.flow.kernels import stream_collide
from fibersweep.flow.lattice import E, Grid, W, make_grid
from fibersweep.flow.lbm import (
    SOLVER_VERSION,
    LatticeSolution,
    lattice_of,
    rates,
    run_stepper,
    solve_nested,
    wall_kind,
)
from fibersweep.flow.midplane import midplane_average, midplane_weights
from fibersweep.flow.schemes import get_wall_scheme
from fibersweep.flow.steppers import PullStepper
from fibersweep.geometry import Geometry
from fibersweep.version import __version__

__all__ = ["PatchBox", "patch_box", "PatchStepper", "solve_patched", "compose", "depth_factor"]

log = logging.getLogger(__name__)

PATCH_METHOD = "one-way-frame-2"  # in the cache key of patched fields: change with the nesting


@dataclasses.dataclass(frozen=True)
class PatchBox:
    """Where the patch sits: x0, y0 [µm] of its lower-left corner and its node counts.

    x0 and y0 are whole multiples of the channel spacing; the patch's node (i, j)
    is at (x0 + (i + 1/2) dx_f, y0 + (j + 1/2) dx_f).
    """

    x0: float
    y0: float
    nx: int
    ny: int
    dx: float

    @property
    def i0(self) -> int:
        """Index of the patch's first column on the whole fine channel grid."""
        return int(round(self.x0 / self.dx))

    @property
    def j0(self) -> int:
        """Index of the patch's first row on the whole fine channel grid."""
        return int(round(self.y0 / self.dx))


def patch_box(settings: FlowSettings) -> PatchBox:
    """The patch of ``settings`` (pillar bounds + margin, out to whole channel cells).

    Clipped to the channel walls in y; a patch that would reach the periodic ends
    in x is refused (use the single fine grid then).
    """
    if settings.patch is None:
        raise ValueError("settings.patch is None: no patch to place")
    geom = settings.geometry.to_geometry()
    dc, df, m = settings.dx, settings.patch.dx, settings.patch.margin
    bx0, by0, bx1, by1 = geom.shape.bounds
    x0 = math.floor((bx0 - m) / dc) * dc
    x1 = math.ceil((bx1 + m) / dc) * dc
    y0 = max(0.0, math.floor((by0 - m) / dc) * dc)
    y1 = min(geom.width, math.ceil((by1 + m) / dc) * dc)
    if x0 <= 0.0 or x1 >= geom.length:
        raise ValueError(
            f"patch.margin = {m} µm makes the patch span x in [{x0:g}, {x1:g}] µm, beyond the "
            f"periodic channel [0, {geom.length:g}]; use a smaller margin"
        )
    return PatchBox(x0, y0, int(round((x1 - x0) / df)), int(round((y1 - y0) / df)), df)


def patch_geometry(geom: Geometry, box: PatchBox) -> Geometry:
    """The channel cut to the patch, the pillar at the same place relative to its nodes."""
    xc, yb = geom.base_center
    return dataclasses.replace(
        geom,
        width=box.ny * box.dx,
        length=box.nx * box.dx,
        pillar_x=xc - box.x0,
        pillar_y_base=yb - box.y0,
    )


def _pad2(a: np.ndarray, sign_y: float) -> np.ndarray:
    """Pad (..., ny, nx) with one ghost layer: periodic in x, sign_y times the mirror in y."""
    a = np.concatenate([a[..., -1:], a, a[..., :1]], axis=-1)
    return np.concatenate([sign_y * a[..., :1, :], a, sign_y * a[..., -1:, :]], axis=-2)


def _bilinear(plane: np.ndarray, dc: float, xs: np.ndarray, ys: np.ndarray, sign_y: float):
    """Bilinear values of a (ny_c, nx_c) node plane at the tensor points (ys x xs) [µm]."""
    padded = _pad2(plane, sign_y)
    gy = ys / dc - 0.5 + 1.0
    gx = xs / dc - 0.5 + 1.0
    Y, X = np.meshgrid(gy, gx, indexing="ij")
    return map_coordinates(padded, [Y.ravel(), X.ravel()], order=1, mode="nearest").reshape(Y.shape)


def boundary_field(
    coarse: LatticeSolution, box: PatchBox, fine_nz: int, density_scale: float, ring: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """The channel solution on the patch's nodes (grown by ``ring`` nodes on each side).

    Parameters
    ----------
    coarse : LatticeSolution
        Channel solution in lattice units.
    box : PatchBox
    fine_nz : int
        Solved depth nodes of the patch.
    density_scale : float
        Factor from channel to patch density deviations (force x nodes).
    ring : int
        Extra nodes on each side in x and y.

    Returns
    -------
    u : ndarray, shape (3, fine_nz, ny + 2 ring, nx + 2 ring)
        Lattice velocity: in-plane bilinear, in depth the least-squares Poiseuille
        parabola through the channel's nodes; u_z = 0.
    drho : ndarray, shape (fine_nz, ny + 2 ring, nx + 2 ring)
        Depth-averaged channel δρ, bilinear, times ``density_scale``.
    """
    g = coarse.grid
    dc, df = g.dx, box.dx
    depth = g.nz_full * dc
    xs = box.x0 + (np.arange(-ring, box.nx + ring) + 0.5) * df
    ys = box.y0 + (np.arange(-ring, box.ny + ring) + 0.5) * df
    zc = (np.arange(g.nz) + 0.5) * dc
    pc = zc * (depth - zc)
    zf = (np.arange(fine_nz) + 0.5) * df
    pf = zf * (depth - zf)
    u = np.zeros((3, fine_nz, ys.size, xs.size))
    for c in range(2):
        amp = sum(pc[k] * _bilinear(coarse.u[c, k], dc, xs, ys, -1.0) for k in range(g.nz))
        amp /= float(np.sum(pc**2))
        u[c] = amp[None] * pf[:, None, None]
    rho2 = coarse.rho.mean(axis=0)
    drho = _bilinear(rho2, dc, xs, ys, 1.0) * density_scale
    return u, np.broadcast_to(drho, (fine_nz, *drho.shape)).copy()


class PatchStepper(PullStepper):
    """The pull stepper with the frame (outermost ring of nodes) held at fixed populations.

    The frame's populations are those it starts with (the channel solution, plus
    the half force the collision leaves in the momentum), so interior nodes next
    to it pull the channel's populations every step. ``args`` as for
    :class:`PullStepper`: (u0, rho0, grad, fx, omega_p, omega_m).
    """

    def __init__(self, grid: Grid, *args, **kwargs):
        super().__init__(grid, *args, **kwargs)
        nx, ny = grid.nx, grid.ny
        self.frame = (
            (slice(None), slice(1, -1), slice(1, -1), 1),
            (slice(None), slice(1, -1), slice(1, -1), nx),
            (slice(None), slice(1, -1), 1, slice(1, -1)),
            (slice(None), slice(1, -1), ny, slice(1, -1)),
        )
        # init_populations carries momentum ρu; after a collision with the Guo force the
        # populations carry ρu + F/2 (the odd part of the force term): add it
        fx = args[3]
        shift = (1.5 * fx * W * E[:, 0]).astype(self.g.dtype)[:, None, None]
        held = []
        for s in self.frame:
            v = self.g[s].copy()
            v += shift
            held.append(v)
        self.held = tuple(held)

    def _pin(self, g: np.ndarray) -> None:
        for s, v in zip(self.frame, self.held, strict=True):
            g[s] = v

    def advance(self, n: int) -> None:
        """n steps, the frame reset after each."""
        for _ in range(n):
            stream_collide(
                self.g, self.gn, self.pull, self.slots, self.fx, self.omega_p, self.omega_m
            )
            self._fill(self.gn)
            self._pin(self.gn)
            self.g, self.gn = self.gn, self.g


def solve_patch_lattice(
    settings: FlowSettings, coarse: LatticeSolution, threads: int | None = None
) -> tuple[LatticeSolution, PatchBox, Geometry]:
    """Solve the patch of ``settings`` nested in the channel solution ``coarse``.

    Returns the patch's lattice solution (lattice velocity in the channel's
    lattice units, the same U_LATTICE), its box and its geometry.
    """
    box = patch_box(settings)
    geom = settings.geometry.to_geometry()
    pgeom = patch_geometry(geom, box)
    fine = settings.model_copy(update={"dx": box.dx, "patch": None})
    full_fine = lattice_of(fine, pillar=False)  # τ and force as the whole fine grid's
    _, omega_p, omega_m, fx = fine_rates = rates(fine, full_fine)
    grid = make_grid(
        pgeom, box.dx, settings.symmetry, closed=get_wall_scheme(settings.pillar_boundary).sub_grid
    )
    cuts = pillar_cuts(grid, pgeom.shape, settings.pillar_boundary)
    density_scale = fx / coarse.report.force * (coarse.grid.dx / box.dx)
    u_ext, rho_ext = boundary_field(coarse, box, grid.nz, density_scale, ring=1)
    solid_t = grid.solid.T
    u_ext[:, :, 1:-1, 1:-1][:, :, solid_t] = 0.0
    ext = Grid(grid.nx + 2, grid.ny + 2, grid.nz, grid.nz_full, grid.symmetry, grid.dx,
               np.zeros((grid.nx + 2, grid.ny + 2), dtype=bool))  # fmt: skip
    grad = np.ascontiguousarray(velocity_gradient(u_ext, ext)[:, :, :, 1:-1, 1:-1])
    u0 = np.ascontiguousarray(u_ext[:, :, 1:-1, 1:-1])
    rho0 = np.ascontiguousarray(rho_ext[:, 1:-1, 1:-1])
    del u_ext, rho_ext
    stepper = PatchStepper(grid, u0, rho0, grad, fx, omega_p, omega_m, cuts=cuts,
                           dtype=np.dtype(settings.precision))  # fmt: skip
    del u0, rho0, grad
    sol = run_stepper(fine, grid, stepper, fine_rates, wall_kind(grid, cuts), threads)
    return sol, box, pgeom


def depth_factor(grid: Grid) -> float:
    """IB z-average of the Poiseuille parabola on ``grid`` over its midplane value.

    The midplane field is the IB-kernel average over a few nodes around z = H/2, so
    a coarser grid averages over a thicker layer (0.978 at 10 nodes across the
    depth, 0.995 at 20): the channel's field is rescaled by the ratio of the two
    factors outside the patch so that it joins the patch's without a step.
    """
    depth = grid.nz_full
    par = lambda k: (k + 0.5) * (depth - k - 0.5)  # noqa: E731
    return sum(w * par(k) for k, w in midplane_weights(grid)) / (depth / 2.0) ** 2


def compose(
    coarse_field: FlowField,
    patch_ux: np.ndarray,
    patch_uy: np.ndarray,
    patch_solid,
    box: PatchBox,
    outside_scale: float = 1.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The whole channel at the patch spacing: the patch inside its box, the channel outside.

    The patch's outermost ring (held at the channel's populations, its own
    moments meaningless) takes the channel's values too.

    Parameters
    ----------
    coarse_field : FlowField
        Channel midplane field [µm/s] at spacing dx_c.
    patch_ux, patch_uy, patch_solid : ndarray, shape (box.nx, box.ny)
        The patch's midplane field [µm/s] and its solid nodes.
    box : PatchBox
    outside_scale : float
        Factor on the channel's field (:func:`depth_factor` of the patch over the channel's).

    Returns
    -------
    ux, uy : ndarray, shape (L_ch / dx_f, W_ch / dx_f), float64
    solid : ndarray of bool, same shape
    """
    geom = coarse_field.geometry
    df = box.dx
    nx, ny = int(round(geom.length / df)), int(round(geom.width / df))
    xs = (np.arange(nx) + 0.5) * df
    ys = (np.arange(ny) + 0.5) * df
    out = []
    # the patch's frame ring is held at the channel's values: the channel's field stands there
    inner = (slice(box.i0 + 1, box.i0 + box.nx - 1), slice(box.j0 + 1, box.j0 + box.ny - 1))
    for comp, patch in ((coarse_field.ux, patch_ux), (coarse_field.uy, patch_uy)):
        full = _bilinear(np.asarray(comp, dtype=np.float64).T, coarse_field.dx, xs, ys, -1.0).T
        full *= outside_scale
        full[inner] = patch[1:-1, 1:-1]
        out.append(np.ascontiguousarray(full))
    solid = np.zeros((nx, ny), dtype=bool)
    solid[box.i0 : box.i0 + box.nx, box.j0 : box.j0 + box.ny] = patch_solid
    return out[0], out[1], solid


def solve_patched(
    settings: FlowSettings, threads: int | None = None, coarse: LatticeSolution | None = None
) -> FlowField:
    """The channel at ``settings.dx`` with the patch at ``settings.patch.dx`` nested in it.

    ``coarse``: the channel's lattice solution if already solved (studies reuse one
    for several patch sizes); by default it is solved here.

    Returns
    -------
    FlowField
        At spacing ``patch.dx`` over the whole channel (see :func:`compose`);
        ``meta["patch"]`` records the box, the channel's solve and the method.
    """
    t0 = time.perf_counter()
    channel = settings.model_copy(update={"patch": None})
    if coarse is None:
        coarse = solve_nested(channel, threads=threads)
    coarse_field = field_from_solution(channel, coarse)
    t_coarse = time.perf_counter() - t0
    sol, box, pgeom = solve_patch_lattice(settings, coarse, threads=threads)
    scale = float(coarse_field.meta["scale_um_per_s_per_lattice"])
    ux, uy = midplane_average(sol.u, sol.grid) * scale
    sub_grid = get_wall_scheme(settings.pillar_boundary).sub_grid
    if sub_grid:
        ux, uy = extend_into_wall(ux, uy, sol.grid.solid, pgeom.shape, box.dx)
    outside = depth_factor(sol.grid) / depth_factor(coarse.grid)
    ux, uy, solid = compose(coarse_field, ux, uy, sol.grid.solid, box, outside)
    rep = sol.report
    meta = {
        "solver_version": SOLVER_VERSION,
        "package_version": __version__,
        "settings": settings.model_dump(mode="json"),
        "report": {**dataclasses.asdict(rep), "grid": list(rep.grid)},
        "scale_um_per_s_per_lattice": scale,
        "u_center_reached": coarse_field.meta["u_center_reached"],
        "dx_um": box.dx,
        "units": {"length": "um", "velocity": "um/s"},
        "patch": {
            "method": PATCH_METHOD,
            "x0_um": box.x0,
            "y0_um": box.y0,
            "nodes": [box.nx, box.ny, sol.grid.nz],
            "channel_dx_um": settings.dx,
            "outside_scale": outside,
            "channel_report": coarse_field.meta["report"],
            "channel_seconds": t_coarse,
            "seconds": time.perf_counter() - t0,
        },
    }
    if sub_grid:
        meta["wall_ghosts"] = GHOST_METHOD
    log.info(
        "patch at dx=%g: %d x %d x %d nodes, %d steps in %.1f s (channel %.1f s)",
        box.dx, box.nx, box.ny, sol.grid.nz, rep.steps, rep.seconds, t_coarse,
    )  # fmt: skip
    return FlowField(
        ux=ux,
        uy=uy,
        dx=box.dx,
        geometry=settings.geometry.to_geometry(),
        fluid=settings.fluid.to_fluid(),
        solid=solid,
        meta=meta,
    )
