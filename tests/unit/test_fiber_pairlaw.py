"""The soft-core pair law, written once (:func:`fibersweep.fiber.contact.pairlaw.soft_core`),
against
its closed form (SPEC.md §3), and its three users: rough and smooth pillar, self-exclusion."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.fiber.contact.pairlaw import soft_core
from fibersweep.fiber.contact.pillar import ROUGH, SMOOTH, PillarArrays, pillar_forces
from fibersweep.fiber.models.exclusion import exclusion_forces, exclusion_jacobian

A = 2.0  # bead radius [µm]
CHI = 1.1
F_REF = 6 * math.pi * 0.34 * A * 600.0  # [pN]
R_EQS = {"rough": A + 0.6, "smooth": A, "self-exclusion": 2 * A}  # r_eq of each user [µm]


def _constants(r_eq: float) -> tuple[float, float, float, float]:
    r_cut = CHI * r_eq
    return r_cut, r_cut * r_cut, r_cut * r_cut - r_eq * r_eq, F_REF / r_eq


def _closed_form(r: float, r_eq: float) -> float:
    """|F| = (F_ref / r_eq) [(R² − r²)/(R² − r_eq²)]⁴ r for r < R (SPEC.md §3), else 0."""
    r_cut = CHI * r_eq
    if r >= r_cut:
        return 0.0
    return F_REF / r_eq * ((r_cut**2 - r**2) / (r_cut**2 - r_eq**2)) ** 4 * r


@pytest.mark.parametrize("user", sorted(R_EQS))
def test_soft_core_is_the_closed_form(user):
    """Force magnitude s·r against the closed form from 0.3 r_eq to the cutoff: relative
    1e-13 (the same arithmetic in another order: a few ulps, times 4 for w⁴). |F| = F_ref at
    r_eq (1e-14). At the cutoff s, g and k are exactly 0 (w = 0)."""
    r_eq = R_EQS[user]
    r_cut, r2c, den, amp = _constants(r_eq)
    for r in np.linspace(0.3 * r_eq, r_cut * (1 - 1e-9), 57):
        s, _, _ = soft_core(r * r, r2c, den, amp)
        assert s * r == pytest.approx(_closed_form(r, r_eq), rel=1e-13)
    s, _, _ = soft_core(r_eq * r_eq, r2c, den, amp)
    assert s * r_eq == pytest.approx(F_REF, rel=1e-14)
    assert soft_core(r2c, r2c, den, amp) == (0.0, 0.0, 0.0)


@pytest.mark.parametrize("user", sorted(R_EQS))
def test_soft_core_derivatives_against_central_differences(user):
    """g: the Jacobian ∂F/∂d = s I − g d dᵀ of F(d) = s(|d|²) d, and k = |d|F|/dr|, against
    central differences of the closed form (step 1e-6 r_eq): within 1e-6 of the largest
    entry (truncation ~1e-12, round-off ~1e-10 relative)."""
    r_eq = R_EQS[user]
    r_cut, r2c, den, amp = _constants(r_eq)
    h = 1e-6 * r_eq

    def force(d: np.ndarray) -> np.ndarray:
        r = math.hypot(d[0], d[1])
        return _closed_form(r, r_eq) / r * d

    for r, ang in ((0.6 * r_eq, 0.3), (r_eq, 1.9), (0.5 * (r_eq + r_cut), -2.4)):
        d = r * np.array([math.cos(ang), math.sin(ang)])
        s, g, k = soft_core(r * r, r2c, den, amp)
        jac = s * np.eye(2) - g * np.outer(d, d)
        ref = np.column_stack(
            [(force(d + h * e) - force(d - h * e)) / (2 * h) for e in np.eye(2)]
        )
        assert np.max(np.abs(jac - ref)) < 1e-6 * np.max(np.abs(ref))
        dfdr = (_closed_form(r + h, r_eq) - _closed_form(r - h, r_eq)) / (2 * h)
        assert k == pytest.approx(abs(dfdr), rel=1e-6)


def test_every_user_applies_the_one_law():
    """The rough pillar (one pillar bead), the smooth pillar (a circle's outline) and the
    self-exclusion (two beads |i − j| = 3 apart) give the law's force and stiffness at the
    same distances: relative 1e-14 (they inline the same kernel)."""
    no_curves = np.zeros((0, 3, 2))
    for r_rel in (0.5, 0.9, 1.0, 1.05):
        # rough: a pillar bead at the origin (a point-like circle outline there)
        r_eq = R_EQS["rough"]
        r_cut, r2c, den, amp = _constants(r_eq)
        rough = PillarArrays(ROUGH, np.zeros((0, 2)), np.zeros(1), np.zeros(1), no_curves,
                             r_cut, r_eq, F_REF, np.array([0.0, 0.0, 1e-12]))  # fmt: skip
        r = r_rel * r_eq
        bx, by = np.array([r * math.cos(0.4)]), np.array([r * math.sin(0.4)])
        out = [np.zeros(1) for _ in range(4)]
        pillar_forces(rough, bx, by, *out)
        s, _, k = soft_core(r * r, r2c, den, amp)
        assert math.hypot(out[0][0], out[1][0]) == pytest.approx(s * r, rel=1e-14)
        assert out[0][0] > 0 and out[1][0] > 0  # pushed away from the pillar bead
        assert out[2][0] == pytest.approx(k, rel=1e-14)
        # smooth: a circular pillar of radius 20 µm; r is the distance to its outline
        r_eq = R_EQS["smooth"]
        r_cut, r2c, den, amp = _constants(r_eq)
        smooth = PillarArrays(SMOOTH, np.zeros((0, 2)), np.zeros(0), np.zeros(0), no_curves,
                              r_cut, r_eq, F_REF, np.array([0.0, 0.0, 20.0]))  # fmt: skip
        r = r_rel * r_eq
        bx, by = np.array([0.0]), np.array([20.0 + r])
        out = [np.zeros(1) for _ in range(4)]
        pillar_forces(smooth, bx, by, *out)
        s, _, k = soft_core(r * r, r2c, den, amp)
        assert out[1][0] == pytest.approx(s * r, rel=1e-12)  # r from 20 + r: 1e-15 · 20/r
        assert out[2][0] == pytest.approx(k, rel=1e-12)
        # self-exclusion: beads 0 and 3 at distance r, forces equal and opposite
        r_eq = R_EQS["self-exclusion"]
        r_cut, r2c, den, amp = _constants(r_eq)
        r = r_rel * r_eq
        x = np.array([0.0, 50.0, 60.0, r])
        y = np.zeros(4)
        fx, fy = np.zeros(4), np.zeros(4)
        exclusion_forces(x, y, 3, r_cut, r_eq, F_REF, fx, fy)
        s, g, _ = soft_core(r * r, r2c, den, amp)
        assert -fx[0] == fx[3] == pytest.approx(s * r, rel=1e-14)
        jac = np.zeros((8, 8))
        exclusion_jacobian(x, y, 3, r_cut, r_eq, F_REF, jac)
        assert jac[0, 0] == pytest.approx(s - g * r * r, rel=1e-12, abs=1e-12 * amp)
        assert jac[1, 1] == pytest.approx(s, rel=1e-14)
