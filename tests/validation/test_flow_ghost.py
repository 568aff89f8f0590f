"""Ghost values inside a sub-grid wall (fibersweep.flow.ghost).

A shear flow u = s d t along a straight wall (d: signed distance from the wall
line, t: its unit tangent) is linear and odd in d, so the mirror reflection
must reproduce it exactly at every ghost node, whatever fraction q of a cell
separates the wall from the nodes and whatever its angle; the IB-interpolated
velocity on the wall must then be that of a linear field through zero. With
the solid nodes left at zero (what the tracer saw before) the velocity on the
wall depends on q: that is the lattice pattern the ghosts remove.
"""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.flow.field import FlowField
from fibersweep.flow.ghost import extend_into_wall, ghost_stencil
from fibersweep.units import Fluid, Geometry

DX = 4.0
NX, NY = 40, 40


def half_plane(q: float, angle_deg: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A wall through the point (x0, y0) at ``angle_deg`` to x, solid below it.

    The wall passes a fraction q of a cell above node row 20 at x0 = 80 µm.
    Returns (vertices of a large CCW polygon covering the solid side [µm],
    unit tangent, unit normal pointing into the fluid).
    """
    a = np.radians(angle_deg)
    t = np.array([np.cos(a), np.sin(a)])
    n = np.array([-t[1], t[0]])
    p0 = np.array([80.0, (20 + 0.5 + q) * DX])
    big = 1e4
    verts = np.array([p0 - big * t, p0 - big * t - big * n, p0 + big * t - big * n, p0 + big * t])
    return verts, t, n


def shear(verts, t, n, s=3.0):
    x = (np.arange(NX) + 0.5) * DX
    y = (np.arange(NY) + 0.5) * DX
    X, Y = np.meshgrid(x, y, indexing="ij")
    d = (X - verts[0, 0]) * n[0] + (Y - verts[0, 1]) * n[1]
    return s * d * t[0], s * d * t[1], d < 1e-9 * DX, d


@pytest.mark.parametrize("angle", [0.0, 60.0, -60.0])
@pytest.mark.parametrize("q", [0.1, 0.3, 0.5, 0.7, 0.9])
def test_reflection_is_exact_for_a_linear_wall_flow(q, angle):
    verts, t, n = half_plane(q, angle)
    ux, uy, solid, d = shear(verts, t, n)
    ghosts = ghost_stencil(solid, verts, DX)[0]
    # ghosts near the channel ends (y = 0 wall, x period) see those boundaries: judge the middle
    gi, gj = np.divmod(ghosts, NY)
    mid = (gi > 8) & (gi < NX - 8) & (gj > 5) & (gj < NY - 5)
    assert mid.sum() > 20
    ex, ey = extend_into_wall(np.where(solid, 0, ux), np.where(solid, 0, uy), solid, verts, DX)
    # tolerance: float64 rounding of the sparse solve
    np.testing.assert_allclose(ex.ravel()[ghosts[mid]], ux.ravel()[ghosts[mid]], atol=1e-9)
    np.testing.assert_allclose(ey.ravel()[ghosts[mid]], uy.ravel()[ghosts[mid]], atol=1e-9)
    fluid = ~solid
    np.testing.assert_array_equal(ex[fluid], ux[fluid])


def _wall_speed(q: float, fill: bool) -> float:
    """IB-interpolated speed on the wall (horizontal, mid-channel), / (s Δx)."""
    verts, t, n = half_plane(q, 0.0)
    ux, uy, solid, _ = shear(verts, t, n, s=1.0)
    ux, uy = np.where(solid, 0, ux), np.where(solid, 0, uy)
    if fill:
        ux, uy = extend_into_wall(ux, uy, solid, verts, DX)
    geom = Geometry()
    field = FlowField(ux=ux, uy=uy, dx=DX, geometry=geom, fluid=Fluid(), solid=solid)
    xs = np.linspace(60.0, 100.0, 9)
    pts = np.column_stack([xs, np.full_like(xs, (20 + 0.5 + q) * DX)])
    return float(np.abs(field.velocity(pts)[:, 0]).max() / DX)


def test_wall_seen_by_the_tracer_does_not_depend_on_q():
    qs = [0.1, 0.3, 0.5, 0.7, 0.9]
    filled = [_wall_speed(q, True) for q in qs]
    raw = [_wall_speed(q, False) for q in qs]
    # measured: with ghosts 0.000-0.019 s Δx (the cosine IB kernel reproduces a
    # linear field only to a few % of s Δx); left at zero the solid nodes give
    # 0.27-0.32 s Δx: the tracer's wall sits about 0.3 cells inside the solid,
    # by an amount that depends on q (spread 0.057 s Δx over q)
    assert max(filled) < 0.025, filled
    assert min(raw) > 0.25, raw
    assert max(raw) - min(raw) > 0.04, raw
