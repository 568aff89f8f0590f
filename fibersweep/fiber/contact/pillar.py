"""Fiber-pillar repulsion: the rough pillar (small beads) and the smooth pillar (Bézier outline).

Both use the soft-core pair law of :mod:`fibersweep.fiber.contact.pairlaw`
(|F| = F_ref at r_eq, zero from the cutoff R_ref = χ r_eq on):

The cutoff is ``fiber.contact.law``'s: chi (the source's, R_ref = χ r_eq) or gap
(R_ref = r_eq + δ_r, a surface gap the same for every bead size;
:meth:`~fibersweep.config.fiber.ContactSettings.cutoff`).

- rough (docs/model.md): pillar beads of radius a_obs centred on the outline,
  2 a_obs apart (a bead on each vertex of a polygon); a fiber bead at centre
  distance r < R_ref from a pillar bead is pushed away from it, r_eq = a + a_obs;
- smooth: the polygon's sides and its corners rounded with radius r_c, each a
  quadratic Bézier curve; the nearest point on a curve is a root of a cubic in
  the curve parameter; the force is along the outward normal, r the
  bead-centre-to-curve distance, r_eq = a. A circular pillar is smooth
  already: its nearest point and normal are exact.

Any pillar shape of :mod:`fibersweep.geometry` (triangle, square, convex
polygon, circle). Only beads whose centre is closer than R_ref to the exact
outline are checked (a cheap bound: both pillars lie on or inside it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numba as nb
import numpy as np

from fibersweep.config.fiber import ContactSettings
from fibersweep.fiber.contact.bezier import bezier_nearest, smooth_curves
from fibersweep.fiber.contact.pairlaw import soft_core
from fibersweep.geometry import Circle
from fibersweep.units import Geometry

__all__ = [
    "ROUGH",
    "SMOOTH",
    "Pillar",
    "PillarArrays",
    "contact_force_scale",
    "contact_forces",
    "make_pillar",
    "outline_distance",
    "pillar_forces",
    "rough_beads",
    "rough_circle_beads",
    "shape_distance",
]

ROUGH = 0
SMOOTH = 1
_NO_CIRCLE = np.zeros(3)  # radius 0: the pillar is a polygon


class PillarArrays(NamedTuple):
    """The pillar as the Numba kernels read it (:meth:`Pillar.arrays`).

    Attributes
    ----------
    kind : int
        ROUGH (0) or SMOOTH (1).
    verts : ndarray, shape (n, 2)
        Polygon vertices (CCW) [µm]; shape (0, 2) for a circle.
    pbx, pby : ndarray, shape (m,)
        Rough pillar bead centres [µm] (empty for smooth).
    curves : ndarray, shape (2n, 3, 2)
        Smooth polygon's Bézier control points [µm] (empty for a circle).
    r_cut, r_eq : float
        Cutoff R_ref and the distance where |F| = F_ref (a + a_obs, or a) [µm].
    f_ref : float
        Force scale [pN].
    circle : ndarray, shape (3,)
        (x, y, radius) of a circular pillar [µm]; radius 0 for a polygon.
    """

    kind: int
    verts: np.ndarray
    pbx: np.ndarray
    pby: np.ndarray
    curves: np.ndarray
    r_cut: float
    r_eq: float
    f_ref: float
    circle: np.ndarray = _NO_CIRCLE


@nb.njit(cache=True)
def outline_distance(px: float, py: float, verts: np.ndarray) -> float:
    """Signed distance [µm] from a point to a CCW convex polygon's outline (negative inside)."""
    best = 1e300
    inside = True
    nv = verts.shape[0]
    for k in range(nv):
        ax = verts[k, 0]
        ay = verts[k, 1]
        bx = verts[(k + 1) % nv, 0]
        by = verts[(k + 1) % nv, 1]
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
def shape_distance(px: float, py: float, verts: np.ndarray, circle: np.ndarray) -> float:
    """Signed distance [µm] to the pillar outline: the circle if circle[2] > 0, else the polygon."""
    if circle[2] > 0.0:
        return math.sqrt((px - circle[0]) ** 2 + (py - circle[1]) ** 2) - circle[2]
    return outline_distance(px, py, verts)


@nb.njit(cache=True)
def pillar_forces(pil, bx, by, fx, fy, stiff, dist):
    """Contact forces on fiber beads (overwrites fx, fy, stiff, dist).

    Parameters
    ----------
    pil : PillarArrays
        The pillar (kind, outline, beads or curves, cutoff, force scale).
    bx, by : ndarray, shape (n,)
        Fiber bead centres [µm].
    fx, fy : ndarray, shape (n,)
        Force on each bead [pN].
    stiff : ndarray, shape (n,)
        Sum over contact pairs of |d|F|/dr| [pN/µm] (time-step bound).
    dist : ndarray, shape (n,)
        Signed bead-centre distance to the contact surface [µm]: the exact
        outline (rough, a circle, and any bead farther than R_ref), or the
        rounded Bézier outline (smooth polygon, beads closer than R_ref to it).

    Returns
    -------
    (any_contact, cx, cy) : (bool, float, float)
        Whether any force is non-zero, and the pillar-side point of the
        strongest pair (the contact point) [µm].
    """
    kind = pil.kind
    verts = pil.verts
    circle = pil.circle
    pbx = pil.pbx
    pby = pil.pby
    curves = pil.curves
    r_cut = pil.r_cut
    r_eq = pil.r_eq
    f_ref = pil.f_ref
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
        d_out = shape_distance(bx[i], by[i], verts, circle)
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
                sp, _, k_r = soft_core(r2, r2c, den, amp)
                # r_ij points to the pillar bead: the force pushes the fiber bead away.
                fx[i] -= sp * rx
                fy[i] -= sp * ry
                fm = sp * math.sqrt(r2)
                stiff[i] += k_r
                any_c = True
                if fm > fmax:
                    fmax = fm
                    cx = pbx[j]
                    cy = pby[j]
        elif circle[2] > 0.0:
            # smooth circle: exact nearest point, force along the outward radius
            rx = bx[i] - circle[0]
            ry = by[i] - circle[1]
            rr = math.sqrt(rx * rx + ry * ry)
            r = abs(d_out)
            sp, _, k_r = soft_core(r * r, r2c, den, amp)
            fm = sp * r
            if rr > 0.0:
                fx[i] += fm * rx / rr
                fy[i] += fm * ry / rr
                cx_i = circle[0] + circle[2] * rx / rr
                cy_i = circle[1] + circle[2] * ry / rr
            else:
                cx_i = circle[0] + circle[2]
                cy_i = circle[1]
            stiff[i] += k_r
            any_c = True
            if fm > fmax:
                fmax = fm
                cx = cx_i
                cy = cy_i
        else:
            d_curve = 1e300
            s_curve = 1.0
            for k in range(curves.shape[0]):
                qx, qy, r, side = bezier_nearest(bx[i], by[i], curves[k], roots)
                if side == 0.0:  # degenerate (sharp) corner: the polygon decides
                    side = -1.0 if d_out < 0.0 else 1.0
                if r < d_curve:
                    d_curve = r
                    s_curve = side
                if r >= r_cut:
                    continue
                sp, _, k_r = soft_core(r * r, r2c, den, amp)
                fm = sp * r
                # push along the outward normal even if the centre crossed the curve
                ex = side * (bx[i] - qx)
                ey = side * (by[i] - qy)
                if r > 0.0:
                    fx[i] += fm * ex / r
                    fy[i] += fm * ey / r
                stiff[i] += k_r
                any_c = True
                if fm > fmax:
                    fmax = fm
                    cx = qx
                    cy = qy
            # distance to the rounded outline itself (the polygon's is only a bound)
            dist[i] = s_curve * d_curve
    return any_c, cx, cy


@dataclass(frozen=True)
class Pillar:
    """Contact description of the pillar, as arrays the kernels read.

    Attributes
    ----------
    kind : int
        ROUGH or SMOOTH.
    vertices : ndarray, shape (n, 2)
        Polygon vertices, CCW [µm]; shape (0, 2) for a circle.
    beads : ndarray, shape (m, 2)
        Rough pillar bead centres [µm] (empty for smooth).
    curves : ndarray, shape (2n, 3, 2)
        Smooth polygon outline control points [µm] (empty for a circle).
    r_cut, r_eq, f_ref : float
        R_ref [µm], the distance where |F| = F_ref [µm], F_ref [pN].
    circle : ndarray, shape (3,)
        (x, y, radius) of a circle [µm]; zeros for a polygon.
    """

    kind: int
    vertices: np.ndarray
    beads: np.ndarray
    curves: np.ndarray
    r_cut: float
    r_eq: float
    f_ref: float
    circle: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def arrays(self) -> PillarArrays:
        """The kernel bundle of this pillar."""
        return PillarArrays(
            int(self.kind),
            np.ascontiguousarray(self.vertices, dtype=np.float64),
            np.ascontiguousarray(self.beads[:, 0], dtype=np.float64),
            np.ascontiguousarray(self.beads[:, 1], dtype=np.float64),
            np.ascontiguousarray(self.curves, dtype=np.float64),
            float(self.r_cut),
            float(self.r_eq),
            float(self.f_ref),
            np.ascontiguousarray(self.circle, dtype=np.float64),
        )

    def distance(self, x: float, y: float) -> float:
        """Signed distance [µm] of a point to the pillar's exact outline (negative inside)."""
        return shape_distance(float(x), float(y), self.vertices, self.circle)

    @property
    def x_max(self) -> float:
        """Largest x of the pillar [µm] (where a fiber has passed it)."""
        if self.circle[2] > 0.0:
            return float(self.circle[0] + self.circle[2])
        return float(self.vertices[:, 0].max())

    @property
    def layer(self) -> float:
        """Thickness of the contact layer R_ref − r_eq [µm]."""
        return self.r_cut - self.r_eq


def rough_beads(vertices: np.ndarray, a_obs: float) -> np.ndarray:
    """Pillar bead centres on a polygon outline, about 2 a_obs apart, one on each vertex, (m, 2)."""
    pts = []
    nv = len(vertices)
    for k in range(nv):
        p0 = vertices[k]
        p1 = vertices[(k + 1) % nv]
        side = float(np.hypot(*(p1 - p0)))
        m = max(1, int(round(side / (2.0 * a_obs))))
        t = np.arange(m) / m
        pts.append(p0 + t[:, None] * (p1 - p0))
    return np.ascontiguousarray(np.concatenate(pts))


def rough_circle_beads(circle: Circle, a_obs: float) -> np.ndarray:
    """Pillar bead centres on a circle, about 2 a_obs apart (at least 3), shape (m, 2)."""
    m = max(3, int(round(2.0 * math.pi * circle.radius / (2.0 * a_obs))))
    return np.ascontiguousarray(circle.outline(m))


def contact_force_scale(
    contact: ContactSettings, mu: float, bead_radius: float, u_center: float
) -> float:
    """F_ref [pN]: ``contact.f_ref``, or 6πμ a |U| when unset (μ [pN s/µm²], a [µm], U [µm/s]).

    The one force scale of the pillar contact and of the fiber's self-exclusion.
    """
    return float(contact.f_ref or 6.0 * math.pi * mu * bead_radius * abs(u_center))


def make_pillar(
    geometry: Geometry, contact: ContactSettings, bead_radius: float, f_ref: float
) -> Pillar:
    """Build the pillar's contact arrays from the geometry and contact settings.

    Raises
    ------
    ValueError
        If the smooth corner radius does not fit on the polygon's sides.
    """
    shape = geometry.shape
    if isinstance(shape, Circle):
        v = np.zeros((0, 2))
        circ = np.array([shape.cx, shape.cy, shape.radius], dtype=np.float64)
    else:
        v = np.ascontiguousarray(shape.vertices)
        circ = np.zeros(3)
    no_curves = np.zeros((0, 3, 2))
    if contact.pillar == "rough":
        a_obs = contact.obstacle_bead_radius
        r_eq = bead_radius + a_obs
        beads = rough_circle_beads(shape, a_obs) if circ[2] > 0 else rough_beads(v, a_obs)
        return Pillar(ROUGH, v, beads, no_curves, contact.cutoff(r_eq), r_eq, f_ref, circ)
    r_eq = bead_radius
    curves = no_curves if circ[2] > 0 else smooth_curves(v, contact.corner_radius)
    return Pillar(SMOOTH, v, np.zeros((0, 2)), curves, contact.cutoff(r_eq), r_eq, f_ref, circ)


def contact_forces(pillar: Pillar, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Contact forces [pN] on beads at ``positions`` (n, 2) [µm], and their outline distances.

    Returns
    -------
    forces : ndarray, shape (n, 2)
    distance : ndarray, shape (n,)
        Signed centre distance to the contact surface [µm] (negative inside).
    """
    p = np.ascontiguousarray(positions, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"positions must have shape (n, 2), got {p.shape}")
    n = p.shape[0]
    fx, fy, st, d = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    pillar_forces(
        pillar.arrays(),
        np.ascontiguousarray(p[:, 0]),
        np.ascontiguousarray(p[:, 1]),
        fx,
        fy,
        st,
        d,
    )
    return np.column_stack([fx, fy]), d
