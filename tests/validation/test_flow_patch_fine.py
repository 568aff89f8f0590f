"""A dx = 2 µm patch in the dx = 4 µm channel against the whole channel at dx = 2 µm (slow).

Small channel (W 400, L 800, H 40 µm, h_obs 75 µm, as the tests' small field).
Tolerances: the separatrix within 0.002 h_obs (below the dx = 2 µm placement
spread of 0.003, docs/validation/flow.md), the peak speed near the pillar within 1 %,
the midplane field within 1 % (relative L2 over the fluid nodes within 40 µm of
the pillar's bounding box); and the L2 error must fall as the patch grows.
"""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.config.flow import FlowSettings
from fibersweep.flow.cache import get_flow_field
from fibersweep.flow.lbm import solve_nested
from fibersweep.flow.patch import solve_patched
from fibersweep.flow.streamlines import separatrix_y

pytestmark = pytest.mark.slow

GEO = {"width": 400.0, "length": 800.0}


def _near(field, reach=40.0):
    x0, y0, x1, y1 = field.geometry.shape.bounds
    X, Y = np.meshgrid(field.x_nodes, field.y_nodes, indexing="ij")
    box = (X > x0 - reach) & (X < x1 + reach) & (Y > y0 - reach) & (Y < y1 + reach)
    return box & ~field.solid


def test_patch_matches_the_whole_fine_grid(flow_cache_dir):
    fine, _ = get_flow_field(FlowSettings.model_validate({"geometry": GEO, "dx": 2.0}),
                             flow_cache_dir)  # fmt: skip
    channel = FlowSettings.model_validate({"geometry": GEO, "dx": 4.0})
    coarse = solve_nested(channel)
    errors = {}
    for margin in (40.0, 160.0):
        s = FlowSettings.model_validate(
            {**channel.model_dump(), "patch": {"dx": 2.0, "margin": margin}}
        )
        patched = solve_patched(s, coarse=coarse)
        assert patched.ux.shape == fine.ux.shape and patched.dx == 2.0
        mask = _near(fine)
        np.testing.assert_array_equal(patched.solid, fine.solid)
        d = np.hypot(patched.ux - fine.ux, patched.uy - fine.uy)[mask]
        errors[margin] = np.linalg.norm(d) / np.linalg.norm(np.hypot(fine.ux, fine.uy)[mask])
        if margin == 160.0:  # the default patch
            assert errors[margin] < 1e-2
            assert abs(separatrix_y(patched) - separatrix_y(fine)) < 2e-3
            peak = np.hypot(patched.ux, patched.uy)[mask].max()
            assert abs(peak / np.hypot(fine.ux, fine.uy)[mask].max() - 1.0) < 1e-2
    assert errors[160.0] < errors[40.0]
