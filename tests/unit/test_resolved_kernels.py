"""The blocked kernels of the resolved lattice against the node-wise reference kernels."""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.flow.lattice import Q
from fibersweep.resolved import kernels, kernels_blocked
from fibersweep.resolved.box import Box, pillar_links, pull_table
from fibersweep.resolved.dld import CellSettings, _box
from fibersweep.resolved.lattice import FluidSettings, Lattice
from fibersweep.resolved.particle import Body, BodyState


def _boxes() -> list[Box]:
    moving = np.array([[0.01, 0.02, 0.0], [0.03, -0.01, 0.0]])
    return [
        Box(5, 4, 3),
        Box(6, 10, 4, periodic_y=True, shift=3, z_mode="walls", wall_velocity=moving),
        Box(7, 5, 4, periodic_y=False, z_mode="symmetric"),
        _box(CellSettings(shift=0.1, dx=4.0))[0],  # shifted faces, pillar, mirror top
    ]


@pytest.mark.parametrize("box", _boxes(), ids=["periodic", "shifted-walls", "y-walls-mirror",
                                               "dld-cell"])  # fmt: skip
def test_row_streaming_equals_the_node_table_on_every_fluid_node(box):
    # exact: both copy the same numbers; the pillar's links are left out (they are
    # overwritten by static_links in either path), and the moving walls' term is summed
    # in another order (1e-17 of a 1e-2 wall speed)
    src = pull_table(box)
    rows = kernels_blocked.row_table(src, box.nx)
    f = np.random.default_rng(1).random((Q, box.nodes))
    ref, new = np.zeros_like(f), np.zeros_like(f)
    flags = box.solid_flags()
    kernels.stream(f, ref, src, flags, box.wall_velocity)
    kernels_blocked.stream_rows(f, new, rows, src, box.wall_velocity)
    check = np.zeros(f.shape, dtype=bool)
    check[:, flags == 0] = True
    node, q, _, _ = pillar_links(box)
    check[q, node] = False
    np.testing.assert_allclose(new[check], ref[check], rtol=0, atol=1e-16)


def test_blocked_collision_equals_the_node_loop_and_leaves_solid_nodes_alone():
    # round-off only (fastmath orders the sums differently): 1e-15 of populations ~0.05
    box = _boxes()[3]
    flags = box.solid_flags()
    rng = np.random.default_rng(2)
    f = 0.05 + 1e-3 * rng.random((Q, box.nodes))
    g = f.copy()
    force = np.array([1e-5, 2e-5, -1e-5])
    kernels.collide(f, flags, force, 0.7, 1.3)
    kernels_blocked.collide_blocked(g, flags, force, 0.7, 1.3)
    np.testing.assert_allclose(g, f, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(g[:, flags != 0], f[:, flags != 0])


def test_a_coupled_lattice_steps_alike_with_either_kernels():
    # a sphere against the pillar of the cell, 30 steps: the populations agree to round-off
    # growth (1e-13 of ~0.05) and the force on the sphere to 1e-9 relative
    box, shape, _ = _box(CellSettings(shift=0.1, dx=4.0))
    body = Body(2.0)
    st = BodyState(np.array([shape.cx, shape.cy + shape.radius + 3.0, box.nz]), u=(1e-3, 0, 0))
    outs = []
    for blocked in (False, True):
        lat = Lattice(box, FluidSettings(tau=1.5), force=(1e-5, 1e-6, 0.0), blocked=blocked)
        lat.place(st.vector(body), 0.0)
        for _ in range(30):
            out = lat.step(st.vector(body))
        outs.append((lat.f.copy(), out))
    (f0, o0), (f1, o1) = outs
    fluid = lat.flags == 0
    np.testing.assert_allclose(f1[:, fluid], f0[:, fluid], rtol=0, atol=1e-13)
    np.testing.assert_allclose(o1[:3], o0[:3], rtol=1e-9)


def test_a_spheres_exact_link_crossing_equals_the_capsules_bisection():
    # the sphere's links cross where |x − t e − c| = a (a quadratic); a capsule of length
    # 1e-12 takes the bisection path (2^-30 ≈ 1e-9 of a link): force, torque and the link
    # matrix agree to that
    box = Box(16, 16, 16)
    lat = Lattice(box, FluidSettings(tau=0.8))
    f = lat.f + 1e-3 * np.random.default_rng(3).random(lat.f.shape)
    res = []
    for ell in (0.0, 1e-12):
        b = BodyState(np.array([8.2, 7.9, 8.1]), u=(1e-3, 2e-4, 0.0), w=(0.0, 1e-4, 0.0))
        vec = b.vector(Body(3.3, half_length=ell))
        flags = box.solid_flags()
        kernels.refill(f.copy(), flags, lat.dims, vec, 0.0, np.zeros(6))
        out = np.zeros(43)
        kernels.particle_links(f, np.zeros_like(f), flags, lat.dims, vec, out)
        res.append(out)
    assert res[0][6] == res[1][6] > 100  # the same links
    np.testing.assert_allclose(res[0], res[1], rtol=1e-7, atol=1e-12)
