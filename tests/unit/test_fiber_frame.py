"""The frames the integrators read the field and the contact through (fibersweep.fiber.frame).

The channel frame is the plain interpolation and contact kernel (bit for bit);
the lattice frame sums the same contact kernel over the pillar images within
reach. Tolerances: bit for bit where the same operations run. Where beads are
moved into a pillar's frame, by up to 3300 µm, the translation rounds positions
by about ulp(3300 µm) = 5e-13 µm, which the contact law's steep layer (a few
tenths of a µm) turns into relative force errors of about 1e-12 (measured
1.6e-12 at row 41): relative 1e-10.
"""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.config.fiber import ContactSettings
from fibersweep.fiber.contact.pillar import make_pillar, pillar_forces
from fibersweep.fiber.frame import CHANNEL, frame_contact, frame_velocity, lattice
from fibersweep.fiber.kernel.bundles import FlowArrays
from fibersweep.flow.field import interpolate_ib
from fibersweep.geometry.array import PillarArray

ARRAY = PillarArray(pillar_shape="triangle", pillar_size=40.0, period_x=80.0, period_y=80.0,
                    shift=0.1)  # fmt: skip


@pytest.fixture(params=["rough", "smooth"])
def pillar(request):
    return make_pillar(ARRAY.cell_geometry, ContactSettings(pillar=request.param), 2.0, 10.0)


def _buffers(n):
    return [np.zeros(n) for _ in range(4)]


def _beads_near_outline(pillar, n=6):
    """n beads 2 µm apart along the triangle's base, below it, in its contact layer [µm]."""
    x0, y0, x1, _ = ARRAY.shape.bounds
    x = 0.5 * (x0 + x1) + 2.0 * (np.arange(n) - n / 2)
    y = np.full(n, y0 - 0.5 * (pillar.r_eq + pillar.r_cut))
    return x, y


def test_channel_frame_is_the_plain_kernels_bit_for_bit(pillar):
    rng = np.random.default_rng(3)
    ux, uy = rng.normal(size=(2, 20, 20))
    flow = FlowArrays(ux, uy, 4.0)
    x, y = _beads_near_outline(pillar)
    u1, u2 = np.zeros((6, 2)), np.zeros((6, 2))
    frame_velocity(CHANNEL, flow, x, y, u1)
    interpolate_ib(ux, uy, 4.0, x, y, u2)
    assert np.array_equal(u1, u2)
    a, b = _buffers(6), _buffers(6)
    n_c, cx, cy = frame_contact(CHANNEL, pillar.arrays(), x, y, *a)
    hit, qx, qy = pillar_forces(pillar.arrays(), x, y, *b)
    assert n_c == 1 and hit
    assert (cx, cy) == (qx, qy)
    for p, q in zip(a, b, strict=True):
        assert np.array_equal(p, q)


@pytest.mark.parametrize(("row", "col"), [(0, 0), (3, -2), (-7, 5), (41, 1)])
def test_lattice_contact_is_the_kernel_in_the_touched_pillars_frame(pillar, row, col):
    """Beads next to pillar (row, col) feel what the same beads next to pillar (0, 0) feel."""
    x, y = _beads_near_outline(pillar)
    ox, oy = ARRAY.offset(row, col)
    fr = lattice(ARRAY, 3, 2.0, 6)
    a, b = _buffers(6), _buffers(6)
    n_c, cx, cy = frame_contact(fr, pillar.arrays(), x + ox, y + oy, *a)
    hit, qx, qy = pillar_forces(pillar.arrays(), x, y, *b)
    assert hit and n_c == 1
    assert (cx, cy) == pytest.approx((qx + ox, qy + oy), abs=1e-12 * max(abs(ox), abs(oy), 1))
    for p, q in zip(a, b, strict=True):  # fx, fy, stiffness, distance
        assert np.allclose(p, q, rtol=1e-10, atol=1e-300)


@pytest.mark.parametrize("kind", ["rough", "smooth"])
def test_a_fiber_across_a_gap_is_pushed_by_both_pillars(kind):
    """Circles 40 µm across, periods 80 µm: a fiber along y spanning the 40 µm gap between
    pillars (0, 0) and (0, 1), its end beads in their contact layers. Two pillars in
    contact; the force on each bead is the sum of the two pillars' forces (1e-12 pN)."""
    arr = PillarArray(pillar_shape="circle", pillar_size=40.0, period_x=80.0, period_y=80.0,
                      shift=0.1)  # fmt: skip
    pil = make_pillar(arr.cell_geometry, ContactSettings(pillar=kind), 2.0, 10.0)
    d = 0.5 * (pil.r_eq + pil.r_cut)
    x0, y0, x1, y1 = arr.shape.bounds
    ys = np.linspace(y1 + d, y0 + 80.0 - d, 19)
    xs = np.full(ys.size, 0.5 * (x0 + x1))
    n = xs.size
    got = _buffers(n)
    n_c, _, _ = frame_contact(lattice(arr, 3, 2.0, n), pil.arrays(), xs, ys, *got)
    assert n_c == 2
    want = np.zeros((2, n))
    for r, c in [(0, 0), (0, 1)]:
        ox, oy = arr.offset(r, c)
        b = _buffers(n)
        pillar_forces(pil.arrays(), xs - ox, ys - oy, *b)
        want += np.array(b[:2])
    assert np.allclose(got[0], want[0], rtol=0, atol=1e-12)
    assert np.allclose(got[1], want[1], rtol=0, atol=1e-12)
    assert got[1][0] > 0 > got[1][-1]  # pushed up by the lower pillar, down by the upper one
    assert np.all(got[1][1:-1] == 0.0)


def test_lattice_velocity_is_periodic_and_reads_the_cell():
    """A point and its images read the same node value of the padded cell field."""
    nx, ny, pad, dx = 40, 40, 3, 2.0
    rng = np.random.default_rng(0)
    cell = rng.normal(size=(nx, ny))
    s = round(ARRAY.lateral_shift / dx)
    i = np.arange(-pad, nx + pad)
    j = np.arange(-pad, ny + pad)
    row = np.floor_divide(i, nx)
    padded = np.ascontiguousarray(
        cell[(i - row * nx)[:, None], (j[None, :] + row[:, None] * s) % ny]
    )
    flow = FlowArrays(padded, -padded, dx)
    fr = lattice(ARRAY, pad, dx, 8)
    x = rng.uniform(0, 80, 8)
    y = rng.uniform(0, 80, 8)
    ref = np.zeros((8, 2))
    frame_velocity(fr, flow, x, y, ref)
    for r, c in [(1, 0), (-2, 3), (9, -4)]:
        ox, oy = ARRAY.offset(r, c)
        out = np.zeros((8, 2))
        frame_velocity(fr, flow, x + ox, y + oy, out)
        assert np.allclose(out, ref, rtol=0, atol=1e-12)
    assert np.allclose(ref[:, 0], -ref[:, 1])
