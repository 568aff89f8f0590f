"""Pillar shapes (fibersweep.geometry) against analytic values and independent computations."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.geometry import Circle, ConvexPolygon, check_shape_name, pillar_shape
from fibersweep.geometry.pillars import PILLAR_SHAPES, centroid_height, unit_width

RNG = np.random.default_rng(7)
HEX = [(math.cos(a), math.sin(a)) for a in np.linspace(0, 2 * math.pi, 6, endpoint=False)]


def _bisect_entry(shape, x, y, ex, ey, n=200) -> float:
    """Independent entry fraction: first sample inside along the segment, refined by bisection."""
    t = np.linspace(0.0, 1.0, n + 1)
    ins = shape.signed_distance(x + t * ex, y + t * ey) < 0
    if not ins.any():
        return math.nan
    k = int(np.argmax(ins))
    if k == 0:
        return 0.0
    lo, hi = t[k - 1], t[k]
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if shape.signed_distance(x + mid * ex, y + mid * ey) < 0:
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)


def test_circle_link_fraction_is_exact():
    """q of every in-plane lattice link into a circle equals the root of |p + t e − c| = r
    (closed form here, bisection in the test): tolerance 1e-9 of a link."""
    c = Circle(10.3, 9.7, 4.6)
    pts = RNG.uniform(3.0, 17.0, size=(400, 2))
    pts = pts[c.signed_distance(pts[:, 0], pts[:, 1]) > 1e-3]
    hits = 0
    for ex, ey in [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (-1, 1), (1, -1), (-1, -1)]:
        t = c.link_entry(pts[:, 0], pts[:, 1], ex, ey)
        for (x, y), tq in zip(pts, t, strict=True):
            ref = _bisect_entry(c, x, y, ex, ey)
            if math.isnan(ref):
                assert math.isnan(tq) or tq > 1 - 1e-9
                continue
            hits += 1
            assert tq == pytest.approx(ref, abs=1e-9)
            # the entry point lies on the circle to rounding
            assert abs(c.signed_distance(x + tq * ex, y + tq * ey)) < 1e-9
    assert hits > 50


def test_circle_link_fraction_hand_values():
    c = Circle(0.0, 0.0, 1.0)
    # from (-1.5, 0) along +x: enters at x = -1, t = 0.5; along the diagonal from (-1, -1):
    # |(-1 + t, -1 + t)| = 1 gives t = 1 - 1/sqrt(2)
    assert c.link_entry(np.array(-1.5), np.array(0.0), 1, 0) == pytest.approx(0.5, abs=1e-15)
    assert c.link_entry(np.array(-1.0), np.array(-1.0), 1, 1) == pytest.approx(
        1 - 1 / math.sqrt(2), abs=1e-15
    )
    # a tangent link (y = 1 line) only grazes: NaN open, t = 1 closed... from (-1, 1) along +x
    assert np.isnan(c.link_entry(np.array(-1.0), np.array(1.0), 1, 0))
    assert c.link_entry(np.array(-1.0), np.array(1.0), 1, 0, closed=True) == pytest.approx(1.0)


@pytest.mark.parametrize("name", ["triangle", "square", "polygon"])
def test_polygon_signed_distance_against_dense_outline(name):
    """Exact signed distance vs the distance to 20 000 points on the outline: the sampled
    distance is ≥ the exact one and within the sampling spacing (< 0.01 µm here)."""
    kw = {"vertices": HEX} if name == "polygon" else {}
    shape = pillar_shape(name, 30.0, 50.0, 20.0, rotation=17.0, **kw)
    v = shape.vertices
    per = np.linspace(0, 1, 20000 // len(v), endpoint=False)
    dense = np.concatenate(
        [v[k] + per[:, None] * (v[(k + 1) % len(v)] - v[k]) for k in range(len(v))]
    )
    pts = RNG.uniform([0, -10], [100, 70], size=(300, 2))
    d = shape.signed_distance(pts[:, 0], pts[:, 1])
    brute = np.min(
        np.hypot(pts[:, None, 0] - dense[None, :, 0], pts[:, None, 1] - dense[None, :, 1]), axis=1
    )
    spacing = max(np.hypot(*(v[(k + 1) % len(v)] - v[k])) for k in range(len(v))) * per[1]
    assert np.all(brute >= np.abs(d) - 1e-9)
    assert np.all(brute - np.abs(d) <= spacing)
    assert np.array_equal(d < 0, shape.inside(pts[:, 0], pts[:, 1]))
    # nearest point + outward normal: p = nearest + d n for points outside and inside
    near, normal, dist = shape.nearest(pts[:, 0], pts[:, 1])
    np.testing.assert_allclose(near + dist[:, None] * normal, pts, atol=1e-9)
    np.testing.assert_allclose(np.hypot(*normal.T), 1.0, atol=1e-12)


@pytest.mark.parametrize("name", PILLAR_SHAPES)
def test_rotation_invariance(name):
    """Distances and link fractions of a rotated shape at rotated points equal the unrotated
    ones (tolerance 1e-9 µm); rotation is about the centroid."""
    kw = {"vertices": HEX} if name == "polygon" else {}
    base = pillar_shape(name, 40.0, 100.0, 50.0, **kw)
    for deg in (0.0, 23.0, 90.0, 217.5):
        rot = base.rotated(deg, base.centroid)
        c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
        pts = RNG.uniform([40, -10], [160, 110], size=(200, 2))
        rel = pts - np.array(base.centroid)
        turned = np.array(base.centroid) + rel @ np.array([[c, s], [-s, c]])
        np.testing.assert_allclose(
            rot.signed_distance(turned[:, 0], turned[:, 1]),
            base.signed_distance(pts[:, 0], pts[:, 1]),
            atol=1e-9,
        )
        # a link along e rotates to a segment along R e: same entry fraction
        e = np.array([1.0, 1.0])
        er = e @ np.array([[c, s], [-s, c]])
        a = base.link_entry(pts[:, 0], pts[:, 1], *e)
        b = rot.link_entry(turned[:, 0], turned[:, 1], *er)
        np.testing.assert_allclose(a, b, atol=1e-9)
        assert rot.area == pytest.approx(base.area, rel=1e-12)


def test_named_shapes_sizes_and_placement():
    h = 75.0
    tri = pillar_shape("triangle", h, 1200.0, 375.0)
    half = 2.0 * h / math.sqrt(3.0) / 2.0
    # the model's triangle, bit for bit
    assert np.array_equal(tri.vertices, [[1200 - half, 375.0], [1200 + half, 375.0], [1200, 450]])
    assert unit_width("triangle", h) == 2 * h / math.sqrt(3)
    assert centroid_height("triangle", h) == h / 3
    circ = pillar_shape("circle", h, 1200.0, 375.0)
    assert (circ.cx, circ.cy, circ.radius) == (1200.0, 375.0 + h / 2, h / 2)
    sq = pillar_shape("square", h, 1200.0, 375.0)
    assert sq.bounds == pytest.approx((1200 - h / 2, 375.0, 1200 + h / 2, 375 + h))
    assert sq.area == pytest.approx(h * h, rel=1e-14)
    # a square turned 45°: diamond, lowest corner on the base line, centroid at x = 1200
    dia = pillar_shape("square", h, 1200.0, 375.0, rotation=45.0)
    assert dia.bounds[1] == pytest.approx(375.0, abs=1e-12)
    assert dia.bounds[3] - dia.bounds[1] == pytest.approx(h * math.sqrt(2), rel=1e-12)
    assert dia.centroid[0] == pytest.approx(1200.0, abs=1e-12)
    # triangle turned 180°: apex down at the base line, flat side at the top
    down = pillar_shape("triangle", h, 1200.0, 375.0, rotation=180.0)
    assert down.bounds[1] == pytest.approx(375.0, abs=1e-12)
    assert centroid_height("triangle", h, 180.0) == pytest.approx(2 * h / 3, rel=1e-12)
    # polygon vertices are in units of h, any origin
    poly = pillar_shape("polygon", h, 1200.0, 375.0, vertices=[(5, 5), (6, 5), (6, 6), (5, 6)])
    assert poly.bounds == pytest.approx(sq.bounds, abs=1e-12)


def test_unknown_shape_lists_valid_ones():
    with pytest.raises(
        ValueError, match="did you mean 'circle'.*triangle, circle, square, polygon"
    ):
        check_shape_name("cirle")
    with pytest.raises(ValueError, match="valid shapes: triangle, circle, square, polygon"):
        pillar_shape("blob", 1.0, 0.0, 0.0)


def test_polygon_checks():
    with pytest.raises(ValueError, match="convex"):
        ConvexPolygon.from_vertices([(0, 0), (2, 0), (1, 0.5), (2, 2), (0, 2)])
    with pytest.raises(ValueError, match="at least 3"):
        ConvexPolygon.from_vertices([(0, 0), (1, 0)])
    with pytest.raises(ValueError, match="collinear"):
        ConvexPolygon.from_vertices([(0, 0), (1, 0), (2, 0), (1, 1)])
    # a pentagram winds twice: every turn has one sign, but it is not convex
    star = [(math.cos(a), math.sin(a)) for a in np.arange(5) * 4 * math.pi / 5]
    with pytest.raises(ValueError, match="convex"):
        ConvexPolygon.from_vertices(star)
    cw = ConvexPolygon.from_vertices([(0, 0), (0, 1), (1, 1), (1, 0)])
    assert cw.area == pytest.approx(1.0)  # re-ordered counter-clockwise


def test_span_at():
    tri = pillar_shape("triangle", 75.0, 1200.0, 375.0)
    lo, hi = tri.span_at(np.array([1200.0, 1210.0, 1300.0]))
    assert lo[0] == 375.0 and lo[1] == 375.0 and np.isnan(lo[2])
    assert hi[0] == pytest.approx(450.0) and hi[1] == pytest.approx(450.0 - 10.0 * math.sqrt(3))
    c = Circle(0.0, 0.0, 2.0)
    lo, hi = c.span_at(np.array([0.0, 1.0]))
    np.testing.assert_allclose(lo, [-2.0, -math.sqrt(3)])
    np.testing.assert_allclose(hi, [2.0, math.sqrt(3)])
