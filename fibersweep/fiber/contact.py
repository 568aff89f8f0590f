"""Fiber-pillar repulsion: the rough pillar (small beads) and the smooth pillar (Bézier outline).

Rough (SPEC section 3): pillar beads of radius a_obs centred on the outline,
2 a_obs apart (a bead on each vertex); a fiber bead at centre distance r < R_ref
from a pillar bead is pushed away with
F = (F_ref / (a + a_obs)) · w⁴ · r,  w = (R_ref² − r²) / (R_ref² − (a + a_obs)²).
Smooth: three sides and three corners rounded with radius r_c, each a quadratic
Bézier curve; the nearest point on a curve is a root of a cubic in the curve
parameter; the force is normal, F = (F_ref / a) · w⁴ · R with
w = (R_ref² − R²) / (R_ref² − a²) and R the bead-centre-to-curve distance.

Only beads whose centre is closer than R_ref to the triangle's outline are
checked (a cheap bound: both pillars lie on or inside the triangle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np

from fibersweep.fiber.settings import ContactSettings
from fibersweep.units import Geometry

__all__ = [
    "ROUGH",
    "SMOOTH",
    "Pillar",
    "contact_forces",
    "cubic_real_roots",
    "make_pillar",
    "outline_distance",
    "pillar_forces",
]

ROUGH = 0
SMOOTH = 1


@nb.njit(cache=True)
def outline_distance(px: float, py: float, verts: np.ndarray) -> float:
    """Signed distance [µm] from a point to a CCW triangle's outline (negative inside)."""
    best = 1e300
    inside = True
    for k in range(3):
        ax = verts[k, 0]
        ay = verts[k, 1]
        bx = verts[(k + 1) % 3, 0]
        by = verts[(k + 1) % 3, 1]
        ex = bx - ax
        ey = by - ay
        if ex * (py - ay) - ey * (px - ax) <= 0.0:
            inside = False
        t = ((px - ax) * ex + (py - ay) * ey) / (ex * ex + ey * ey)
        t = min(1.0, max(0.0, t))
        dx = px - (ax + t * ex)
        dy = py - (ay + t * ey)
        d = math.sqrt(dx * dx + dy * dy)
        if d < best:
            best = d
    return -best if inside else best


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
def _bezier_nearest(px: float, py: float, ctrl: np.ndarray, roots: np.ndarray):
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


@nb.njit(cache=True)
def pillar_forces(
    kind: int,
    bx: np.ndarray,
    by: np.ndarray,
    verts: np.ndarray,
    pbx: np.ndarray,
    pby: np.ndarray,
    curves: np.ndarray,
    r_cut: float,
    r_eq: float,
    f_ref: float,
    fx: np.ndarray,
    fy: np.ndarray,
    stiff: np.ndarray,
    dist: np.ndarray,
):
    """Contact forces on fiber beads (overwrites fx, fy, stiff, dist).

    Parameters
    ----------
    kind : int
        ROUGH (0) or SMOOTH (1).
    bx, by : ndarray, shape (n,)
        Fiber bead centres [µm].
    verts : ndarray, shape (3, 2)
        Triangle vertices (CCW) [µm].
    pbx, pby : ndarray, shape (m,)
        Pillar bead centres (rough) [µm].
    curves : ndarray, shape (6, 3, 2)
        Bézier control points (smooth) [µm].
    r_cut, r_eq : float
        Cutoff R_ref and the distance where |F| = F_ref (a + a_obs, or a) [µm].
    f_ref : float
        Force scale [pN].
    fx, fy : ndarray, shape (n,)
        Force on each bead [pN].
    stiff : ndarray, shape (n,)
        Sum over contact pairs of |d|F|/dr| [pN/µm] (time-step bound).
    dist : ndarray, shape (n,)
        Signed bead-centre distance to the contact surface [µm]: the triangle
        outline (rough, and any bead farther than R_ref), or the rounded Bézier
        outline (smooth, beads closer than R_ref to the triangle).

    Returns
    -------
    (any_contact, cx, cy) : (bool, float, float)
        Whether any force is non-zero, and the pillar-side point of the
        strongest pair (the contact point) [µm].
    """
    n = bx.shape[0]
    r2c = r_cut * r_cut
    den = r2c - r_eq * r_eq
    amp = f_ref / r_eq
    roots = np.empty(3)
    any_c = False
    fmax = 0.0
    cx = math.nan
    cy = math.nan
    for i in range(n):
        fx[i] = 0.0
        fy[i] = 0.0
        stiff[i] = 0.0
        d_out = outline_distance(bx[i], by[i], verts)
        dist[i] = d_out
        if d_out >= r_cut:
            continue
        if kind == ROUGH:
            for j in range(pbx.shape[0]):
                rx = pbx[j] - bx[i]
                ry = pby[j] - by[i]
                r2 = rx * rx + ry * ry
                if r2 >= r2c:
                    continue
                w = (r2c - r2) / den
                w3 = w * w * w
                r = math.sqrt(r2)
                # r_ij points to the pillar bead: the force pushes the fiber bead away.
                fx[i] -= amp * w3 * w * rx
                fy[i] -= amp * w3 * w * ry
                fm = amp * w3 * w * r
                stiff[i] += abs(amp * (w3 * w - 8.0 * w3 * r2 / den))
                any_c = True
                if fm > fmax:
                    fmax = fm
                    cx = pbx[j]
                    cy = pby[j]
        else:
            d_curve = 1e300
            s_curve = 1.0
            for k in range(curves.shape[0]):
                qx, qy, r, side = _bezier_nearest(bx[i], by[i], curves[k], roots)
                if side == 0.0:  # degenerate (sharp) corner: the triangle decides
                    side = -1.0 if d_out < 0.0 else 1.0
                if r < d_curve:
                    d_curve = r
                    s_curve = side
                if r >= r_cut:
                    continue
                w = (r2c - r * r) / den
                w3 = w * w * w
                # push along the outward normal even if the centre crossed the curve
                ex = side * (bx[i] - qx)
                ey = side * (by[i] - qy)
                fm = amp * w3 * w * r
                if r > 0.0:
                    fx[i] += fm * ex / r
                    fy[i] += fm * ey / r
                stiff[i] += abs(amp * (w3 * w - 8.0 * w3 * r * r / den))
                any_c = True
                if fm > fmax:
                    fmax = fm
                    cx = qx
                    cy = qy
            # distance to the rounded outline itself (the triangle's is only a bound)
            dist[i] = s_curve * d_curve
    return any_c, cx, cy


@dataclass(frozen=True)
class Pillar:
    """Contact description of the pillar, as arrays the kernels read.

    Attributes
    ----------
    kind : int
        ROUGH or SMOOTH.
    vertices : ndarray, shape (3, 2)
    beads : ndarray, shape (m, 2)
        Rough pillar bead centres [µm] (empty for smooth).
    curves : ndarray, shape (6, 3, 2)
        Smooth outline control points [µm].
    r_cut, r_eq, f_ref : float
        R_ref [µm], the distance where |F| = F_ref [µm], F_ref [pN].
    """

    kind: int
    vertices: np.ndarray
    beads: np.ndarray
    curves: np.ndarray
    r_cut: float
    r_eq: float
    f_ref: float

    @property
    def layer(self) -> float:
        """Thickness of the contact layer R_ref − r_eq [µm]."""
        return self.r_cut - self.r_eq


def rough_beads(vertices: np.ndarray, a_obs: float) -> np.ndarray:
    """Pillar bead centres on the outline, about 2 a_obs apart, one on each vertex, (m, 2)."""
    pts = []
    for k in range(3):
        p0 = vertices[k]
        p1 = vertices[(k + 1) % 3]
        side = float(np.hypot(*(p1 - p0)))
        m = max(1, int(round(side / (2.0 * a_obs))))
        t = np.arange(m) / m
        pts.append(p0 + t[:, None] * (p1 - p0))
    return np.ascontiguousarray(np.concatenate(pts))


def smooth_curves(vertices: np.ndarray, corner_radius: float) -> np.ndarray:
    """Six quadratic Bézier curves (3, 2) each: corner k then side k→k+1, shape (6, 3, 2).

    A corner of radius r of a 60° wedge is tangent to the sides at r·√3 from the vertex.
    """
    t = corner_radius * math.sqrt(3.0)
    out = np.empty((6, 3, 2))
    for k in range(3):
        v = vertices[k]
        vp = vertices[(k - 1) % 3]
        vn = vertices[(k + 1) % 3]
        up = (vp - v) / np.hypot(*(vp - v))
        un = (vn - v) / np.hypot(*(vn - v))
        out[2 * k] = [v + t * up, v, v + t * un]
        start = v + t * un
        end = vn - t * un
        out[2 * k + 1] = [start, 0.5 * (start + end), end]
    return out


def make_pillar(
    geometry: Geometry, contact: ContactSettings, bead_radius: float, f_ref: float
) -> Pillar:
    """Build the pillar's contact arrays from the geometry and contact settings."""
    v = np.ascontiguousarray(geometry.vertices)
    if contact.pillar == "rough":
        a_obs = contact.obstacle_bead_radius
        r_eq = bead_radius + a_obs
        beads = rough_beads(v, a_obs)
        return Pillar(ROUGH, v, beads, np.zeros((6, 3, 2)), contact.chi * r_eq, r_eq, f_ref)
    r_eq = bead_radius
    curves = smooth_curves(v, contact.corner_radius)
    return Pillar(SMOOTH, v, np.zeros((0, 2)), curves, contact.chi * r_eq, r_eq, f_ref)


def contact_forces(pillar: Pillar, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Contact forces [pN] on beads at ``positions`` (n, 2) [µm], and their outline distances.

    Returns
    -------
    forces : ndarray, shape (n, 2)
    distance : ndarray, shape (n,)
        Signed centre distance to the triangle outline [µm] (negative inside).
    """
    p = np.ascontiguousarray(positions, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"positions must have shape (n, 2), got {p.shape}")
    n = p.shape[0]
    fx, fy, st, d = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    pillar_forces(
        pillar.kind,
        np.ascontiguousarray(p[:, 0]),
        np.ascontiguousarray(p[:, 1]),
        pillar.vertices,
        np.ascontiguousarray(pillar.beads[:, 0]),
        np.ascontiguousarray(pillar.beads[:, 1]),
        pillar.curves,
        pillar.r_cut,
        pillar.r_eq,
        pillar.f_ref,
        fx,
        fy,
        st,
        d,
    )
    return np.column_stack([fx, fy]), d
