"""Public entry points of the flow solver: lattice solve -> scaled midplane FlowField.

:func:`solve_flow` runs the D3Q19 solver (:mod:`fibersweep.flow.lbm`, coarser
grids first where valid), averages the in-plane velocity over z with the IB
kernel at z = H/2 (:mod:`fibersweep.flow.midplane`) and scales it so the
midplane centreline speed far from the pillar is ``fluid.u_center``.
"""

from __future__ import annotations

import math
from dataclasses import asdict

from fibersweep import __version__
from fibersweep.errors import SolverError
from fibersweep.flow.field import FlowField
from fibersweep.flow.ghost import GHOST_METHOD, extend_into_wall
from fibersweep.flow.lbm import (
    MACH_LIMIT,
    SOLVER_VERSION,
    U_LATTICE,
    LatticeSolution,
    SolveReport,
    choose_tau,
    coarser_settings,
    solve_lattice,
    solve_nested,
)
from fibersweep.flow.midplane import (
    full_depth,
    midplane_average,
    midplane_centre_speed,
    midplane_weights,
)
from fibersweep.flow.schemes import get_wall_scheme
from fibersweep.flow.settings import FlowSettings

__all__ = [
    "SOLVER_VERSION",
    "U_LATTICE",
    "MACH_LIMIT",
    "SolveReport",
    "LatticeSolution",
    "choose_tau",
    "coarser_settings",
    "solve_lattice",
    "solve_nested",
    "solve_flow",
    "field_from_solution",
    "midplane_weights",
    "midplane_average",
    "midplane_centre_speed",
    "full_depth",
]


def solve_flow(settings: FlowSettings, threads: int | None = None) -> FlowField:
    """Steady midplane flow for ``settings``, scaled to ``fluid.u_center``.

    Solved by :func:`solve_nested` (coarser grids first where they are valid).

    Parameters
    ----------
    settings : FlowSettings
    threads : int, optional
        Numba threads (default: all for large grids).

    Returns
    -------
    FlowField
        ux, uy [µm/s] of shape (nx, ny), z-averaged with the IB kernel at z = H/2
        (zero on pillar nodes, except with a sub-grid pillar wall: there the
        solid nodes within reach of the IB stencil hold ghost values that make
        the interpolated field vanish on the exact wall, see
        :mod:`fibersweep.flow.ghost`); ``meta`` holds the solver report and settings.
    """
    if settings.patch is not None:  # a finer grid around the pillar (flow/patch.py)
        from fibersweep.flow.patch import solve_patched

        return solve_patched(settings, threads=threads)
    return field_from_solution(settings, solve_nested(settings, threads=threads))


def field_from_solution(settings: FlowSettings, sol: LatticeSolution) -> FlowField:
    """Scale a lattice solution to physical units and build the FlowField."""
    geom = settings.geometry.to_geometry()
    fluid = settings.fluid.to_fluid()
    grid = sol.grid
    x_far = geom.x_far
    u_ref = midplane_centre_speed(sol.u, grid, x_far, geom.width / 2.0)
    if not (math.isfinite(u_ref) and u_ref > 0):
        raise SolverError(f"centreline speed far from the pillar is {u_ref!r}; cannot scale")
    scale = fluid.u_center / u_ref
    ux, uy = midplane_average(sol.u, grid) * scale
    ghosts = get_wall_scheme(settings.pillar_boundary).sub_grid
    if ghosts:  # sub-grid wall: solid nodes near it get mirrored values (ghost.py)
        ux, uy = extend_into_wall(ux, uy, grid.solid, geom.shape, grid.dx)
    meta = {
        "solver_version": SOLVER_VERSION,
        "package_version": __version__,
        "settings": settings.model_dump(mode="json"),
        "report": {**asdict(sol.report), "grid": list(sol.report.grid)},
        "scale_um_per_s_per_lattice": scale,
        "u_center_reached": u_ref * scale,  # the centreline speed is linear in u
        "dx_um": grid.dx,
        "units": {"length": "um", "velocity": "um/s"},
    }
    if ghosts:
        meta["wall_ghosts"] = GHOST_METHOD
    u3d = full_depth(sol.u, grid) * scale if settings.keep_3d else None
    return FlowField(
        ux=ux,
        uy=uy,
        dx=grid.dx,
        geometry=geom,
        fluid=fluid,
        solid=grid.solid.copy(),
        meta=meta,
        u3d=u3d,
    )
