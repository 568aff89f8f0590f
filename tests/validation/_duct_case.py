"""The empty-duct case shared by the duct validations: solve from rest, compare with the series."""

from __future__ import annotations

from typing import Any

import numpy as np

from fibersweep.config.flow import FlowSettings, GeometrySettings
from fibersweep.flow.analytic import duct_velocity
from fibersweep.flow.solver import solve_lattice


def solve_duct(depth: int, width: int, **settings: Any) -> tuple[Any, np.ndarray, float]:
    """Steady duct flow from rest at ``depth`` x ``width`` nodes (dx = 1, no pillar).

    Parameters
    ----------
    depth, width : int
        Nodes across the depth and the width.
    **settings
        Further :class:`FlowSettings` (collision, tau, symmetry, precision, ...).

    Returns
    -------
    (solution, ux, error)
        The solver's solution, the lattice ux at x = 0, shape (nz, width), and its
        relative L2 error against the analytic series.
    """
    flow = FlowSettings(
        geometry=GeometrySettings(width=width, depth=depth, length=2, pillar_height=0.5),
        dx=1.0,
        **{"tolerance": 1e-7, "max_steps": 60_000, **settings},
    )
    nz = depth // 2 if flow.symmetry else depth
    sol = solve_lattice(flow, pillar=False, initial=np.zeros((3, nz, width, 2)))
    assert sol.report.converged, sol.report
    nu = (sol.report.tau - 0.5) / 3.0
    y = np.arange(width) + 0.5
    z = np.arange(nz) + 0.5
    exact = duct_velocity(y[None, :], z[:, None], width, depth, sol.report.force / nu)
    ux = sol.u[0, :, :, 0]
    return sol, ux, float(np.linalg.norm(ux - exact) / np.linalg.norm(exact))
