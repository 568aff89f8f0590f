"""The 4-point cosine IB kernel of FlowField.velocity against exact properties."""

import numpy as np
import pytest

from fibersweep.flow.field import FlowField, ib_phi
from fibersweep.units import Geometry

GEOM = Geometry(width=200.0, depth=40.0, length=400.0, pillar_height=40.0)


def test_kernel_partition_of_unity_and_support():
    # sum_k phi(r - k) = 1 for any shift r: exact up to round-off (1e-14).
    for r in np.linspace(0, 1, 17):
        s = sum(ib_phi(r - k) for k in range(-3, 4))
        assert s == pytest.approx(1.0, abs=1e-14)
    assert ib_phi(2.0) == 0.0 and ib_phi(-2.5) == 0.0
    assert ib_phi(0.0) == pytest.approx(0.5)


def test_uniform_field_is_reproduced_away_from_walls():
    f = FlowField.from_function(lambda X, Y: (600.0 + 0 * X, -30.0 + 0 * Y), GEOM, dx=4.0)
    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.uniform(0, 400, 50), rng.uniform(10, 190, 50)])
    u = f.velocity(pts)
    # Partition of unity: exact to 1e-12 relative.
    assert np.allclose(u[:, 0], 600.0, rtol=1e-12)
    assert np.allclose(u[:, 1], -30.0, rtol=1e-12)


def _first_moment_max() -> float:
    """max over shifts r of |sum_k (r - k) phi(r - k)| (lattice units)."""
    return max(
        abs(sum((r - k) * ib_phi(r - k) for k in range(-3, 5))) for r in np.linspace(0, 1, 401)
    )


def test_linear_field_error_is_bounded_by_first_moment_and_x_is_periodic():
    # The cosine kernel's first moment is not exactly zero (max ~0.021 lattice units),
    # so a linear field u = s*y is reproduced to within s * m1 * dx: stated bound, plus 1e-9.
    m1 = _first_moment_max()
    assert 0.0 < m1 < 0.03
    dx, slope = 4.0, 3.0
    f = FlowField.from_function(lambda X, Y: (slope * Y, 0.0 * X), GEOM, dx=dx)
    pts = np.array([[1.3, 50.7], [399.9, 120.2], [200.0, 100.0], [17.0, 62.0]])
    u = f.velocity(pts)
    assert np.all(np.abs(u[:, 0] - slope * pts[:, 1]) <= slope * m1 * dx + 1e-9)
    # At node-aligned and mid-node points the kernel is symmetric: exact to 1e-10.
    sym = np.array([[200.0, 102.0], [200.0, 100.0]])
    assert f.velocity(sym)[:, 0] == pytest.approx(slope * sym[:, 1], abs=1e-10)
    # Shifting by the periodic length gives the same value.
    u2 = f.velocity(pts + np.array([400.0, 0.0]))
    assert np.allclose(u, u2, atol=1e-12)


def test_velocity_vanishes_toward_walls_and_rejects_bad_shapes():
    f = FlowField.from_function(lambda X, Y: (1.0 + 0 * X, 0 * Y), GEOM, dx=4.0)
    # At the wall only half the stencil is fluid: about 1/2 (no-slip seen through the kernel).
    assert f.velocity(np.array([[100.0, 0.0]]))[0, 0] == pytest.approx(0.5, abs=1e-12)
    with pytest.raises(ValueError, match="shape"):
        f.velocity(np.zeros((3, 3)))


def test_pillar_nodes_are_zero_and_reverse_flips_sign():
    f = FlowField.from_function(lambda X, Y: (1.0 + 0 * X, 0 * Y), GEOM, dx=2.0, with_pillar=True)
    assert f.solid.any()
    assert np.all(f.ux[f.solid] == 0.0)
    cx, cy = GEOM.centroid
    assert f.velocity(np.array([[cx, cy]]))[0, 0] == pytest.approx(0.0, abs=1e-12)
    r = f.reversed()
    assert np.array_equal(r.ux, -f.ux)
    assert r.fluid.u_center == pytest.approx(-f.fluid.u_center)
