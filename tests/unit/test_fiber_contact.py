"""Pillar contact: cubic roots, Bézier nearest points, force laws, outline distance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.config.fiber import ContactSettings
from fibersweep.fiber.contact.bezier import bezier_nearest, cubic_real_roots
from fibersweep.fiber.contact.pillar import (
    ROUGH,
    SMOOTH,
    PillarArrays,
    contact_forces,
    make_pillar,
    outline_distance,
    pillar_forces,
)
from fibersweep.units import Geometry

A = 2.0
F_REF = 6 * math.pi * 0.34 * A * 600.0
GEO = Geometry()


def test_cubic_roots_against_numpy():
    rng = np.random.default_rng(0)
    out = np.empty(3)
    for _ in range(300):
        c = rng.normal(size=4)
        k = cubic_real_roots(c[0], c[1], c[2], c[3], out)
        ref = np.roots(c)
        ref = np.sort(ref[np.abs(ref.imag) < 1e-7].real)
        assert k == ref.size
        np.testing.assert_allclose(np.sort(out[:k]), ref, atol=1e-8)  # tolerance: double roots
    # degenerate: quadratic, linear
    assert cubic_real_roots(0.0, 1.0, -3.0, 2.0, out) == 2
    np.testing.assert_allclose(np.sort(out[:2]), [1.0, 2.0])
    assert cubic_real_roots(0.0, 0.0, 2.0, -1.0, out) == 1 and out[0] == 0.5


def test_bezier_nearest_against_brute_force():
    rng = np.random.default_rng(3)
    s = np.linspace(0, 1, 200001)
    roots = np.empty(3)
    for _ in range(50):
        ctrl = rng.uniform(-5, 5, size=(3, 2))
        p = rng.uniform(-8, 8, size=2)
        curve = (
            (1 - s)[:, None] ** 2 * ctrl[0]
            + 2 * ((1 - s) * s)[:, None] * ctrl[1]
            + s[:, None] ** 2 * ctrl[2]
        )
        d_ref = np.min(np.hypot(*(curve - p).T))
        _, _, d, _ = bezier_nearest(p[0], p[1], ctrl, roots)
        assert d == pytest.approx(d_ref, abs=1e-6)  # brute force on 2e5 samples


def test_outline_distance_against_sampling():
    v = GEO.vertices
    rng = np.random.default_rng(5)
    t = np.linspace(0, 1, 20001)[:, None]
    pts = np.concatenate([v[k] + t * (v[(k + 1) % 3] - v[k]) for k in range(3)])
    for _ in range(100):
        p = GEO.centroid + rng.normal(scale=40, size=2)
        d = outline_distance(p[0], p[1], v)
        ref = np.min(np.hypot(*(pts - p).T))
        inside = bool(GEO.inside_pillar(np.array(p[0]), np.array(p[1])))
        assert abs(d) == pytest.approx(ref, abs=1e-3)
        assert (d < 0) == inside


def test_rough_pillar_beads_on_outline():
    pil = make_pillar(GEO, ContactSettings(), A, F_REF)
    gaps = np.hypot(*np.diff(np.vstack([pil.beads, pil.beads[:1]]), axis=0).T)
    assert gaps.max() == pytest.approx(1.2, rel=0.02)  # 2 a_obs apart (rounded per side)
    for b in pil.beads:
        assert abs(outline_distance(b[0], b[1], pil.vertices)) < 1e-9
    assert pil.r_cut == pytest.approx(1.1 * (A + 0.6))


def test_rough_force_law_single_pair():
    """F = (F_ref/(a+a_obs)) w⁴ r away from the pillar bead; F_ref at a + a_obs; 0 past R_ref."""
    r_eq, r_cut = A + 0.6, 1.1 * (A + 0.6)
    # one pillar bead at the origin, on the outline of a triangle
    verts_near = np.array([[-50.0, 0.0], [50.0, 0.0], [0.0, -80.0]])
    pil = PillarArrays(
        ROUGH, verts_near, np.array([0.0]), np.array([0.0]), np.zeros((6, 3, 2)), r_cut, r_eq, F_REF
    )
    for r in (2.4, r_eq, 2.7, 2.85, r_cut, 3.0):
        fx, fy, st, d = np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1)
        pillar_forces(pil, np.array([0.0]), np.array([r]), fx, fy, st, d)
        w = max((r_cut**2 - r**2) / (r_cut**2 - r_eq**2), 0.0)
        expect = F_REF / r_eq * w**4 * r if r < r_cut else 0.0
        assert fx[0] == pytest.approx(0.0, abs=1e-9)
        assert fy[0] == pytest.approx(expect, rel=1e-12, abs=1e-12)  # pushed to +y, away
    fx, fy, st, d = np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1)
    pillar_forces(pil, np.array([0.0]), np.array([r_eq]), fx, fy, st, d)
    assert fy[0] == pytest.approx(F_REF, rel=1e-12)
    # stiffness = |d|F|/dr| by central differences (tolerance 1e-5 relative)
    h = 1e-6
    f = [
        F_REF / r_eq * ((r_cut**2 - r**2) / (r_cut**2 - r_eq**2)) ** 4 * r
        for r in (r_eq + h, r_eq - h)
    ]
    assert st[0] == pytest.approx(abs(f[0] - f[1]) / (2 * h), rel=1e-5)


def test_smooth_pillar_normal_force_and_rounded_corners():
    pil = make_pillar(GEO, ContactSettings(pillar="smooth", corner_radius=2.0), A, F_REF)
    assert pil.kind == SMOOTH
    v = pil.vertices
    mid = 0.5 * (v[0] + v[1])
    f, d = contact_forces(pil, np.array([[mid[0] + 5.0, mid[1] - A]]))
    np.testing.assert_allclose(f[0], [0.0, -F_REF], atol=1e-6 * F_REF)  # R = a: F_ref, normal
    f, _ = contact_forces(pil, np.array([[mid[0], mid[1] - 1.1 * A - 1e-9]]))
    assert np.all(f == 0.0)
    # the rounded apex lies 1.5 µm below the sharp one (Bézier midpoint, t/2·cos30°, t = r_c√3):
    # a bead 2.0 µm above the sharp apex is 3.5 µm from the outline, beyond R_ref: no force
    f, _ = contact_forces(pil, np.array([[v[2, 0], v[2, 1] + 2.0]]))
    assert np.all(f == 0.0)
    # the smooth outline is continuous: curve ends meet
    c = pil.curves
    for k in range(6):
        np.testing.assert_allclose(c[k, 2], c[(k + 1) % 6, 0], atol=1e-12)
