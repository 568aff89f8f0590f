"""The pillar channel's FlowField from a lattice solution: midplane average, scale, wall ghosts.

The in-plane velocity is averaged over z with the IB kernel at z = H/2
(:mod:`fibersweep.flow.midplane`) and scaled so that the midplane centreline
speed far from the pillar is ``fluid.u_center``.
"""

from __future__ import annotations

import math
from dataclasses import asdict

from fibersweep.config.flow import FlowSettings
from fibersweep.errors import SolverError
from fibersweep.flow.field import FlowField
from fibersweep.flow.ghost import GHOST_METHOD, extend_into_wall
from fibersweep.flow.lbm import SOLVER_VERSION, LatticeSolution
from fibersweep.flow.midplane import full_depth, midplane_average, midplane_centre_speed
from fibersweep.flow.schemes import get_wall_scheme
from fibersweep.version import __version__

__all__ = ["field_from_solution"]


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
