"""Following a resolved sphere across the shifted x faces of a unit cell."""

from __future__ import annotations

import numpy as np

from fibersweep.resolved.box import Box
from fibersweep.resolved.lattice import FluidSettings, Lattice
from fibersweep.resolved.particle import Body, BodyState
from fibersweep.resolved.run import Coupled

NX, NY, NZ, S = 14, 16, 12, 5


def _run(offset, steps=800):
    g = 2e-5
    box = Box(NX, NY, NZ, periodic_y=True, shift=S, z_mode="walls")
    fluid = FluidSettings(tau=1.0)
    lat = Lattice(box, fluid, force=(g, 0.0, 0.0))
    z = np.arange(NZ) + 0.5
    u0 = np.zeros((3, NZ, NY, NX))
    u0[0] = (g / (2 * fluid.nu) * z * (NZ - z))[:, None, None]
    lat.init_velocity(u0)
    x0 = np.array([13.0, 8.3, 5.7]) + np.asarray(offset, dtype=float)
    run = Coupled(lat, Body(3.0), BodyState(x0, u=(u0[0].max(), 0, 0)))
    rec = run.run(steps, every=100)
    return rec, int((lat.flags == 2).sum()), x0


def test_a_sphere_and_its_images_across_the_shifted_faces_move_alike():
    base, n0, x0 = _run((0.0, 0.0, 0.0))
    assert base.x[-1, 0] > NX  # the centre crossed the downstream face
    for off in ((NX, S, 0.0), (-NX, -S + NY, 0.0), (2 * NX, 2 * S - NY, 0.0)):
        other, n1, x1 = _run(off)
        np.testing.assert_allclose(other.x - x1, base.x - x0, atol=1e-9)
        np.testing.assert_allclose(other.u, base.u, atol=1e-13)
        assert n1 == n0


def test_the_shifted_cell_is_the_plain_block_of_its_rows():
    # a shifted cell (NX, NY, S) with an obstacle = a plain box of 2 rows (2 NX, NY) when 2 S = NY
    s, ny = 8, 16
    solid = np.zeros((NX, ny), dtype=bool)
    solid[4:8, 3:9] = True
    cell = Lattice(Box(NX, ny, 4, periodic_y=True, shift=s, z_mode="walls", solid=solid),
                   FluidSettings(), force=(1e-5, 2e-6, 0.0))
    block_solid = np.zeros((2 * NX, ny), dtype=bool)
    block_solid[:NX] = solid
    block_solid[NX:] = np.roll(solid, s, axis=1)
    block = Lattice(Box(2 * NX, ny, 4, periodic_y=True, z_mode="walls", solid=block_solid),
                    FluidSettings(), force=(1e-5, 2e-6, 0.0))
    for _ in range(300):
        cell.step()
        block.step()
    _, uc = cell.velocity()
    _, ub = block.velocity()
    np.testing.assert_allclose(ub[..., :NX], uc, atol=1e-15)
    np.testing.assert_allclose(ub[..., NX:], np.roll(uc, s, axis=2), atol=1e-15)
