"""A bead's drag and the flow's push near the pillar's wall, from the sphere–plane theory.

Used by the ``near_wall`` effect (:mod:`fibersweep.fiber.effects.near_wall`).
Each bead of radius a whose centre is within reach of a pillar's surface sees
that surface as the plane tangent to it at its nearest point (outward normal
n, centre distance h, gap ε = (h − a)/a). The exact results for a sphere near a
plane wall (:mod:`fibersweep.fiber.hydro.wall_mobility`) then give, in units of 6πμa:

* the drag along the wall λ_t (torque-free λ∥ for a lone sphere, which rolls;
  f_tt for a bead of a fiber, which turns with the fiber) and across it λ⊥;
* the force on the bead held in the local flow, per unit of the ambient
  velocity at its centre: c_t along the wall (Goldman, Cox & Brenner's shear
  force, plus the rolling term for a lone sphere) and c_n across it (Goren &
  O'Neill's flow towards the wall).

They enter as an extra force on each bead, F_w = −ΔR U + E, with

    ΔR = 6πμa s [(λ_t − 1)(I − nn) + (λ⊥ − 1) nn],
    E  = 6πμa s [(c_t − 1)(u − (u·n) n) + (c_n − 1)(u·n) n],

u the bead's background velocity and s = k exp(−(δ/ℓ)²) the strength k times
a screening over ℓ = H/2 (δ = h − a; the top and bottom walls, H/2 from the
midplane, bound the pillar's disturbance; 0.9991 at δ = 0.6 µm in a 40 µm deep
channel). For a lone bead this is exact: U = (c_t/λ_t) u_t + (c_n/λ⊥) u_n +
M_w F, the force-free motion of a sphere in the wall's shear and normal flow
and its near-wall mobility M_w = [λ_t⁻¹ (I − nn) + λ⊥⁻¹ nn]/(6πμa). With
several beads, their RPY coupling carries each bead's extra force to the
others (the added-resistance composition of :mod:`fibersweep.fiber.hydro.first_reflection`):

- rigid body (body frame, K_i the map from (V_x, V_y, Ω) to bead i):
  (I + N ΔR_b) V = V₀ + N E_b, ΔR_b = Σ K_iᵀ ΔR_i K_i, E_b = Σ K_iᵀ E_i, and
  the body mobility becomes N' = (I + N ΔR_b)⁻¹ N;
- free beads: U = M'(M⁻¹ u + E + F), M' = (M⁻¹ + Z)⁻¹ with Z = diag(ΔR_i),
  by the Woodbury identity over the beads near a wall only.

Where two pillars are within reach (a bead in an array's gap) their terms add
(linear superposition of the single-wall resistances).

The plane: the nearest point of the surface the contact law sees (the rough
pillar's outline, whose beads keep the fiber's beads a_obs off it; the smooth
pillar's rounded outline; a circle). On a face it is the face; in a corner's
region of a sharp polygon (the rough pillar) it is the plane normal to the
line from the vertex to the bead centre, at the vertex: a sphere meeting a
corner is treated as meeting a wall through the corner, which overestimates
the resistance of a sharp edge. On the smooth pillar the rounded corner's
tangent plane at the nearest point. The gap is clamped at
:data:`~fibersweep.fiber.hydro.wall_mobility.MIN_GAP`.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fibersweep.fiber.contact.bezier import bezier_nearest
from fibersweep.fiber.contact.pillar import ROUGH, SMOOTH, Pillar
from fibersweep.fiber.hydro.first_reflection import solve_body
from fibersweep.fiber.hydro.wall_mobility import MIN_GAP, bead_coefficients

__all__ = [
    "NROWS",
    "REACH",
    "convex_point",
    "corner_radius_at",
    "curvature_factor",
    "squeeze_factor",
    "new_scratch",
    "polygon_sides",
    "sides_of",
    "bead_wall_mobility",
    "rigid_wall_body",
    "surface_point",
    "wall_terms",
    "wall_terms_at",
]

#: Gaps beyond REACH screening lengths are skipped: the screening is below 1.2e-4 there.
REACH = 3.0

#: Rows of the per-bead scratch array ``b`` (NROWS, n) the kernels share: where the
#: terms were computed (LX, LY [µm], NaN: never), ΔR (RXX, RXY, RYY [pN s/µm]), the push
#: map P with E = P u (PXX, PXY, PYY [pN s/µm]) and E (EX, EY [pN]).
LX, LY, RXX, RXY, RYY, PXX, PXY, PYY, EX, EY = range(10)
NROWS = 10


@nb.njit(cache=True, inline="always")
def _segment(px, py, ax, ay, bx, by):
    """Nearest point (qx, qy) of the segment a→b to p, squared distance, and the cross
    product of a→b with q→p (> 0: p on the left)."""
    ex = bx - ax
    ey = by - ay
    t = ((px - ax) * ex + (py - ay) * ey) / (ex * ex + ey * ey)
    t = min(1.0, max(0.0, t))
    qx = ax + t * ex
    qy = ay + t * ey
    return qx, qy, (px - qx) ** 2 + (py - qy) ** 2, ex * (py - ay) - ey * (px - ax)


@nb.njit(cache=True)
def surface_point(kind, verts, circle, curves, roots, px, py):
    """Outward normal and signed centre distance of point p to the contact surface.

    Parameters
    ----------
    kind : int
        ROUGH or SMOOTH (:mod:`fibersweep.fiber.contact.pillar`).
    verts : ndarray, shape (m, 2)
        CCW polygon [µm] (empty for a circle).
    circle : ndarray, shape (3,)
        (x, y, radius) [µm]; radius 0 for a polygon.
    curves : ndarray, shape (2m, 3, 2)
        The smooth polygon's Bézier outline (corner k, then side k→k+1).
    roots : ndarray, shape (3,)
        Scratch.
    px, py : float
        The point [µm].

    Returns
    -------
    (nx, ny, d) : floats
        Unit normal of the local plane, pointing into the fluid, and the signed
        distance [µm] (negative inside).
    """
    if circle[2] > 0.0:
        rx = px - circle[0]
        ry = py - circle[1]
        rr = math.sqrt(rx * rx + ry * ry)
        if rr == 0.0:
            return 1.0, 0.0, -circle[2]
        return rx / rr, ry / rr, rr - circle[2]
    best = 1e300
    qx = px
    qy = py
    inside = True
    ox = 1.0  # outward normal of the nearest side (used when p lies on the surface)
    oy = 0.0
    smooth = kind == SMOOTH and curves.shape[0] > 0
    nv = verts.shape[0]
    for k in range(nv):
        if smooth:
            c = curves[2 * k + 1]
            ax, ay, bx, by = c[0, 0], c[0, 1], c[2, 0], c[2, 1]
        else:
            ax, ay = verts[k, 0], verts[k, 1]
            bx, by = verts[(k + 1) % nv, 0], verts[(k + 1) % nv, 1]
        sx, sy, d2, cross = _segment(px, py, ax, ay, bx, by)
        if cross <= 0.0:
            inside = False
        if d2 < best:
            best = d2
            qx = sx
            qy = sy
            ln = math.sqrt((bx - ax) ** 2 + (by - ay) ** 2)
            ox = (by - ay) / ln
            oy = -(bx - ax) / ln
    best = math.sqrt(best)
    side = -1.0 if inside else 1.0
    if smooth:
        # a corner's curve lies within its tangent length of the vertex
        for k in range(nv):
            c = curves[2 * k]
            vx = c[1, 0]
            vy = c[1, 1]
            reach = math.sqrt((c[0, 0] - vx) ** 2 + (c[0, 1] - vy) ** 2)
            if math.sqrt((px - vx) ** 2 + (py - vy) ** 2) - reach >= best:
                continue
            bxq, byq, r, sd = bezier_nearest(px, py, c, roots)
            if r < best:
                best = r
                qx = bxq
                qy = byq
                if sd != 0.0:
                    side = sd
                ox = vx - c[0, 0] + vx - c[2, 0]  # along the corner's bisector, outwards
                oy = vy - c[0, 1] + vy - c[2, 1]
                lo = math.sqrt(ox * ox + oy * oy)
                ox /= lo
                oy /= lo
    if best == 0.0:
        return ox, oy, 0.0
    return side * (px - qx) / best, side * (py - qy) / best, side * best


def polygon_sides(verts: np.ndarray) -> np.ndarray:
    """Per side k of a CCW convex polygon: (a_x, a_y, n_x, n_y, e_x/|e|², e_y/|e|²), (m, 6).

    a the side's first vertex, n its outward unit normal, e = a_{k+1} − a_k: what
    :func:`convex_point` reads, computed once per run.
    """
    v = np.ascontiguousarray(verts, dtype=np.float64).reshape(-1, 2)
    e = np.roll(v, -1, axis=0) - v
    ln2 = np.einsum("ij,ij->i", e, e)
    ln = np.sqrt(ln2)
    return np.ascontiguousarray(
        np.column_stack([v, e[:, 1] / ln, -e[:, 0] / ln, e[:, 0] / ln2, e[:, 1] / ln2])
    )


@nb.njit(cache=True, inline="always")
def convex_point(sides, px, py):
    """:func:`surface_point` of a convex polygon (the rough pillar) from its precomputed
    sides (:func:`polygon_sides`), without a division or a root on a face.

    Outside, the nearest point lies on the one side whose outward half-plane holds
    p and onto whose segment p projects, or else at the vertex v_j where p projects
    beyond the end of side j − 1 and before the start of side j (of those two, a
    side whose half-plane holds p finds it); inside, on the side of largest signed
    distance (a convex polygon's inside point projects onto it).
    """
    m = sides.shape[0]
    best = -1e300
    kb = 0
    for k in range(m):
        rx = px - sides[k, 0]
        ry = py - sides[k, 1]
        d = rx * sides[k, 2] + ry * sides[k, 3]
        if d > 0.0:
            t = rx * sides[k, 4] + ry * sides[k, 5]
            if 0.0 <= t <= 1.0:
                return sides[k, 2], sides[k, 3], d
            # beyond its end (start): the vertex there, if p projects before the next
            # side's start (beyond the previous side's end)
            j = (k + 1) % m if t > 1.0 else k
            i = j - 1 if j > 0 else m - 1
            tj = (px - sides[j, 0]) * sides[j, 4] + (py - sides[j, 1]) * sides[j, 5]
            ti = (px - sides[i, 0]) * sides[i, 4] + (py - sides[i, 1]) * sides[i, 5]
            if tj < 0.0 and ti > 1.0:
                vx = px - sides[j, 0]
                vy = py - sides[j, 1]
                r = math.sqrt(vx * vx + vy * vy)
                return vx / r, vy / r, r
        if d > best:
            best = d
            kb = k
    return sides[kb, 2], sides[kb, 3], best


@nb.njit(cache=True, inline="always")
def _circle_point(cx, cy, r, px, py):
    """:func:`surface_point` of a circle of centre (cx, cy) and radius r [µm]."""
    rx = px - cx
    ry = py - cy
    rr = math.sqrt(rx * rx + ry * ry)
    if rr > 0.0:
        return rx / rr, ry / rr, rr - r
    return 1.0, 0.0, -r  # at the centre: any direction


def squeeze_factor(a: float, r1: float, r2: float) -> float:
    """Squeeze-film force of a gap h + x²/(2R₁) + z²/(2R₂) over the sphere–plane one.

    The leading lubrication force on a surface approaching another at speed U across
    a gap with those principal radii (the Reynolds equation's exact solution
    p = 3μU/((α + β) h²), α = 1/2R₁, β = 1/2R₂) is 12πμU (R₁R₂)^{3/2}/((R₁ + R₂) h);
    divided by the sphere–plane 6πμU a²/h (R₁ = R₂ = a).

    Parameters
    ----------
    a, r1, r2 : float
        Bead radius and the gap's two principal radii [µm].

    Returns
    -------
    float
        2 (R₁R₂)^{3/2} / ((R₁ + R₂) a²).
    """
    return 2.0 * (r1 * r2) ** 1.5 / ((r1 + r2) * a * a)


@nb.njit(cache=True, inline="always")
def curvature_factor(a, radius):
    """Normal lubrication resistance beside a convex cylinder of ``radius`` over the plane's.

    A sphere of radius a at gap h from a surface whose radius of curvature is R in
    the plane of motion and infinite along the pillar's axis (a full-depth pillar)
    sees the gap h + x²/(2R₁) + z²/(2R₂), R₁ = aR/(a + R), R₂ = a. The Reynolds
    equation of the squeeze film then has the exact solution p = 3μU/((α+β) h(x, z)²)
    (α = 1/2R₁, β = 1/2R₂), whose force is 12πμU (R₁R₂)^{3/2}/((R₁ + R₂) h)
    (:func:`squeeze_factor`): with q = R/(a + R) the plane's 6πμU a²/h times
    2 q^{3/2}/(1 + q). A sphere beside a sphere of radius R (R₂ = R₁ too) gives q²,
    Jeffrey & Onishi's leading X₁₁ᴬ term. It scales λ⊥ − 1 whole: the lubrication
    term exactly, the O(ln) and O(1) terms (the plane's) approximately.

    Parameters
    ----------
    a, radius : float
        Bead radius and the surface's radius of curvature [µm] (inf: a plane, factor 1).

    Returns
    -------
    float
        2 q^{3/2}/(1 + q), q = R/(a + R), in (0, 1].
    """
    if not radius < 1e300:
        return 1.0
    q = radius / (a + radius)
    return 2.0 * q * math.sqrt(q) / (1.0 + q)


@nb.njit(cache=True, inline="always")
def _wall(nx, ny, d, a, z0, ell, free, fn=1.0):
    """One wall's ΔR and push map P (E = P u) on a bead: (Rxx, Rxy, Ryy, Pxx, Pxy, Pyy).

    ``fn`` scales the normal resistance λ⊥ − 1 (:func:`curvature_factor`; 1: the plane).
    """
    delta = max(d - a, 0.0)
    w = z0 * math.exp(-((delta / ell) ** 2))
    gap = max((d - a) / a, MIN_GAP)
    lam_t, lam_n, c_t, c_n = bead_coefficients(gap, free)
    dt = w * (lam_t - 1.0)
    if fn != 1.0:
        lam_n = 1.0 + fn * (lam_n - 1.0)
    dd = w * (lam_n - 1.0) - dt
    pt = w * (c_t - 1.0)
    pd = w * (c_n - 1.0) - pt
    return (dt + dd * nx * nx, dd * nx * ny, dt + dd * ny * ny,
            pt + pd * nx * nx, pd * nx * ny, pt + pd * ny * ny)  # fmt: skip


@nb.njit(cache=True)
def corner_radius_at(kind, verts, curves, px, py, rc):
    """Radius of curvature [µm] of a polygon pillar's surface nearest to p (outside it).

    ``rc`` is the corners' radius; inf on a face. The rough pillar: p is in vertex
    j's wedge when it projects beyond side j − 1's end and before side j's start;
    the smooth pillar: when it lies between the normals at corner j's tangent
    points (its curve's ends).
    """
    nv = verts.shape[0]
    smooth = kind == SMOOTH and curves.shape[0] > 0
    for j in range(nv):
        if smooth:
            c = curves[2 * j]
            t0x, t0y, t1x, t1y = c[0, 0], c[0, 1], c[2, 0], c[2, 1]
            ex0, ey0 = c[1, 0] - c[0, 0], c[1, 1] - c[0, 1]
            ex1, ey1 = c[2, 0] - c[1, 0], c[2, 1] - c[1, 1]
        else:
            i = j - 1 if j > 0 else nv - 1
            k = (j + 1) % nv
            t0x, t0y = verts[j, 0], verts[j, 1]
            t1x, t1y = t0x, t0y
            ex0, ey0 = verts[j, 0] - verts[i, 0], verts[j, 1] - verts[i, 1]
            ex1, ey1 = verts[k, 0] - verts[j, 0], verts[k, 1] - verts[j, 1]
        if (px - t0x) * ex0 + (py - t0y) * ey0 > 0.0 and (px - t1x) * ex1 + (py - t1y) * ey1 < 0.0:
            return rc
    return math.inf


@nb.njit(cache=True, inline="always")
def _normal_factor(curved, is_circle, a, cr, kind, verts, curves, px, py, rc):
    """:func:`curvature_factor` of the pillar surface nearest to p; 1 when not ``curved``.

    A circle's radius is ``cr``; a polygon's is ``rc`` in a corner's wedge and inf on a
    face (:func:`corner_radius_at`).
    """
    if not curved:
        return 1.0
    if is_circle:
        return curvature_factor(a, cr)
    return curvature_factor(a, corner_radius_at(kind, verts, curves, px, py, rc))


def sides_of(pillar) -> np.ndarray:
    """:func:`polygon_sides` of a rough polygon pillar (``PillarArrays``); (0, 6) otherwise."""
    if pillar.kind == ROUGH and pillar.circle[2] == 0.0 and pillar.verts.shape[0] >= 3:
        return polygon_sides(pillar.verts)
    return np.zeros((0, 6))


def new_scratch(n: int) -> np.ndarray:
    """The per-bead scratch array (NROWS, n) of :func:`wall_terms`, nothing computed yet."""
    b = np.zeros((NROWS, n))
    b[LX] = np.nan
    b[LY] = np.nan
    return b


@nb.njit(cache=True, inline="always")
def wall_terms(
    x, y, u, dist, a, z0, ell, free, kind, verts, circle, curves, roots, sides,
    lattice, px, py, sy, bounds, tol, b, curved=False, rc=0.0,
):  # fmt: skip
    """Extra resistance ΔR_i and force E_i of every bead near a pillar (lab frame).

    E_i = P_i u_i is linear in the bead's background velocity: ΔR_i and P_i
    depend on its position only. They are kept per bead in ``b`` with the
    position they were computed at and recomputed only for a bead that has moved
    more than ``tol`` in x or y since; E_i is formed from the current u_i always.

    Parameters
    ----------
    x, y : ndarray, shape (n,)
        Bead centres [µm] (unwrapped in an array).
    u : ndarray, shape (n, 2)
        Background velocities [µm/s].
    dist : ndarray, shape (n,)
        Distance of each centre to the nearest pillar outline [µm] (the contact
        stage's; a lower bound of the distance to the contact surface).
    a : float
        Bead radius [µm].
    z0 : float
        k · 6πμa [pN s/µm].
    ell : float
        Screening length ℓ [µm].
    free : bool
        Torque-free beads (a lone sphere) or beads turning with the body.
    kind, verts, circle, curves, roots
        The pillar (:func:`surface_point`).
    sides : ndarray, shape (m, 6)
        The rough pillar's :func:`polygon_sides` (read instead of ``verts`` by
        :func:`convex_point`); shape (0, 6) for a smooth pillar or a circle.
    lattice : bool
        Pillars at every (r px, r sy + c py) (an array) or one (the channel).
    px, py, sy : float
        Periods and row shift of the array [µm].
    bounds : ndarray, shape (4,)
        (x0, y0, x1, y1) of the pillar at the origin of the array [µm].
    tol : float
        Reuse distance [µm] (0: only at the very same position, which is exact).
    b : ndarray, shape (NROWS, n)
        Per-bead scratch (:data:`NROWS`; :func:`new_scratch`): positions, ΔR_i and
        P_i kept between calls and updated; E_i written.
    curved : bool
        Scale the normal resistance by the local curvature (:func:`curvature_factor`):
        a circle's radius, ``rc`` at a polygon's corners, a plane on its faces
        (False: the plane everywhere, as before).
    rc : float
        The polygon's corner radius [µm] when ``curved``.

    Returns
    -------
    int
        Beads with a non-zero term.
    """
    reach = REACH * ell
    # Which surface, decided once: the per-bead branch then binds one array at most (each
    # array an inlined call binds costs two reference counts, per bead).
    cx = circle[0]
    cy = circle[1]
    cr = circle[2]
    is_circle = cr > 0.0
    is_convex = sides.shape[0] > 0
    count = 0
    for i in range(x.shape[0]):
        bx = x[i]
        by = y[i]
        if not (abs(bx - b[LX, i]) <= tol and abs(by - b[LY, i]) <= tol):
            b[LX, i] = bx
            b[LY, i] = by
            # summed over the walls within reach in locals, stored once; the channel's
            # branch is the lattice loop's body for one image, kept apart because the
            # shared loop measured 4 % slower over the quick sweep
            rxx = rxy = ryy = pxx = pxy = pyy = 0.0
            if dist[i] - a < reach:
                if not lattice:
                    if is_circle:
                        nx, ny, d = _circle_point(cx, cy, cr, bx, by)
                    elif is_convex:
                        nx, ny, d = convex_point(sides, bx, by)
                    else:
                        nx, ny, d = surface_point(kind, verts, circle, curves, roots, bx, by)
                    if d - a < reach:
                        fn = _normal_factor(
                            curved, is_circle, a, cr, kind, verts, curves, bx, by, rc
                        )
                        t = _wall(nx, ny, d, a, z0, ell, free, fn)
                        rxx += t[0]
                        rxy += t[1]
                        ryy += t[2]
                        pxx += t[3]
                        pxy += t[4]
                        pyy += t[5]
                else:
                    r_far = reach + a
                    r0 = math.floor((bx - r_far - bounds[2]) / px)
                    r1 = math.floor((bx + r_far - bounds[0]) / px)
                    for r in range(r0, r1 + 1):
                        oxr = r * px
                        dy = r * sy
                        c0 = math.floor((by - r_far - bounds[3] - dy) / py)
                        c1 = math.floor((by + r_far - bounds[1] - dy) / py)
                        for c in range(c0, c1 + 1):
                            oy = dy + c * py
                            qx = bx - oxr
                            qy = by - oy
                            if is_circle:
                                nx, ny, d = _circle_point(cx, cy, cr, qx, qy)
                            elif is_convex:
                                nx, ny, d = convex_point(sides, qx, qy)
                            else:
                                nx, ny, d = surface_point(
                                    kind, verts, circle, curves, roots, qx, qy
                                )
                            if d - a < reach:
                                fn = _normal_factor(
                                    curved, is_circle, a, cr, kind, verts, curves, qx, qy, rc
                                )
                                t = _wall(nx, ny, d, a, z0, ell, free, fn)
                                rxx += t[0]
                                rxy += t[1]
                                ryy += t[2]
                                pxx += t[3]
                                pxy += t[4]
                                pyy += t[5]
            b[RXX, i] = rxx
            b[RXY, i] = rxy
            b[RYY, i] = ryy
            b[PXX, i] = pxx
            b[PXY, i] = pxy
            b[PYY, i] = pyy
        ux = u[i, 0]
        uy = u[i, 1]
        b[EX, i] = b[PXX, i] * ux + b[PXY, i] * uy
        b[EY, i] = b[PXY, i] * ux + b[PYY, i] * uy
        if b[RXX, i] != 0.0 or b[RYY, i] != 0.0 or b[PXX, i] != 0.0 or b[PYY, i] != 0.0:
            count += 1
    return count


@nb.njit(cache=True, inline="always")
def rigid_wall_body(s, nm, c, sn, b, vbx, vby, om, nm_out, m3):
    """Body velocity of a rigid fiber with the wall terms (module docstring).

    Parameters
    ----------
    s : ndarray, shape (n,)
        Bead offsets along the axis [µm].
    nm : ndarray, shape (3, 3)
        Body mobility N (body frame).
    c, sn : float
        cos and sin of the fiber angle.
    b : ndarray, shape (NROWS, n)
        ΔR_i and E_i, lab frame (:func:`wall_terms`).
    vbx, vby, om : float
        Body velocity without them (body frame) [µm/s, rad/s].
    nm_out : ndarray, shape (3, 3)
        Written: N' = (I + N ΔR_b)⁻¹ N.
    m3 : ndarray, shape (3, 3, 3)
        Scratch (no allocation per call).

    Returns
    -------
    (vbx, vby, om)
        (I + N ΔR_b)⁻¹ (V₀ + N E_b), body frame.
    """
    r = m3[0]
    am = m3[1]
    ainv = m3[2]
    for i in range(3):
        for j in range(3):
            r[i, j] = 0.0
    eb0 = 0.0
    eb1 = 0.0
    eb2 = 0.0
    cc = c * c
    ss = sn * sn
    cs = c * sn
    for i in range(s.shape[0]):
        rxx = b[RXX, i]
        rxy = b[RXY, i]
        ryy = b[RYY, i]
        ex = b[EX, i]
        ey = b[EY, i]
        if rxx == 0.0 and ryy == 0.0 and ex == 0.0 and ey == 0.0:
            continue
        bxx = cc * rxx + 2.0 * cs * rxy + ss * ryy
        bxy = cs * (ryy - rxx) + (cc - ss) * rxy
        byy = ss * rxx - 2.0 * cs * rxy + cc * ryy
        si = s[i]
        r[0, 0] += bxx
        r[0, 1] += bxy
        r[0, 2] += bxy * si
        r[1, 1] += byy
        r[1, 2] += byy * si
        r[2, 2] += byy * si * si
        ebx = c * ex + sn * ey
        eby = -sn * ex + c * ey
        eb0 += ebx
        eb1 += eby
        eb2 += eby * si
    r[1, 0] = r[0, 1]
    r[2, 0] = r[0, 2]
    r[2, 1] = r[1, 2]
    for i in range(3):
        for j in range(3):
            am[i, j] = nm[i, 0] * r[0, j] + nm[i, 1] * r[1, j] + nm[i, 2] * r[2, j]
        am[i, i] += 1.0
    b0 = vbx + nm[0, 0] * eb0 + nm[0, 1] * eb1 + nm[0, 2] * eb2
    b1 = vby + nm[1, 0] * eb0 + nm[1, 1] * eb1 + nm[1, 2] * eb2
    b2 = om + nm[2, 0] * eb0 + nm[2, 1] * eb1 + nm[2, 2] * eb2
    return solve_body(am, ainv, nm, nm_out, b0, b1, b2)


@nb.njit(cache=True)
def bead_wall_mobility(mob, vel, b):
    """Free beads with the wall terms, in place: M -> M', u -> M'(M⁻¹ u + E).

    With A the beads near a wall, Z_A their 2×2 blocks ΔR_i and
    G = (I + M_AA Z_A)⁻¹ (Woodbury): M' = M − M[:, A] Z_A G M[A, :] and
    M'(M⁻¹ u + E) = u + M[:, A] (E_A − Z_A G (u_A + M_AA E_A)).

    Parameters
    ----------
    mob : ndarray, shape (2n, 2n)
        Bead mobility M [µm/(pN s)] (symmetric); overwritten with M'.
    vel : ndarray, shape (2n,)
        Background velocities u [µm/s]; overwritten.
    b : ndarray, shape (NROWS, n)
        ΔR_i and E_i (:func:`wall_terms`).
    """
    rxx = b[RXX]
    rxy = b[RXY]
    ryy = b[RYY]
    ex = b[EX]
    ey = b[EY]
    n = rxx.shape[0]
    k = 0
    for i in range(n):
        if rxx[i] != 0.0 or ryy[i] != 0.0 or ex[i] != 0.0 or ey[i] != 0.0:
            k += 1
    if k == 0:
        return
    beads = np.empty(k, dtype=np.int64)
    j = 0
    for i in range(n):
        if rxx[i] != 0.0 or ryy[i] != 0.0 or ex[i] != 0.0 or ey[i] != 0.0:
            beads[j] = i
            j += 1
    m2 = 2 * k
    n2 = 2 * n
    ma = np.empty((n2, m2))  # M[:, A] = M[A, :]ᵀ
    for p in range(k):
        b = beads[p]
        for r in range(n2):
            ma[r, 2 * p] = mob[r, 2 * b]
            ma[r, 2 * p + 1] = mob[r, 2 * b + 1]
    ea = np.empty(m2)
    for p in range(k):
        ea[2 * p] = ex[beads[p]]
        ea[2 * p + 1] = ey[beads[p]]
    t = np.empty((m2, m2))  # I + M_AA Z_A
    rhs = np.empty((m2, n2 + 1))  # [M[A, :] | u_A + M_AA E_A]
    for p in range(m2):
        rp = 2 * beads[p // 2] + p % 2
        acc = vel[rp]
        for q in range(k):
            b = beads[q]
            m0 = ma[rp, 2 * q]
            m1 = ma[rp, 2 * q + 1]
            t[p, 2 * q] = m0 * rxx[b] + m1 * rxy[b]
            t[p, 2 * q + 1] = m0 * rxy[b] + m1 * ryy[b]
            acc += m0 * ea[2 * q] + m1 * ea[2 * q + 1]
        t[p, p] += 1.0
        for r in range(n2):
            rhs[p, r] = ma[r, p]
        rhs[p, n2] = acc
    g = np.linalg.solve(t, rhs)
    # Z_A G [...], block by block
    for q in range(k):
        b = beads[q]
        for r in range(n2 + 1):
            g0 = g[2 * q, r]
            g1 = g[2 * q + 1, r]
            g[2 * q, r] = rxx[b] * g0 + rxy[b] * g1
            g[2 * q + 1, r] = rxy[b] * g0 + ryy[b] * g1
    for r in range(n2):
        acc = 0.0
        for p in range(m2):
            acc += ma[r, p] * (ea[p] - g[p, n2])
        vel[r] += acc
        for c in range(n2):
            acc = 0.0
            for p in range(m2):
                acc += ma[r, p] * g[p, c]
            mob[r, c] -= acc


def wall_terms_at(
    pillar: Pillar,
    positions: np.ndarray,
    velocities: np.ndarray,
    *,
    bead_radius: float,
    viscosity: float,
    depth: float,
    strength: float = 1.0,
    free_rotation: bool = False,
    curved: bool = False,
    corner_radius: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """ΔR_i (n, 2, 2) [pN s/µm] and E_i (n, 2) [pN] of beads beside one pillar (no images).

    ``positions`` (n, 2) [µm], ``velocities`` (n, 2) background velocities [µm/s];
    ``depth`` the channel depth H [µm] (screening ℓ = H/2; ``math.inf``: none);
    ``curved``, ``corner_radius`` [µm]: the local curvature of :func:`wall_terms`.
    """
    p = np.ascontiguousarray(positions, dtype=np.float64)
    u = np.ascontiguousarray(velocities, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 2 or u.shape != p.shape:
        raise ValueError(f"positions and velocities must be (n, 2), got {p.shape}, {u.shape}")
    n = p.shape[0]
    arr = pillar.arrays()
    b = new_scratch(n)
    a = float(bead_radius)
    wall_terms(
        np.ascontiguousarray(p[:, 0]), np.ascontiguousarray(p[:, 1]), u, np.zeros(n), a,
        float(strength) * 6.0 * math.pi * float(viscosity) * a, 0.5 * float(depth),
        bool(free_rotation), arr.kind, arr.verts, arr.circle, arr.curves, np.zeros(3),
        sides_of(arr), False, 1.0, 1.0, 0.0, np.zeros(4), 0.0, b, bool(curved),
        float(corner_radius),
    )  # fmt: skip
    r = np.stack([np.stack([b[RXX], b[RXY]], -1), np.stack([b[RXY], b[RYY]], -1)], -2)
    return r, np.column_stack([b[EX], b[EY]])
