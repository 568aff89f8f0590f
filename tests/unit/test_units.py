"""Geometry of the pillar and unit helpers against hand-computed values."""

import math

import numpy as np
import pytest

from fibersweep.units import Fluid, Geometry


def test_pillar_matches_spec_placement():
    g = Geometry()
    # l_obs = 2 h / sqrt(3) = 86.60 µm (SPEC table), exact to rounding.
    assert g.pillar_base_length == pytest.approx(86.6025, abs=1e-4)
    v = g.vertices
    # Base centre at x = L/2, centroid on the centreline (SPEC decision).
    assert v[:2, 1] == pytest.approx([400 - 25, 400 - 25])
    assert g.centroid == pytest.approx((1200.0, 400.0))
    assert v[2] == pytest.approx([1200.0, 450.0])
    # Equilateral: all sides equal to l_obs within 1e-12 relative.
    sides = [np.linalg.norm(v[k] - v[(k + 1) % 3]) for k in range(3)]
    assert sides == pytest.approx([g.pillar_base_length] * 3, rel=1e-12)


def test_y_over_h_round_trip():
    g = Geometry()
    for s in (0.0, 1 / 3, 1.0, -0.2):
        assert g.y_over_h(g.y_from_base(s)) == pytest.approx(s, abs=1e-12)
    assert g.y_from_base(1.0) == pytest.approx(g.vertices[2, 1])


def test_inside_pillar():
    g = Geometry()
    cx, cy = g.centroid
    assert g.inside_pillar(np.array(cx), np.array(cy))
    # Just outside each vertex, and far away.
    for vx, vy in g.vertices:
        assert not g.inside_pillar(np.array(vx + 1e-6 * (vx - cx)), np.array(vy + 1e-6 * (vy - cy)))
    assert not g.inside_pillar(np.array(10.0), np.array(10.0))
    # Area check by Monte Carlo-free quadrature on a fine grid: within 0.5 %.
    x = np.linspace(1150, 1250, 801)
    y = np.linspace(370, 455, 681)
    X, Y = np.meshgrid(x, y)
    area = g.inside_pillar(X, Y).sum() * (x[1] - x[0]) * (y[1] - y[0])
    exact = 0.5 * g.pillar_base_length * g.pillar_height
    assert area == pytest.approx(exact, rel=5e-3)


def test_fits_and_reynolds():
    assert Geometry().fits()
    assert not Geometry(width=100.0).fits()
    # SPEC: Re = rho U h / mu ~ 1e-4.
    re = Fluid().reynolds(75.0)
    assert re == pytest.approx(1190 * 600e-6 * 75e-6 / 0.34, rel=1e-12)
    assert 1e-5 < re < 1e-3
    assert math.isclose(Fluid().u_center, 600.0)
