"""Quadratic Bézier outline of the smooth pillar: nearest points via the roots of a cubic."""

from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = ["bezier_nearest", "cubic_real_roots", "smooth_curves"]


@nb.njit(cache=True)
def _cbrt(x: float) -> float:
    return math.copysign(abs(x) ** (1.0 / 3.0), x)


@nb.njit(cache=True)
def cubic_real_roots(c3: float, c2: float, c1: float, c0: float, out: np.ndarray) -> int:
    """Real roots of c3 s³ + c2 s² + c1 s + c0 into ``out`` (size 3); returns their count.

    Degenerate leading coefficients fall back to the quadratic / linear case.
    """
    scale = abs(c2) + abs(c1) + abs(c0)
    if abs(c3) <= 1e-12 * scale or c3 == 0.0:
        if abs(c2) <= 1e-12 * (abs(c1) + abs(c0)) or c2 == 0.0:
            if c1 == 0.0:
                return 0
            out[0] = -c0 / c1
            return 1
        disc = c1 * c1 - 4.0 * c2 * c0
        if disc < 0.0:
            return 0
        sq = math.sqrt(disc)
        q = -0.5 * (c1 + math.copysign(sq, c1))
        if q == 0.0:
            out[0] = 0.0
            return 1
        out[0] = q / c2
        out[1] = c0 / q
        return 2
    a = c2 / c3
    b = c1 / c3
    c = c0 / c3
    p = b - a * a / 3.0
    q = 2.0 * a * a * a / 27.0 - a * b / 3.0 + c
    shift = -a / 3.0
    disc = 0.25 * q * q + p * p * p / 27.0
    if disc > 0.0:
        sq = math.sqrt(disc)
        out[0] = _cbrt(-0.5 * q + sq) + _cbrt(-0.5 * q - sq) + shift
        cnt = 1
    elif p == 0.0:
        out[0] = shift
        cnt = 1
    else:
        m = 2.0 * math.sqrt(-p / 3.0)
        arg = 3.0 * q / (p * m)
        arg = min(1.0, max(-1.0, arg))
        th = math.acos(arg) / 3.0
        for k in range(3):
            out[k] = m * math.cos(th - 2.0 * math.pi * k / 3.0) + shift
        cnt = 3
    # One Newton step polishes the closed-form roots.
    for k in range(cnt):
        s = out[k]
        f = ((c3 * s + c2) * s + c1) * s + c0
        df = (3.0 * c3 * s + 2.0 * c2) * s + c1
        if df != 0.0:
            out[k] = s - f / df
    return cnt


@nb.njit(cache=True)
def bezier_nearest(px: float, py: float, ctrl: np.ndarray, roots: np.ndarray):
    """Nearest point on the quadratic Bézier with control points ctrl (3, 2).

    Returns (x, y, distance, side): side is +1 when the point is on the right of
    the curve's direction (outside, for curves running counter-clockwise round
    the pillar), −1 on its left, 0 when the tangent vanishes.
    """
    ax = ctrl[0, 0] - 2.0 * ctrl[1, 0] + ctrl[2, 0]
    ay = ctrl[0, 1] - 2.0 * ctrl[1, 1] + ctrl[2, 1]
    bx = 2.0 * (ctrl[1, 0] - ctrl[0, 0])
    by = 2.0 * (ctrl[1, 1] - ctrl[0, 1])
    cx = ctrl[0, 0] - px
    cy = ctrl[0, 1] - py
    # d/ds |B(s) - p|² / 2 = (2A s + B)·(A s² + B s + C)
    c3 = 2.0 * (ax * ax + ay * ay)
    c2 = 3.0 * (ax * bx + ay * by)
    c1 = bx * bx + by * by + 2.0 * (ax * cx + ay * cy)
    c0 = bx * cx + by * cy
    cnt = cubic_real_roots(c3, c2, c1, c0, roots)
    best = 1e300
    qx = ctrl[0, 0]
    qy = ctrl[0, 1]
    sbest = 0.0
    for k in range(cnt + 2):
        if k < cnt:
            s = min(1.0, max(0.0, roots[k]))
        elif k == cnt:
            s = 0.0
        else:
            s = 1.0
        x = (ax * s + bx) * s + ctrl[0, 0]
        y = (ay * s + by) * s + ctrl[0, 1]
        d = math.sqrt((x - px) ** 2 + (y - py) ** 2)
        if d < best:
            best = d
            qx = x
            qy = y
            sbest = s
    tx = 2.0 * ax * sbest + bx
    ty = 2.0 * ay * sbest + by
    cross = tx * (py - qy) - ty * (px - qx)
    side = 0.0 if (tx == 0.0 and ty == 0.0) else (-1.0 if cross > 0.0 else 1.0)
    return qx, qy, best, side


def smooth_curves(vertices: np.ndarray, corner_radius: float) -> np.ndarray:
    """Quadratic Bézier curves (3, 2) each, corner k then side k→k+1, shape (2n, 3, 2).

    A corner of radius r with interior angle θ is tangent to its sides at
    r·cot(θ/2) from the vertex (r·√3 for the triangle's 60°, taken exactly).

    Raises
    ------
    ValueError
        If two corners' tangent points overlap on a side (r too large for it).
    """
    nv = len(vertices)
    out = np.empty((2 * nv, 3, 2))
    reach = np.empty(nv)
    for k in range(nv):
        v = vertices[k]
        up = (vertices[(k - 1) % nv] - v) / np.hypot(*(vertices[(k - 1) % nv] - v))
        un = (vertices[(k + 1) % nv] - v) / np.hypot(*(vertices[(k + 1) % nv] - v))
        cos_t = float(np.clip(up @ un, -1.0, 1.0))
        if abs(cos_t - 0.5) < 1e-12:
            reach[k] = corner_radius * math.sqrt(3.0)
        else:
            reach[k] = corner_radius * math.sqrt((1.0 + cos_t) / (1.0 - cos_t))
    for k in range(nv):
        v = vertices[k]
        vp = vertices[(k - 1) % nv]
        vn = vertices[(k + 1) % nv]
        up = (vp - v) / np.hypot(*(vp - v))
        un = (vn - v) / np.hypot(*(vn - v))
        side = float(np.hypot(*(vn - v)))
        if reach[k] + reach[(k + 1) % nv] > side * (1.0 + 1e-12):
            raise ValueError(
                f"corner_radius {corner_radius} µm is too large for the pillar's side of "
                f"{side:.3g} µm (its rounded corners overlap)"
            )
        t = reach[k]
        out[2 * k] = [v + t * up, v, v + t * un]
        start = v + t * un
        end = vn - reach[(k + 1) % nv] * un
        out[2 * k + 1] = [start, 0.5 * (start + end), end]
    return out
