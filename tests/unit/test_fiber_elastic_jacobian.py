"""The analytic elastic Jacobian against central differences of the elastic forces."""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.fiber.models.elastic import elastic_forces, elastic_jacobian

A = 2.0  # bead radius [µm]


def _fd_jacobian(x, y, S, B, h=1e-6):
    """∂F/∂q by central differences of elastic_forces (step h [µm])."""
    n = x.shape[0]
    jac = np.zeros((2 * n, 2 * n))
    f1, g1, f2, g2 = (np.zeros(n) for _ in range(4))
    for j in range(n):
        for comp, arr in enumerate((x, y)):
            arr[j] += h
            elastic_forces(x, y, A, S, B, f1, g1)
            arr[j] -= 2 * h
            elastic_forces(x, y, A, S, B, f2, g2)
            arr[j] += h
            jac[0::2, 2 * j + comp] = (f1 - f2) / (2 * h)
            jac[1::2, 2 * j + comp] = (g1 - g2) / (2 * h)
    return jac


@pytest.mark.parametrize("E", [26e6, 1e5])
@pytest.mark.parametrize("seed", [0, 1])
def test_analytic_jacobian_matches_central_differences(E, seed):
    """A bent, stretched and compressed 12-bead chain (springs 0.9-1.1 of 2a, turning
    angles up to ~30°): analytic J within 1e-6 of max|J| of central differences.
    Tolerance: the differences' truncation error O(h² F''') and round-off
    O(eps |F| / h) are both ~1e-8 relative at h = 1e-6 µm; 1e-6 leaves margin,
    while any wrong term of the Hessian is O(1) relative."""
    rng = np.random.default_rng(seed)
    n = 12
    seg = 2 * A * rng.uniform(0.9, 1.1, n - 1)
    ang = np.cumsum(rng.uniform(-0.5, 0.5, n - 1))
    x = np.concatenate([[0.0], np.cumsum(seg * np.cos(ang))])
    y = np.concatenate([[0.0], np.cumsum(seg * np.sin(ang))])
    S = E * np.pi * A**2
    B = E * np.pi * A**4 / 4
    jac = np.zeros((2 * n, 2 * n))
    elastic_jacobian(x, y, A, S, B, jac)
    ref = _fd_jacobian(x, y, S, B)
    assert np.max(np.abs(jac - ref)) < 1e-6 * np.max(np.abs(ref))
    # J = −∇²H is symmetric and block pentadiagonal
    assert np.allclose(jac, jac.T, rtol=0, atol=1e-12 * np.max(np.abs(ref)))
    for i in range(n):
        for j in range(n):
            if abs(i - j) > 2:
                assert not np.any(jac[2 * i : 2 * i + 2, 2 * j : 2 * j + 2])


def test_rigid_motions():
    """A bent, strained 9-bead chain: translations are zero modes, J v = 0; the rotation
    v = (−y, x) is not (the chain is not in equilibrium), but rotation invariance of H
    gives exactly J v = (−F_y, F_x) per bead (F rotated by 90°). Both to 1e-9 of
    max|J| |v| (round-off)."""
    n = 9
    t = np.linspace(0, 1.2, n)
    x = 20 * np.sin(t)
    y = 20 * (1 - np.cos(t))
    S, B = 1e3, 5e3
    jac = np.zeros((2 * n, 2 * n))
    elastic_jacobian(x, y, A, S, B, jac)
    fx, fy = np.zeros(n), np.zeros(n)
    elastic_forces(x, y, A, S, B, fx, fy)
    scale = np.max(np.abs(jac))
    for v in (np.tile([1.0, 0.0], n), np.tile([0.0, 1.0], n)):
        assert np.max(np.abs(jac @ v)) < 1e-9 * scale
    v = np.column_stack([-y, x]).ravel()
    expected = np.column_stack([-fy, fx]).ravel()
    assert np.max(np.abs(fx)) > 1.0  # a real check: the forces are not zero
    assert np.max(np.abs(jac @ v - expected)) < 1e-9 * scale * np.max(np.abs(v))
