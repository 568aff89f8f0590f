"""Deformation observables (fiber/models/deformation.py) on configurations with known answers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.fiber.models.deformation import deformation

A = 2.0
NO_CIRCLE = np.zeros(3)
FAR_SQUARE = np.array([[1e4, 1e4], [1e4 + 1, 1e4], [1e4 + 1, 1e4 + 1], [1e4, 1e4 + 1]])


def _arc(n: int, radius: float, spacing: float = 2 * A) -> np.ndarray:
    """n beads on a circle of the given radius [µm], ``spacing`` apart (chords)."""
    dphi = 2 * math.asin(spacing / (2 * radius))
    phi = dphi * (np.arange(n) - (n - 1) / 2)
    return np.column_stack([radius * np.sin(phi), radius * (1 - np.cos(phi))])


def test_straight_fiber():
    """Straight, unstretched: κ = 0, end-to-end ratio 1, tension 0, no wrap (exact)."""
    b = np.column_stack([np.arange(10) * 2 * A, np.zeros(10)])[None]
    d = deformation(b, np.ones(1), FAR_SQUARE, NO_CIRCLE, 2.86, A, 1e6)
    assert d["max_curvature"] == 0.0
    assert d["min_end_to_end"] == pytest.approx(1.0, abs=1e-12)
    assert d["max_tension"] == pytest.approx(0.0, abs=1e-6)
    assert d["max_wrap"] == 0.0


def test_arc_curvature_end_to_end_and_wrap_around_a_circle():
    """Beads on an arc of radius R hugging a circular pillar of radius R - 3 µm centred
    at the arc's centre: κ = φ/(2a) with φ = 2 asin(a/R) (1/R to O((a/R)²): rel. 1e-3 at
    R = 40 µm); end-to-end ratio = chord / contour (exact); wrap = (n - 2) φ over the
    interior beads (all beads are on the pillar: n - 2 turning angles)."""
    R, n = 40.0, 15
    b = _arc(n, R)
    phi = 2 * math.asin(A / R)
    circle = np.array([0.0, R, R - 3.0])
    d = deformation(b[None], np.ones(1), np.zeros((0, 2)), circle, 2.86, A, 1e6)
    assert d["max_curvature"] == pytest.approx(phi / (2 * A), rel=1e-9)
    assert d["max_curvature"] == pytest.approx(1 / R, rel=1e-3)
    chord = np.linalg.norm(b[-1] - b[0])
    assert d["min_end_to_end"] == pytest.approx(chord / ((n - 1) * 2 * A), rel=1e-12)
    assert d["max_wrap"] == pytest.approx(math.degrees((n - 2) * phi), rel=1e-9)


def test_wrap_only_in_contact_rows_and_tension_of_a_stretched_fiber():
    """A row not in contact has no wrap; a uniformly stretched fiber (segments 2a(1+ε))
    has tension (S/2a)(2aε) = E π a² ε [pN] (exact)."""
    eps = 1e-3
    b = np.column_stack([np.arange(8) * 2 * A * (1 + eps), np.zeros(8)])[None]
    arc = _arc(8, 30.0)[None]
    circle = np.array([0.0, 30.0, 27.0])
    d = deformation(np.concatenate([arc, b]), np.zeros(2), np.zeros((0, 2)), circle, 2.86, A, 1e6)
    assert d["max_wrap"] == 0.0
    assert d["max_tension"] == pytest.approx(1e6 * math.pi * A**2 * eps, rel=1e-6)


def test_bad_shape_is_refused():
    with pytest.raises(ValueError, match="beads"):
        deformation(np.zeros((0, 3, 2)), np.zeros(0), FAR_SQUARE, NO_CIRCLE, 2.86, A, 1e6)
