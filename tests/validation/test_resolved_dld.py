"""A resolved sphere in the circle array's unit cell: the pillar images it meets; bump, zigzag."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.resolved import dld


def test_the_nearest_pillar_is_found_across_shifted_faces():
    cs = dld.CellSettings(shift=0.2, dx=2.0)
    box, shape, s = dld._box(cs)
    assert (box.nx, box.ny, box.nz, s) == (40, 40, 10, 8)
    assert shape.radius == pytest.approx(10.0)
    # on the apex of the pillar two rows downstream: its centre is (cx + 2 nx, cy + 2 s)
    x = np.array([shape.cx + 2 * box.nx, shape.cy + 2 * s + shape.radius + 3.0 + 1.5, 10.0])
    h, n = dld._nearest_pillar(shape, box, x, 3.0)
    assert h == pytest.approx(1.5) and n == pytest.approx([0.0, 1.0, 0.0])
    # one period up and one row upstream
    x = np.array([shape.cx - box.nx + 20.0, shape.cy - s + box.ny, 10.0])
    h, _ = dld._nearest_pillar(shape, box, x, 2.0)
    assert h == pytest.approx(20.0 - 10.0 - 2.0)


def test_the_empty_cell_carries_its_mean_flow_along_x():
    cs = dld.CellSettings(shift=0.2, dx=4.0)
    lat, u_gap = dld.empty_cell(cs, radius=3.0)
    _, u = lat.velocity()
    ux, uy = float(u[0].sum()), float(u[1].sum())
    assert abs(math.atan2(uy, ux)) < 1e-3
    # the scale: the superficial velocity is u_g (G/λ)(2/3); Re_p = u_g a/ν
    assert ux / lat.box.nodes == pytest.approx(u_gap * (40 / 80) * (2 / 3), rel=1e-3)
    assert u_gap * 3.0 / lat.fluid.nu == pytest.approx(cs.reynolds)


@pytest.mark.slow
def test_small_sphere_zigzags_and_large_sphere_bumps_at_eps_01():
    # measured (docs/validation/resolved.md): 8 µm zigzags (26 µm below the next pillar's
    # centre), 20 µm bumps (32 µm above); a decision either way by more than a pillar radius
    cs = dld.CellSettings(shift=0.1, dx=2.0, tau=1.5)
    small, big = dld.decide(cs, 8.0), dld.decide(cs, 20.0)
    assert not any(small.bumped) and all(big.bumped)
    assert min(abs(o) for o in small.offsets + big.offsets) > 20.0
