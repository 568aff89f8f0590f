"""Near-pillar wall drag (pillar_hydro) against dense linear algebra of the same law."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.fiber.hydro.first_reflection import (
    mobility_with_wall_drag,
    rigid_wall_velocity,
    wall_drag,
)
from fibersweep.fiber.hydro.rpy import body_mobility, body_velocity, rigid_map, rpy_matrix

A, MU = 2.0, 0.34


@pytest.mark.parametrize("n", [1, 5, 12])
def test_rigid_wall_velocity_is_the_dense_constrained_solve(n):
    # (Kᵀ M⁻¹ K + Kᵀ Z K) V = Kᵀ M⁻¹ u + F (body frame), solved densely, vs the
    # kernel's 3x3 update of the precomputed N. Tolerance 1e-9 relative (round-off).
    rng = np.random.default_rng(n)
    bm = body_mobility(n, A, MU)
    ub = rng.normal(size=2 * n) * 100.0  # angle 0: lab frame = body frame
    fx, fy = rng.normal(size=n), rng.normal(size=n)
    zeta = np.where(rng.random(n) < 0.5, rng.random(n) * 30.0, 0.0)
    zeta[0] = 12.0
    v0 = body_velocity(1.0, 0.0, bm.offsets, bm.P, bm.N, ub, fx, fy, True)
    nm_out = np.empty((3, 3))
    got = np.array(rigid_wall_velocity(bm.offsets, bm.N, zeta, *v0, nm_out))

    k = rigid_map(bm.offsets)
    m = rpy_matrix(np.column_stack([bm.offsets, np.zeros(n)]), A, MU)
    r = k.T @ np.linalg.solve(m, k)
    if n == 1:
        r[2, 2] = 8.0 * math.pi * MU * A**3  # as body_mobility does for a lone sphere
    r_tot = r + k.T @ np.diag(np.repeat(zeta, 2)) @ k
    f_b = np.column_stack([fx, fy]).reshape(-1)
    want = np.linalg.solve(r_tot, k.T @ np.linalg.solve(m, ub) + k.T @ f_b)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
    np.testing.assert_allclose(nm_out, np.linalg.inv(r_tot), rtol=1e-9, atol=1e-12)


def test_wall_drag_only_slows():
    # extra resistance never speeds a body up: |V|_R' <= |V0|_R for any ζ >= 0, and a
    # sideways push with drag on the last bead only turns the fiber about that end
    n = 10
    bm = body_mobility(n, A, MU)
    zero2, zero = np.zeros(2 * n), np.zeros(n)
    v0 = body_velocity(1.0, 0.0, bm.offsets, bm.P, bm.N, zero2, zero, np.ones(n), True)
    zeta = np.zeros(n)
    zeta[-1] = 6.0 * math.pi * MU * A
    v = rigid_wall_velocity(bm.offsets, bm.N, zeta, *v0, np.empty((3, 3)))
    assert abs(v0[2]) < 1e-12  # a uniform push alone does not turn it
    assert 0.0 < v[1] < v0[1] and v[2] < 0.0  # slower, and the +s end lags
    # in the resistance norm ‖V‖² = Vᵀ N⁻¹ V the map V0 -> V is (I + N^½ΔR N^½)⁻¹-like,
    # with eigenvalues in (0, 1]: never faster (1e-12 for round-off)
    rng = np.random.default_rng(3)
    r = np.linalg.inv(bm.N)
    for _ in range(20):
        vv = rng.normal(size=3)
        w = np.array(
            rigid_wall_velocity(bm.offsets, bm.N, rng.random(n) * 40.0, *vv, np.empty((3, 3)))
        )
        assert w @ r @ w <= vv @ r @ vv * (1 + 1e-12)


def test_bead_mobility_woodbury_is_the_dense_inverse():
    # M' = (M⁻¹ + Z)⁻¹ and (I + M Z)⁻¹ u with two of seven beads dragged; 1e-10 relative
    n = 7
    pos = np.column_stack([np.arange(n) * 2.0 * A, 0.3 * np.sin(np.arange(n))])
    m = rpy_matrix(pos, A, MU)
    zeta = np.zeros(n)
    zeta[[1, 5]] = [8.0, 20.0]
    z = np.diag(np.repeat(zeta, 2))
    u = np.random.default_rng(0).normal(size=2 * n)
    want_m = np.linalg.inv(np.linalg.inv(m) + z)
    want_u = np.linalg.solve(np.eye(2 * n) + m @ z, u)
    got_m, got_u = m.copy(), u.copy()
    mobility_with_wall_drag(got_m, zeta, got_u)
    np.testing.assert_allclose(got_m, want_m, rtol=1e-10, atol=1e-10 * np.abs(want_m).max())
    np.testing.assert_allclose(got_u, want_u, rtol=1e-10, atol=1e-10)
    same_m, same_u = m.copy(), u.copy()
    mobility_with_wall_drag(same_m, np.zeros(n), same_u)
    np.testing.assert_array_equal(same_m, m)
    np.testing.assert_array_equal(same_u, u)


def test_wall_drag_law():
    # first-reflection drag beside a plane wall, β/(1 − β) with β = 9a/16h, screened over 40 µm
    dist = np.array([1.0, 2.0, 4.0, 2000.0])  # inside the radius, touching, 2 µm gap, far
    zeta = np.empty(4)
    count = wall_drag(dist, A, 0.5, 40.0, MU, zeta)
    z0 = 6.0 * math.pi * MU * A
    touch = 0.5 * z0 * (9 / 16) / (7 / 16)  # 0.5 x 9/7 of the Stokes drag
    beta = 9 / 32
    gap2 = 0.5 * z0 * beta / (1 - beta) * math.exp(-2.0 / 40.0)
    np.testing.assert_allclose(zeta[:3], [touch, touch, gap2], rtol=1e-12)
    assert zeta[3] == 0.0 and count == 3
