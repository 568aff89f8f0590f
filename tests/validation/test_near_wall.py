"""The ``near_wall`` effect assembled: a bead's near-wall mobility and flow push in the models.

The sphere–plane coefficients are validated in test_wall_mobility.py; here their
assembly (fibersweep.fiber.hydro.nearwall, fibersweep.fiber.effects.near_wall):

* a one-bead rigid fiber (a sphere) beside a plane wall in a simple shear moves
  with Goldman, Cox & Brenner's force-free, torque-free velocity (and across
  a stagnation flow with Goren & O'Neill's c_n/λ⊥), through the integrator;
* the rigid-body and free-bead (Woodbury) forms equal the dense algebra
  (M⁻¹ + Z)⁻¹ and agree with each other for a straight fiber;
* the local plane: the contact law's surface (rough: the polygon; smooth: its
  rounded Bézier outline; a circle), and the same terms at every image of an
  array's pillar;
* one bead beside a flat face of any orientation has the sphere–wall mobility
  (Brenner across, Goldman, Cox & Brenner along), also through a contact force;
* the bead-spring model's velocities are the dense algebra's with the terms;
* k = 0 is bit for bit no effect (rigid and bead-spring);
* against today's ``pillar_hydro`` where both apply (far from the wall).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.fiber.contact.pillar import ROUGH, SMOOTH, Pillar, outline_distance, pillar_forces
from fibersweep.fiber.effects import DynamicsContext, build_effects
from fibersweep.fiber.effects.near_wall import NearWall
from fibersweep.fiber.frame import CHANNEL, Lattice
from fibersweep.fiber.hydro import nearwall as nw
from fibersweep.fiber.hydro import wall_mobility as wm
from fibersweep.fiber.hydro.first_reflection import wall_drag
from fibersweep.fiber.hydro.nearwall import (
    bead_wall_mobility,
    rigid_wall_body,
    surface_point,
    wall_terms,
    wall_terms_at,
)
from fibersweep.fiber.hydro.rpy import body_mobility, body_velocity, rigid_map, rpy_matrix
from fibersweep.fiber.kernel.bundles import FlowArrays, assemble, make_params
from fibersweep.fiber.models.beadspring import bead_velocity
from fibersweep.fiber.models.rigid import rigid_velocity, run_rigid
from fibersweep.flow.field import interpolate_ib

A = 2.0  # bead radius [µm]
MU = 1.0 / (6.0 * math.pi * A)  # 6πμa = 1
Y_WALL = 40.0  # the wall: the top face of a wide rectangular pillar [µm]
WALL = np.array([[-2000.0, -500.0], [2000.0, -500.0], [2000.0, Y_WALL], [-2000.0, Y_WALL]])
DX = 1.0
NX, NY = 64, 120


def _pillar(kind=ROUGH, verts=WALL, curves=None, circle=None) -> Pillar:
    """A pillar whose contact force is off (rough: no beads; the outline is all that counts)."""
    return Pillar(
        kind,
        verts,
        np.zeros((0, 2)),
        np.zeros((0, 3, 2)) if curves is None else curves,
        1.1 * A,
        A,
        1.0,
        np.zeros(3) if circle is None else circle,
    )


def _field(ux_of, uy_of) -> FlowArrays:
    """Node values of an analytic field (nodes at (i + ½) Δx), ghost values inside the pillar
    continuing it as the flow solver's do."""
    xs = (np.arange(NX) + 0.5) * DX
    ys = (np.arange(NY) + 0.5) * DX
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    return FlowArrays(np.ascontiguousarray(ux_of(gx, gy)), np.ascontiguousarray(uy_of(gx, gy)), DX)


def _kernel(flow, pillar, n=1, depth=math.inf, t_stop=1.0, strength=1.0, model="rigid"):
    ctx = DynamicsContext(
        bead_radius=A, dx=DX, depth=depth, viscosity=MU, n_beads=n, pillar=pillar.arrays()
    )
    st = FiberSettings(bead_radius=A, model=model)
    params = make_params(
        st, mu=MU, u_center=1.0, x_stop=1e9, y_lo=-math.inf, y_hi=math.inf, random=False,
        mode=1, t_stop=t_stop,
    )  # fmt: skip
    effects = (NearWall(strength).kernel(ctx),) if strength else ()
    return assemble(st, n, flow, pillar.arrays(), params, effects, CHANNEL)


def _sphere_velocity(k, x, y):
    out = rigid_velocity(k.frame, k.flow, k.pillar, k.body, k.work, k.effects, x, y, 0.3)
    return out[0], out[1]


def _interp(flow, x, y):
    u = np.zeros((1, 2))
    interpolate_ib(flow.ux, flow.uy, flow.dx, np.array([x]), np.array([y]), u)
    return u[0]


@pytest.mark.parametrize("gap", [0.05, 0.3, 1.0, 3.0])
def test_a_sphere_in_a_wall_shear_moves_with_goldman_cox_brenner_velocity(gap):
    """One bead (a rigid fiber of one bead: free to rotate) at gap ε beside the wall in the
    shear u = γ̇ (y − y_w) x̂ moves parallel to it with U/(γ̇h) of Goldman, Cox & Brenner
    times the interpolated flow at its centre (1e-12), not across it (1e-12 of U); the
    interpolated flow is γ̇h to within γ̇ · 0.022 Δx (the cosine kernel's first moment, at
    most 0.0211 Δx); over a run of 1 s
    through the integrator the sphere travels U·t at constant height (1e-9 relative)."""
    rate = 3.0
    flow = _field(lambda x, y: rate * (y - Y_WALL), lambda x, y: 0.0 * x)
    h = A * (1 + gap)
    x0, y0 = 20.3, Y_WALL + h
    k = _kernel(flow, _pillar())
    u = _interp(flow, x0, y0)
    assert u[0] == pytest.approx(rate * h, abs=rate * 0.022 * DX)
    vx, vy = _sphere_velocity(k, x0, y0)
    assert vx == pytest.approx(wm.shear_velocity(gap) * u[0], rel=1e-12)
    assert abs(vy) <= 1e-12 * abs(vx)
    rec, _, _ = run_rigid(k, x0, y0, 0.3)
    t, x, y = rec[-1, 0], rec[-1, 1], rec[-1, 2]
    assert t == pytest.approx(1.0, rel=1e-12)
    assert (x - x0) / t == pytest.approx(vx, rel=1e-9)
    assert y == pytest.approx(y0, abs=1e-9)
    # without the effect it follows the fluid
    assert _sphere_velocity(_kernel(flow, _pillar(), strength=0.0), x0, y0)[0] == pytest.approx(
        u[0], rel=1e-12
    )


@pytest.mark.parametrize("gap", [0.05, 0.3, 1.0])
def test_a_sphere_in_a_stagnation_flow_crosses_with_goren_oneill_push(gap):
    """Planar stagnation flow towards the wall, u = (2α (x − x_s)(y − y_w), −α (y − y_w)²) (its
    normal force on a sphere on the axis is the axisymmetric flow's: the difference is odd
    under a quarter turn about the normal). The sphere on the axis moves across with
    c_n/λ⊥ times the interpolated normal velocity (1e-12). That velocity is
    −α (h² − 2h m₁ Δx + m₂ Δx²), m₁ and m₂ the cosine kernel's discrete first and second
    moments (|m₁| ≤ 0.0211, 0.5 ≤ m₂ ≤ 0.5429 over all node offsets): a shift of −α Δx² · 0.5
    to 0.55 from −α h², bounded on both sides here."""
    alpha, xs = 0.5, 32.0
    flow = _field(
        lambda x, y: 2 * alpha * (x - xs) * (y - Y_WALL), lambda x, y: -alpha * (y - Y_WALL) ** 2
    )
    h = A * (1 + gap)
    k = _kernel(flow, _pillar())
    u = _interp(flow, xs, Y_WALL + h)
    vx, vy = _sphere_velocity(k, xs, Y_WALL + h)
    sw = wm.sphere_wall(gap)
    assert vy == pytest.approx(sw.normal_push / sw.normal * u[1], rel=1e-12)
    shift = (u[1] + alpha * h * h) / (-alpha * DX * DX)
    assert 0.5 - 2 * h * 0.0211 / DX <= shift <= 0.5429 + 2 * h * 0.0211 / DX


def _scratch(r, e):
    """The kernels' per-bead array (nearwall.NROWS, n) holding ΔR (n, 2, 2) and E (n, 2)."""
    b = nw.new_scratch(len(r))
    b[nw.RXX], b[nw.RXY], b[nw.RYY] = r[:, 0, 0], r[:, 0, 1], r[:, 1, 1]
    b[nw.EX], b[nw.EY] = e[:, 0], e[:, 1]
    return b


def _straight_fiber(n, theta, gap):
    """Positions (n, 2) of a straight fiber whose lowest bead is at gap ε above the wall."""
    s = (np.arange(n) - 0.5 * (n - 1)) * 2 * A
    pos = np.column_stack([s * math.cos(theta), s * math.sin(theta)])
    pos[:, 0] += 10.0
    pos[:, 1] += Y_WALL + A * (1 + gap) - pos[:, 1].min()
    return s, pos


def test_rigid_and_bead_forms_equal_the_dense_algebra():
    """A 6-bead fiber at 20° with its low end at ε = 0.1 in a shear: the free-bead form
    (Woodbury over the beads near the wall) gives M' = (M⁻¹ + Z)⁻¹ and M'(M⁻¹ u + E) of the
    dense algebra, and the rigid form (I + N ΔR_b)⁻¹ (V₀ + N E_b) the constrained solution
    (Kᵀ (M⁻¹ + Z) K)⁻¹ Kᵀ (M⁻¹ u + E) of the same beads, all to 1e-10."""
    n, theta = 6, math.radians(20.0)
    s, pos = _straight_fiber(n, theta, 0.1)
    u = np.column_stack([0.7 * (pos[:, 1] - Y_WALL), -0.05 * (pos[:, 1] - Y_WALL) ** 2])
    r, e = wall_terms_at(_pillar(), pos, u, bead_radius=A, viscosity=MU, depth=40.0)
    assert np.all(np.linalg.eigvalsh(r) > 0)
    z = np.zeros((2 * n, 2 * n))
    for i in range(n):
        z[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] = r[i]
    m = rpy_matrix(pos, A, MU)
    m_new = np.linalg.inv(np.linalg.inv(m) + z)
    f_new = m_new @ (np.linalg.solve(m, u.ravel()) + e.ravel())
    mob, vel = m.copy(), u.ravel().copy()
    bead_wall_mobility(mob, vel, _scratch(r, e))
    assert np.allclose(mob, m_new, rtol=0, atol=1e-10 * np.abs(m_new).max())
    assert np.allclose(vel, f_new, rtol=0, atol=1e-10 * np.abs(f_new).max())

    # rigid: body frame (x along the fiber), K the rigid map there
    c, sn = math.cos(theta), math.sin(theta)
    rot = np.array([[c, -sn], [sn, c]])
    bm = body_mobility(n, A, MU)
    vb0 = body_velocity(c, sn, bm.offsets, bm.P, bm.N, u.ravel(), np.zeros(n), np.zeros(n), False)
    nm_out = np.zeros((3, 3))
    got = rigid_wall_body(
        bm.offsets, np.array(bm.N), c, sn, _scratch(r, e), *vb0, nm_out, np.zeros((3, 3, 3))
    )
    kmap = rigid_map(s)
    mb = rpy_matrix(np.column_stack([s, 0 * s]), A, MU)
    zb = np.zeros_like(z)
    for i in range(n):
        zb[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] = rot.T @ r[i] @ rot
    ub = (u @ rot).ravel()
    eb = (e @ rot).ravel()
    res = kmap.T @ (np.linalg.inv(mb) + zb) @ kmap
    want = np.linalg.solve(res, kmap.T @ (np.linalg.solve(mb, ub) + eb))
    assert np.allclose(got, want, rtol=1e-10, atol=1e-10 * np.abs(want).max())
    assert np.allclose(nm_out, np.linalg.inv(res), rtol=1e-10, atol=1e-10 * np.abs(nm_out).max())


def test_the_plane_is_the_contact_surface():
    """Rough pillar: the signed distance and normal are the polygon's (outline_distance to
    1e-12; in a corner's region the normal points from the vertex to the centre). Smooth
    pillar: the distance to its rounded Bézier outline, the contact kernel's own distance
    inside its cutoff (1e-9), never below the polygon's outside it. Circle: exact."""
    tri = np.array([[0.0, 0.0], [86.6, 0.0], [43.3, 75.0]])
    rng = np.random.default_rng(3)
    pts = rng.uniform([-20, -20], [110, 95], size=(400, 2))
    roots = np.zeros(3)
    rough = _pillar(ROUGH, tri).arrays()
    for px, py in pts:
        nx, ny, d = surface_point(ROUGH, rough.verts, rough.circle, rough.curves, roots, px, py)
        assert d == pytest.approx(outline_distance(px, py, tri), abs=1e-12)
        if d > 0:
            h = 1e-6
            gx = (outline_distance(px + h, py, tri) - outline_distance(px - h, py, tri)) / (2 * h)
            gy = (outline_distance(px, py + h, tri) - outline_distance(px, py - h, tri)) / (2 * h)
            assert (nx, ny) == pytest.approx((gx, gy), abs=1e-6)
    nx, ny, d = surface_point(ROUGH, rough.verts, rough.circle, rough.curves, roots, 43.3, 80.0)
    assert (nx, ny, d) == pytest.approx((0.0, 1.0, 5.0), abs=1e-12)
    # the rough pillar's fast path (precomputed sides) is the same plane, for a triangle
    # and a turned square, outside and inside, faces and corners (1e-12)
    for poly in (tri, _square(0.3, (40.0, 30.0), 35.0)):
        sides = nw.polygon_sides(poly)
        for px, py in pts:
            want = surface_point(ROUGH, poly, rough.circle, rough.curves, roots, px, py)
            assert nw.convex_point(sides, px, py) == pytest.approx(want, abs=1e-12)

    from fibersweep.fiber.contact.bezier import smooth_curves

    curves = smooth_curves(tri, 2.0)
    smooth = Pillar(SMOOTH, tri, np.zeros((0, 2)), curves, 30.0, A, 1.0).arrays()
    fx, fy, st, dist = (np.zeros(len(pts)) for _ in range(4))
    pillar_forces(smooth, pts[:, 0].copy(), pts[:, 1].copy(), fx, fy, st, dist)
    for (px, py), dk in zip(pts, dist, strict=True):
        _, _, d = surface_point(SMOOTH, tri, smooth.circle, curves, roots, px, py)
        poly = outline_distance(px, py, tri)
        if abs(poly) < 30.0:
            assert d == pytest.approx(dk, abs=1e-9)
        if poly > 0:
            assert d >= poly - 1e-12
    circ = np.array([5.0, 6.0, 20.0])
    nx, ny, d = surface_point(ROUGH, np.zeros((0, 2)), circ, np.zeros((0, 3, 2)), roots, 5.0, 30.0)
    assert (nx, ny, d) == pytest.approx((0.0, 1.0, 4.0), abs=1e-12)


def test_every_image_of_an_array_pillar_acts_and_two_add():
    """In an array the terms of a bead beside any image of the pillar are those beside the
    pillar itself (1e-12); in a gap between two images both walls' terms add (linear
    superposition of single-wall resistances)."""
    circ = np.array([40.0, 40.0, 20.0])
    pil = _pillar(ROUGH, np.zeros((0, 2)), circle=circ)
    arr = pil.arrays()
    px, py, sy = 80.0, 80.0, 8.0
    bounds = np.array([20.0, 20.0, 60.0, 60.0])

    def terms(points, lattice, depth=20.0):
        p = np.asarray(points, dtype=float)
        n = len(p)
        u = np.column_stack([np.full(n, 5.0), np.full(n, -1.0)])
        b = nw.new_scratch(n)
        wall_terms(p[:, 0].copy(), p[:, 1].copy(), u, np.zeros(n), A, 1.0, 0.5 * depth, False,
                   arr.kind, arr.verts, circ, arr.curves, np.zeros(3), np.zeros((0, 6)),
                   lattice, px, py, sy, bounds, 0.0, b)  # fmt: skip
        return b[nw.RXX :]

    here = (40.0 + 22.5, 40.0 + 1.0)
    ox, oy = 2 * px, 2 * sy + 1 * py  # row 2, column 1
    assert np.allclose(terms([(here[0] + ox, here[1] + oy)], True), terms([here], False),
                       rtol=1e-12, atol=1e-15)  # fmt: skip
    # midway between the pillar of row 0 and the one above it (gaps 18 µm); H = 30 µm gives a
    # reach of 3 · 15 = 45 µm, which takes in these two and no other image (the next, row −1
    # at (−40, 72), is 60.4 µm away)
    mid = (40.0, 80.0)
    both = terms([mid], True, depth=30.0)
    one = terms([mid], False, depth=30.0)
    other = terms([(mid[0], mid[1] - py)], False, depth=30.0)
    assert np.all(one[[0, 2, 3, 5]] > 0)  # ΔR and P along the normal and across it
    assert np.allclose(both, one + other, rtol=1e-12, atol=1e-15)


def test_against_pillar_hydro_far_from_the_wall():
    """Where both apply, a bead of a fiber far from the wall (h/a = 5, 10, 20, no screening):
    the added drag along the wall is pillar_hydro's β/(1 − β) to O(x³) (|difference| ≤ x³);
    across the wall the theory's is twice that to leading order. From the reflection series
    λ⊥ = 1/(1 − 9/8 x + x³/2) and λ∥ = 1/(1 − 9/16 x + x³/8 + O(x⁴)), λ − 1 = A₁x + A₂x² +
    A₃x³ with A = (9/8, (9/8)², (9/8)³ − 1/2) and B = (9/16, (9/16)², (9/16)³ − 1/8), the ratio
    is 2 (1 + 9/16 x + c₂ x²) + O(x³), c₂ = A₃/A₁ − B₃/B₁ − (9/16)² = 0.41059; the exact
    coefficients are within x³ of it. The flow's push along the wall (c_t − 1 → 9/16 x) is
    what pillar_hydro lacks."""
    for hh in (5.0, 10.0, 20.0):
        x = 1 / hh
        r, e = wall_terms_at(_pillar(), [[0.0, Y_WALL + hh * A]], [[1.0, 0.0]], bead_radius=A,
                             viscosity=MU, depth=math.inf)  # fmt: skip
        zeta = np.zeros(1)
        wall_drag(np.array([hh * A]), A, 1.0, 1e300, MU, zeta)
        assert abs(r[0, 0, 0] - zeta[0]) <= x**3
        a1, b1 = 9 / 8, 9 / 16
        c2 = (a1**3 - 0.5) / a1 - (b1**3 - 1 / 8) / b1 - b1**2
        assert abs(r[0, 1, 1] / r[0, 0, 0] - 2 * (1 + b1 * x + c2 * x**2)) <= x**3
        assert e[0, 0] == pytest.approx(wm.sphere_wall(hh - 1).shear_force - 1, rel=1e-12)
        assert e[0, 0] == pytest.approx(9 / 16 * x, rel=1.2 * x)


def test_strength_scales_every_correction_and_the_effect_is_registered():
    """k multiplies ΔR and E (k = 0.5: half of k = 1, 1e-14); the registry builds it; values
    outside [0, 2] are refused naming the effect."""
    pos = [[0.0, Y_WALL + 2.5]]
    r1, e1 = wall_terms_at(_pillar(), pos, [[1.0, -1.0]], bead_radius=A, viscosity=MU, depth=40.0)
    r2, e2 = wall_terms_at(_pillar(), pos, [[1.0, -1.0]], bead_radius=A, viscosity=MU, depth=40.0,
                           strength=0.5)  # fmt: skip
    assert np.allclose(r2, 0.5 * r1, rtol=1e-14) and np.allclose(e2, 0.5 * e1, rtol=1e-14)
    assert build_effects({"near_wall": 1.0}).effects[0].name == "near_wall"
    from fibersweep.errors import InputError

    for bad in (-0.1, 2.5):
        with pytest.raises(InputError, match="effects.near_wall"):
            build_effects({"near_wall": bad})


def test_lattice_frame_record_is_read_by_the_effect():
    """The effect's record takes the array's periods and shift from the run's frame."""
    fr = Lattice(0.0, 80.0, 80.0, 8.0, np.array([20.0, 20.0, 60.0, 60.0]),
                 *(np.zeros(1) for _ in range(6)))  # fmt: skip
    ctx = DynamicsContext(bead_radius=A, dx=2.0, depth=40.0, viscosity=MU, n_beads=1,
                          pillar=_pillar().arrays(), frame=fr)  # fmt: skip
    rec = NearWall(1.0).kernel(ctx)
    assert rec.lattice and (rec.px, rec.py, rec.sy) == (80.0, 80.0, 8.0) and rec.free
    assert not NearWall(1.0).kernel(DynamicsContext(bead_radius=A, dx=2.0, depth=40.0)).lattice


def _square(angle, centre=(0.0, 0.0), half=500.0):
    """A large square pillar turned by ``angle`` [rad] (CCW vertices); its top face's outward
    normal is (−sin angle, cos angle)."""
    c, s = math.cos(angle), math.sin(angle)
    base = np.array([[-half, -half], [half, -half], [half, half], [-half, half]])
    return base @ np.array([[c, s], [-s, c]]) + np.asarray(centre)


@pytest.mark.parametrize("gap", [0.01, 0.1, 1.0, 5.0])
@pytest.mark.parametrize("wall_angle", [0.0, 0.7])
def test_one_bead_has_the_sphere_wall_mobility(gap, wall_angle):
    """One bead (a sphere, free to roll) beside a flat face whose normal n is turned by an
    angle: its body mobility with the effect is [λ∥⁻¹ (I − nn) + λ⊥⁻¹ nn]/(6πμa) (Brenner
    across, Goldman, Cox & Brenner's torque-free drag along; 1e-12 relative, at any body
    angle), its rotation mobility is unchanged. Through the rigid model in a still fluid a
    contact force F on it (the pillar's repulsion, along n) moves it with F/(6πμa λ⊥)
    (1e-12), and with no effect with F/(6πμa)."""
    verts = _square(wall_angle)
    n = np.array([-math.sin(wall_angle), math.cos(wall_angle)])  # the top face's normal
    h = A * (1 + gap)
    pos = np.array([[0.0, 0.0]]) + (500.0 + h) * n
    sw = wm.sphere_wall(gap)
    want = (np.eye(2) - np.outer(n, n)) / sw.torque_free + np.outer(n, n) / sw.normal
    r, e = wall_terms_at(_pillar(ROUGH, verts), pos, np.zeros((1, 2)), bead_radius=A,
                         viscosity=MU, depth=math.inf, free_rotation=True)  # fmt: skip
    assert np.all(e == 0.0)
    bm = body_mobility(1, A, MU)
    for th in (0.0, 0.4, 2.0):
        c, sn = math.cos(th), math.sin(th)
        rot = np.array([[c, -sn], [sn, c]])
        nm_out = np.zeros((3, 3))
        rigid_wall_body(bm.offsets, np.array(bm.N), c, sn, _scratch(r, e), 0.0, 0.0, 0.0,
                        nm_out, np.zeros((3, 3, 3)))  # fmt: skip
        lab = rot @ nm_out[:2, :2] @ rot.T
        assert np.allclose(lab, want, rtol=0, atol=1e-12)  # 6πμa = 1
        assert nm_out[2, 2] == pytest.approx(bm.N[2, 2], rel=1e-12)
        assert np.allclose(nm_out[:2, 2], 0.0, atol=1e-15)

    # a contact force through the rigid model (a still fluid: no push): a smooth square whose
    # repulsion reaches the bead (r_cut 2h)
    flow = _field(lambda x, y: 0.0 * x, lambda x, y: 0.0 * x)
    from fibersweep.fiber.contact.bezier import smooth_curves

    centre = np.array([32.0, 60.0]) - (500.0 + h) * n
    sq = _square(wall_angle, centre)
    pil = Pillar(SMOOTH, sq, np.zeros((0, 2)), smooth_curves(sq, 5.0), 2.0 * h, A, 1.0)
    k_on = _kernel(flow, pil)
    k_off = _kernel(flow, pil, strength=0.0)
    v_on = np.array(_sphere_velocity(k_on, 32.0, 60.0))
    f = np.array([k_on.work.fx[0], k_on.work.fy[0]])
    assert np.linalg.norm(f) > 0 and abs(f @ n) == pytest.approx(np.linalg.norm(f), rel=1e-12)
    assert np.allclose(v_on, f / sw.normal, rtol=0, atol=1e-12 * np.linalg.norm(f))
    v_off = np.array(_sphere_velocity(k_off, 32.0, 60.0))
    assert np.allclose(v_off, f, rtol=0, atol=1e-12 * np.linalg.norm(f))


def test_effect_at_zero_strength_is_bit_identical_to_none():
    """near_wall = 0 gives, bit for bit, the velocity and run of no effect (its terms are
    exact zeros and the updated mobility is the identity times N), for a sphere and a
    6-bead fiber beside the wall in a shear."""
    flow = _field(lambda x, y: 0.5 * (y - Y_WALL) + 0.1, lambda x, y: 0.01 * (x - 20.0))
    for n, y0 in ((1, Y_WALL + 2.2), (6, Y_WALL + 3.0)):
        none = _kernel(flow, _pillar(), n=n, strength=0.0, t_stop=2.0)  # no effect
        ctx = DynamicsContext(bead_radius=A, dx=DX, depth=math.inf, viscosity=MU, n_beads=n,
                              pillar=_pillar().arrays())  # fmt: skip
        zero = none._replace(effects=(NearWall(0.0).kernel(ctx),) + none.effects)
        a = rigid_velocity(zero.frame, zero.flow, zero.pillar, zero.body, zero.work,
                           zero.effects, 20.0, y0, 0.05)  # fmt: skip
        b = rigid_velocity(none.frame, none.flow, none.pillar, none.body, none.work,
                           none.effects, 20.0, y0, 0.05)  # fmt: skip
        assert a[:3] == b[:3]
        rec_a, _, _ = run_rigid(zero, 20.0, y0, 0.05)
        rec_b, _, _ = run_rigid(none, 20.0, y0, 0.05)
        assert rec_a.tobytes() == rec_b.tobytes()  # bits (the record holds NaN columns)


def test_bead_spring_model_moves_its_beads_with_the_wall_terms():
    """The bead-spring model's bead velocities with the effect are M'(M⁻¹ u + E) + M' F
    (M' = (M⁻¹ + Z)⁻¹) of the dense algebra, u the interpolated flow, F the model's own
    elastic and contact forces, for a bent 6-bead chain half near the wall (1e-10); at
    k = 0 they are u + M F bit for bit."""
    flow = _field(lambda x, y: 0.4 * (y - Y_WALL), lambda x, y: -0.02 * (y - Y_WALL) ** 2 / 10)
    n = 6
    pos = np.column_stack([20.0 + 4.1 * np.arange(n), Y_WALL + 2.3 + 0.15 * np.arange(n) ** 2])
    out = {}
    for s in ("on", "zero", "none"):
        k = _kernel(flow, _pillar(), n=n, depth=40.0, strength=s == "on", model="bead-spring")
        if s == "zero":  # the effect present at k = 0
            ctx = DynamicsContext(bead_radius=A, dx=DX, depth=40.0, viscosity=MU, n_beads=n,
                                  pillar=_pillar().arrays())  # fmt: skip
            k = k._replace(effects=(NearWall(0.0).kernel(ctx),) + k.effects)
        k.work.x[:] = pos[:, 0]
        k.work.y[:] = pos[:, 1]
        bead_velocity(k.frame, k.flow, k.pillar, k.body, k.params, k.work, k.bead, k.effects)
        out[s] = (k.bead.f.copy(), k.work.u.copy(), np.column_stack([k.work.fx, k.work.fy]))
    f, u, force = out["on"]
    assert np.abs(force).max() > 0
    r, e = wall_terms_at(_pillar(), pos, u, bead_radius=A, viscosity=MU, depth=40.0)
    z = np.zeros((2 * n, 2 * n))
    for i in range(n):
        z[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] = r[i]
    m = rpy_matrix(pos, A, MU)
    m_new = np.linalg.inv(np.linalg.inv(m) + z)
    want = m_new @ (np.linalg.solve(m, u.ravel()) + e.ravel() + force.ravel())
    assert np.allclose(f, want, rtol=0, atol=1e-10 * np.abs(want).max())
    assert out["zero"][0].tobytes() == out["none"][0].tobytes()


def test_rigid_model_keeps_a_beads_terms_within_the_reuse_distance():
    """The rigid model keeps a bead's ΔR and push map while the bead stays within
    RIGID_REUSE (2 finite-difference steps) of where they were computed; its force E = P u
    follows the current u always; a bead that moved further gets fresh terms (equal to a
    computation from scratch there, 1e-15). Over that distance the terms change by at most
    1.5 RIGID_REUSE/δ of the largest at a contact gap δ = 0.1 a (λ⊥ ~ a/δ: 1/δ, times
    λ⊥/(λ⊥ − 1) ≈ 1.1)."""
    from fibersweep.fiber.effects.near_wall import RIGID_REUSE

    tol = RIGID_REUSE
    arr = _pillar().arrays()
    sides = nw.sides_of(arr)
    assert sides.shape == (4, 6)

    def call(b, x, y, u):
        wall_terms(np.array([x]), np.array([y]), np.array([u], dtype=float), np.zeros(1), A,
                   1.0, 20.0, False, arr.kind, arr.verts, arr.circle, arr.curves, np.zeros(3),
                   sides, False, 1.0, 1.0, 0.0, np.zeros(4), tol, b)  # fmt: skip
        return b[:, 0].copy()

    y0 = Y_WALL + 1.1 * A
    b = nw.new_scratch(1)
    first = call(b, 10.0, y0, (1.0, -0.5))
    kept = call(b, 10.0 + 0.9 * tol, y0 - 0.9 * tol, (2.0, 0.3))
    assert np.array_equal(kept[nw.LX : nw.EX], first[nw.LX : nw.EX])
    p = kept[[nw.PXX, nw.PXY, nw.PXY, nw.PYY]].reshape(2, 2)
    assert np.allclose(kept[[nw.EX, nw.EY]], p @ [2.0, 0.3], rtol=1e-15, atol=0)
    moved = call(b, 10.0, y0 - 1.1 * tol, (2.0, 0.3))
    fresh = call(nw.new_scratch(1), 10.0, y0 - 1.1 * tol, (2.0, 0.3))
    assert np.allclose(moved, fresh, rtol=1e-15, atol=0)
    delta = 0.1 * A
    near = call(nw.new_scratch(1), 10.0, Y_WALL + A + delta, (1.0, -0.5))
    off = call(nw.new_scratch(1), 10.0, Y_WALL + A + delta + tol, (1.0, -0.5))
    rel = np.abs(off[nw.RXX : nw.EX] - near[nw.RXX : nw.EX]) / np.abs(near[nw.RXX : nw.EX]).max()
    assert rel.max() <= 1.5 * tol / delta
