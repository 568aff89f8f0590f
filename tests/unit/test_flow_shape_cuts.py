"""Every pillar shape builds its sub-grid wall: cut points on the exact outline, ghosts valid."""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.config.flow import FlowSettings
from fibersweep.flow.cuts import pillar_cuts
from fibersweep.flow.ghost import ghost_stencil
from fibersweep.flow.lbm import lattice_of

GEOMETRIES = {
    "circle": {"pillar_shape": "circle"},
    "square": {"pillar_shape": "square"},
    "diamond": {"pillar_shape": "square", "pillar_rotation": 45.0},
    "turned triangle": {"pillar_shape": "triangle", "pillar_rotation": 17.0},
    "polygon": {
        "pillar_shape": "polygon",
        "pillar_vertices": [[0, 0], [1, 0], [1.2, 0.8], [0.3, 1.1]],
        "pillar_x": 1201.3,
    },
}


@pytest.mark.parametrize("name", list(GEOMETRIES))
def test_cut_points_lie_on_the_outline(name):
    """The point x + q e of every cut link is on the shape's outline to 1e-9 Δx; every fluid
    node next to a solid node has its link cut; solid nodes are those inside (closed)."""
    s = FlowSettings.model_validate(
        {"geometry": GEOMETRIES[name], "dx": 4.0, "pillar_boundary": "interpolated"}
    )
    geo = s.geometry.to_geometry()
    grid = lattice_of(s)
    shape = geo.shape
    xs = (np.arange(grid.nx) + 0.5) * grid.dx
    ys = (np.arange(grid.ny) + 0.5) * grid.dx
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    assert np.array_equal(grid.solid, shape.signed_distance(X, Y) <= 1e-9 * grid.dx)
    cuts = pillar_cuts(grid, shape, "interpolated")
    checked = 0
    for ex in (-1, 0, 1):
        for ey in (-1, 0, 1):
            q = cuts.q[:, ex + 1, ey + 1]
            ok = np.isfinite(q)
            if (ex, ey) == (0, 0):
                assert not ok.any()
                continue
            assert np.all((q[ok] > 0.0) & (q[ok] <= 1.0))
            px = (cuts.i[ok] + 0.5 + q[ok] * ex) * grid.dx
            py = (cuts.j[ok] + 0.5 + q[ok] * ey) * grid.dx
            np.testing.assert_allclose(shape.signed_distance(px, py), 0.0, atol=1e-9 * grid.dx)
            # links into solid nodes are all cut
            into = grid.solid[(cuts.i + ex) % grid.nx, np.clip(cuts.j + ey, 0, grid.ny - 1)]
            assert np.all(ok[into])
            checked += int(ok.sum())
    assert checked > 100
    ghosts, w_ghost, w_fluid = ghost_stencil(grid.solid, shape, grid.dx)
    assert ghosts.size > 0
    # each mirror point is a bilinear combination: weights sum to 1 (walls count as 0 only
    # outside the channel, which the pillar does not reach)
    total = np.asarray(w_ghost.sum(axis=1)).ravel() + np.asarray(w_fluid.sum(axis=1)).ravel()
    assert np.all(total <= 1.0 + 1e-12)
