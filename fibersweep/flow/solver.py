"""Public entry points of the flow solver: lattice solve -> scaled midplane FlowField.

:func:`solve_flow` runs the D3Q19 solver (:mod:`fibersweep.flow.lbm`, coarser
grids first where valid, or with a finer patch round the pillar,
:mod:`fibersweep.flow.patch`) and builds the channel's field from it
(:func:`~fibersweep.flow.channel_field.field_from_solution`).
"""

from __future__ import annotations

from fibersweep.config.flow import FlowSettings
from fibersweep.flow.channel_field import field_from_solution
from fibersweep.flow.field import FlowField
from fibersweep.flow.lattice import MACH_LIMIT, U_LATTICE
from fibersweep.flow.lbm import (
    SOLVER_VERSION,
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
from fibersweep.flow.patch import solve_patched

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

    Solved by :func:`solve_nested` (coarser grids first where they are valid),
    or with ``settings.patch`` by :func:`~fibersweep.flow.patch.solve_patched`.

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
    if settings.patch is not None:
        return solve_patched(settings, threads=threads)
    return field_from_solution(settings, solve_nested(settings, threads=threads))
