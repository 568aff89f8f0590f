"""RPY mobility and the rigid-body mobility of a straight fiber."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.fiber.hydro.rpy import body_mobility, fiber_offsets, rpy_matrix, rpy_pair

A = 2.0
MU = 0.34


def _rpy3d(rv: np.ndarray, a: float, mu: float) -> np.ndarray:
    """Independent 3D RPY tensor (written from the SPEC formula with numpy outer products)."""
    r = np.linalg.norm(rv)
    e = np.outer(rv, rv) / r**2
    eye = np.eye(3)
    if r >= 2 * a:
        return ((1 + 2 * a**2 / (3 * r**2)) * eye + (1 - 2 * a**2 / r**2) * e) / (
            8 * np.pi * mu * r
        )
    return ((1 - 9 * r / (32 * a)) * eye + (3 * r / (32 * a)) * e) / (6 * np.pi * mu * a)


@pytest.mark.parametrize("r", [0.5, 1.0, 3.0, 4.0, 4.5, 8.0, 40.0])
def test_rpy_pair_matches_3d_tensor(r):
    rng = np.random.default_rng(1)
    ang = rng.uniform(0, 2 * np.pi)
    rv = r * np.array([np.cos(ang), np.sin(ang)])
    m3 = _rpy3d(np.array([*rv, 0.0]), A, MU)
    # tolerance: round-off only
    np.testing.assert_allclose(rpy_pair(rv, A, MU), m3[:2, :2], rtol=1e-12, atol=1e-15)
    assert abs(m3[2, 0]) < 1e-15 and abs(m3[2, 1]) < 1e-15  # z decouples in the plane


def test_two_sphere_closed_form_along_and_across():
    """Two spheres r apart pushed by equal forces move with U = F (m0 + m_pair).

    Closed forms (Rotne-Prager): along the line of centres m = (1 - 2a²/3r²)/(4πμr),
    across it m = (1 + 2a²/3r²)/(8πμr). Tolerance: round-off (1e-12 relative).
    """
    m0 = 1 / (6 * np.pi * MU * A)
    for r in (4.0, 6.0, 10.0):
        m = rpy_matrix(np.array([[0.0, 0.0], [r, 0.0]]), A, MU)
        u_along = (m @ np.array([1.0, 0, 1.0, 0]))[0]
        u_across = (m @ np.array([0, 1.0, 0, 1.0]))[1]
        assert u_along == pytest.approx(
            m0 + (1 - 2 * A**2 / (3 * r**2)) / (4 * np.pi * MU * r), 1e-12
        )
        assert u_across == pytest.approx(
            m0 + (1 + 2 * A**2 / (3 * r**2)) / (8 * np.pi * MU * r), 1e-12
        )


def test_rpy_continuous_at_contact():
    # Far and overlapping forms meet at r = 2a (both give 5/(48πμa) along, 7/(48πμa)... across).
    lo = rpy_pair(np.array([2 * A * (1 - 1e-12), 0.0]), A, MU)
    hi = rpy_pair(np.array([2 * A, 0.0]), A, MU)
    np.testing.assert_allclose(lo, hi, rtol=1e-9)
    assert hi[0, 0] == pytest.approx(5 / (48 * np.pi * MU * A), rel=1e-12)


@pytest.mark.parametrize("n", [2, 11, 22, 30])
@pytest.mark.parametrize("spacing", [1.5, 2.0, 2.2])
def test_grand_mobility_spd(n, spacing):
    """M symmetric positive definite for straight and bent chains at the spacings used."""
    s = (np.arange(n) - 0.5 * (n - 1)) * spacing * A
    for bend in (0.0, 0.3):
        ang = bend * s / (s.max() + 1e-9)
        pos = np.column_stack([s * np.cos(ang), s * np.sin(ang)])
        m = rpy_matrix(pos, A, MU)
        np.testing.assert_allclose(m, m.T, rtol=0, atol=1e-15)
        assert np.linalg.eigvalsh(m).min() > 0


def test_body_mobility_single_bead_and_uniform_flow():
    b1 = body_mobility(1, A, MU)
    m0 = 1 / (6 * np.pi * MU * A)
    np.testing.assert_allclose(np.diag(b1.N)[:2], [m0, m0], rtol=1e-12)
    for n in (2, 11, 22):
        b = body_mobility(n, A, MU)
        # Uniform background velocity: V = u, Ω = 0 exactly (tolerance: round-off).
        u = np.tile([3.0, -2.0], n)
        np.testing.assert_allclose(b.P @ u, [3.0, -2.0, 0.0], atol=1e-10)
        np.testing.assert_allclose(b.N, b.N.T, atol=1e-18)
        # Straight fiber: translation along/across and rotation decouple; along is faster.
        assert abs(b.N[0, 1]) < 1e-15 and abs(b.N[1, 2]) < 1e-15
        assert b.N[0, 0] > b.N[1, 1]
        # Rigid rotation of the background (u = Ω ẑ × r) is followed exactly.
        s = fiber_offsets(n, A)
        rot = np.column_stack([np.zeros(n), 0.7 * s]).ravel()
        np.testing.assert_allclose(b.P @ rot, [0.0, 0.0, 0.7], atol=1e-10)


def test_body_mobility_cached():
    assert body_mobility(11, A, MU) is body_mobility(11, A, MU)


def test_long_fiber_against_rod_hydrodynamics():
    """Drag of a 30-bead fiber against the cylinder formulas of Tirado & de la Torre
    (aspect ratio p = L/2a, end corrections ν_par = −0.207, ν_perp = 0.839, ν_rot = −0.662):
    ζ_par = 2πμL/(ln p + ν_par), ζ_perp = 4πμL/(ln p + ν_perp), ζ_rot = πμL³/(3(ln p + ν_rot)).
    A bead chain is not a cylinder: tolerance 15 % on each ratio."""
    n = 30
    b = body_mobility(n, A, MU)
    L = n * 2 * A
    lp = math.log(n)
    z_par = 2 * np.pi * MU * L / (lp - 0.207)
    z_perp = 4 * np.pi * MU * L / (lp + 0.839)
    z_rot = np.pi * MU * L**3 / (3 * (lp - 0.662))
    assert b.N[0, 0] / b.N[1, 1] == pytest.approx(z_perp / z_par, rel=0.15)
    assert b.N[2, 2] / b.N[1, 1] == pytest.approx(z_perp / z_rot, rel=0.15)
    assert math.isfinite(b.tip_mobility) and b.tip_mobility > b.N[0, 0]
