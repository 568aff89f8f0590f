"""Rigid multiblob fiber: body velocity from the background flow and contact, adaptive RK2.

For a straight rigid fiber of n beads (body frame: beads on the x axis at
offsets s_i), the body velocity (V, Ω) is
    (V_b, Ω) = P u_b + N (F_b, τ),   P = N Kᵀ M⁻¹,  N = (Kᵀ M⁻¹ K)⁻¹,
with u_b the beads' background velocities rotated into the body frame and
(F, τ) the total contact force and torque (see :mod:`fibersweep.fiber.mobility`).

Time stepping: explicit midpoint (RK2). The step is bounded by
- a bead displacement: ``max_disp`` far away, shrinking to ``contact_disp``
  as the closest bead approaches the contact layer (half the remaining free
  distance per step, so a step never carries a bead through the layer);
- the contact stiffness: Δt ≤ 0.5 / (m_tip Σ_i k_i), with m_tip the largest
  bead mobility of the rigid body and k_i = Σ_pairs |d|F|/dr| (stability of
  the explicit step, whose real stability interval is [−2, 0]);
- ``dt_max``.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fibersweep.fiber import kparams as K
from fibersweep.fiber import record as R
from fibersweep.fiber.contact import pillar_forces
from fibersweep.fiber.wallhydro import rigid_wall_velocity, wall_drag
from fibersweep.flow.field import interpolate_ib

__all__ = ["body_velocity", "coulomb_friction", "integrate_rigid", "rigid_velocity", "seed_numba"]


@nb.njit(cache=True)
def seed_numba(seed: int) -> None:
    """Seed Numba's own random generator (used for Brownian increments)."""
    np.random.seed(seed)  # noqa: NPY002 - Numba has its own per-thread RNG


@nb.njit(cache=True)
def body_velocity(c, sn, s, pm, nm, ub, fx, fy, with_force):
    """Body-frame velocity P u_b + N (F_b, τ) of a rigid fiber of beads at offsets ``s``.

    Parameters
    ----------
    c, sn : float
        cos and sin of the fiber angle.
    s : ndarray, shape (n,)
        Bead offsets along the axis [µm].
    pm, nm : ndarray, shapes (3, 2n), (3, 3)
        Body-frame P and N.
    ub : ndarray, shape (2n,)
        Background velocities of the beads, lab frame (x0, y0, x1, ...) [µm/s].
    fx, fy : ndarray, shape (n,)
        Forces on the beads, lab frame [pN]; used only when ``with_force``.
    with_force : bool

    Returns
    -------
    (vbx, vby, om)
        Body velocity (body frame) [µm/s, rad/s].
    """
    n = s.shape[0]
    vbx = 0.0
    vby = 0.0
    om = 0.0
    for i in range(n):
        ubx = c * ub[2 * i] + sn * ub[2 * i + 1]
        uby = -sn * ub[2 * i] + c * ub[2 * i + 1]
        vbx += pm[0, 2 * i] * ubx + pm[0, 2 * i + 1] * uby
        vby += pm[1, 2 * i] * ubx + pm[1, 2 * i + 1] * uby
        om += pm[2, 2 * i] * ubx + pm[2, 2 * i + 1] * uby
    if with_force:
        fbx = 0.0
        fby = 0.0
        tq = 0.0
        for i in range(n):
            fbx += c * fx[i] + sn * fy[i]
            fby += -sn * fx[i] + c * fy[i]
            tq += s[i] * (c * fy[i] - sn * fx[i])
        vbx += nm[0, 0] * fbx + nm[0, 1] * fby + nm[0, 2] * tq
        vby += nm[1, 0] * fbx + nm[1, 1] * fby + nm[1, 2] * tq
        om += nm[2, 0] * fbx + nm[2, 1] * fby + nm[2, 2] * tq
    return vbx, vby, om


@nb.njit(cache=True)
def coulomb_friction(c, sn, s, nm, fx, fy, mu_f, vbx, vby, om, ft):
    """Coulomb friction on the contacting beads of a rigid fiber (projected Gauss-Seidel).

    Each bead's tangential force (along t̂ = ẑ × n̂, n̂ the direction of its
    contact force) is set to stop its tangential motion, clipped to ±μ_f |F_n|
    (stick or slide); the normal forces are fixed. All in the body frame.

    Parameters
    ----------
    c, sn : float
        cos and sin of the fiber angle.
    s : ndarray, shape (n,)
        Bead offsets [µm].
    nm : ndarray, shape (3, 3)
        Body mobility N.
    fx, fy : ndarray, shape (n,)
        Contact forces (lab frame) [pN].
    mu_f : float
        Friction coefficient.
    vbx, vby, om : float
        Frictionless body velocity (body frame) [µm/s, rad/s].
    ft : ndarray, shape (n,)
        Written with each bead's tangential force along its t̂ [pN].

    Returns
    -------
    (vbx, vby, om)
        Body velocity with friction (body frame).
    """
    n = s.shape[0]
    for i in range(n):
        ft[i] = 0.0
    for _ in range(30):
        change = 0.0
        for i in range(n):
            fnx = c * fx[i] + sn * fy[i]
            fny = -sn * fx[i] + c * fy[i]
            fn = math.sqrt(fnx * fnx + fny * fny)
            if fn == 0.0:
                continue
            tx = -fny / fn
            ty = fnx / fn
            vt = vbx * tx + (vby + om * s[i]) * ty
            # m_t = t̂ᵀ K_i N K_iᵀ t̂ with K_iᵀ t̂ = (tx, ty, s_i ty)
            kz = s[i] * ty
            g0 = nm[0, 0] * tx + nm[0, 1] * ty + nm[0, 2] * kz
            g1 = nm[1, 0] * tx + nm[1, 1] * ty + nm[1, 2] * kz
            g2 = nm[2, 0] * tx + nm[2, 1] * ty + nm[2, 2] * kz
            mt = tx * g0 + ty * g1 + kz * g2
            lim = mu_f * fn
            new = min(lim, max(-lim, ft[i] - vt / mt))
            d = new - ft[i]
            if d != 0.0:
                ft[i] = new
                vbx += g0 * d
                vby += g1 * d
                om += g2 * d
                change = max(change, abs(d) / lim)
        if change < 1e-6:
            break
    return vbx, vby, om


@nb.njit(cache=True)
def rigid_velocity(
    xc,
    yc,
    th,
    s,
    pm,
    nm,
    ux,
    uy,
    dx,
    verts,
    pbx,
    pby,
    curves,
    prm,
    bx,
    by,
    u,
    fx,
    fy,
    st,
    dist,
    ft_,
):
    """Lab-frame body velocity of a rigid fiber at (xc, yc, th).

    Parameters
    ----------
    xc, yc, th : float
        Centre [µm] and angle [rad] of the axis (towards bead n-1).
    s : ndarray, shape (n,)
        Bead offsets along the axis [µm].
    pm, nm : ndarray, shapes (3, 2n), (3, 3)
        Body-frame P and N.
    ux, uy, dx : field arrays (nx, ny) [µm/s] and spacing [µm].
    verts, pbx, pby, curves : pillar arrays (see contact.pillar_forces).
    prm : ndarray
        Kernel parameters (kparams).
    bx, by, u, fx, fy, st, dist, ft_ : work arrays, shapes (n,), (n,), (n, 2), (n,) x5.

    Returns
    -------
    (vx, vy, om, any_contact, cx, cy, min_dist, stiff_sum)
    """
    n = s.shape[0]
    c = math.cos(th)
    sn = math.sin(th)
    for i in range(n):
        bx[i] = xc + s[i] * c
        by[i] = yc + s[i] * sn
    interpolate_ib(ux, uy, dx, bx, by, u)
    any_c, cx, cy = pillar_forces(
        int(prm[K.P_KIND]),
        bx,
        by,
        verts,
        pbx,
        pby,
        curves,
        prm[K.P_R_CUT],
        prm[K.P_R_EQ],
        prm[K.P_F_REF],
        fx,
        fy,
        st,
        dist,
    )
    vscale = prm[K.P_VSCALE]
    min_d = 1e300
    stiff = 0.0
    for i in range(n):
        u[i, 0] *= vscale
        u[i, 1] *= vscale
        if dist[i] < min_d:
            min_d = dist[i]
        stiff += st[i]
    ub = u.reshape(2 * n)
    vbx, vby, om = body_velocity(c, sn, s, pm, nm, ub, fx, fy, any_c)
    nm_eff = nm
    hyd_s = prm[K.P_HYD_S]
    if hyd_s > 0.0:
        zeta = np.empty(n)
        if wall_drag(dist, prm[K.P_A], hyd_s, prm[K.P_HYD_L], prm[K.P_MU], zeta) > 0:
            nm_eff = np.empty((3, 3))
            vbx, vby, om = rigid_wall_velocity(s, nm, zeta, vbx, vby, om, nm_eff)
    if any_c:
        mu_f = prm[K.P_MU_F]
        if mu_f > 0.0:
            vbx, vby, om = coulomb_friction(c, sn, s, nm_eff, fx, fy, mu_f, vbx, vby, om, ft_)
    vx = c * vbx - sn * vby
    vy = sn * vbx + c * vby
    return vx, vy, om, any_c, cx, cy, min_d, stiff


@nb.njit(cache=True)
def integrate_rigid(state, s, pm, nm, chol, tip_m, ux, uy, dx, verts, pbx, pby, curves, prm, rec):
    """Advance a rigid fiber until a stop condition or until ``rec`` is full.

    Parameters
    ----------
    state : ndarray, shape (5,)
        [t, xc, yc, th, t_stopped_since] (updated in place; the last is NaN when
        the fiber is not in a stopped contact).
    s, pm, nm, chol : body-frame offsets (n,), P (3, 2n), N (3, 3), chol(N) (3, 3).
    tip_m : float
        Largest bead mobility of the rigid body [µm/(pN s)].
    ux, uy, dx, verts, pbx, pby, curves, prm : see :func:`rigid_velocity`.
    rec : ndarray, shape (cap, record.NCOLS)
        One row per step, written from row 0.

    Returns
    -------
    (rows, code) : (int, int)
        Rows written and the stop code (record.CHUNK_FULL when ``rec`` filled up).
    """
    n = s.shape[0]
    bx = np.empty(n)
    by = np.empty(n)
    u = np.empty((n, 2))
    fx = np.empty(n)
    fy = np.empty(n)
    st = np.empty(n)
    dist = np.empty(n)
    ft_ = np.zeros(n)
    t = state[0]
    xc = state[1]
    yc = state[2]
    th = state[3]
    stopped_since = state[4]
    half = 0.5 * (s[n - 1] - s[0])
    sh = s[n - 1]
    st_ = s[0]
    kT = prm[K.P_KT]
    mode = int(prm[K.P_MODE])
    rows = 0
    code = R.CHUNK_FULL
    cap = rec.shape[0]
    while rows < cap:
        vx, vy, om, any_c, cx, cy, min_d, stiff = rigid_velocity(
            xc,
            yc,
            th,
            s,
            pm,
            nm,
            ux,
            uy,
            dx,
            verts,
            pbx,
            pby,
            curves,
            prm,
            bx,
            by,
            u,
            fx,
            fy,
            st,
            dist,
            ft_,
        )
        c = math.cos(th)
        sn = math.sin(th)
        hvx = vx - om * sh * sn
        hvy = vy + om * sh * c
        com_speed = math.sqrt(vx * vx + vy * vy)
        r = rec[rows]
        r[R.T] = t
        r[R.XC] = xc
        r[R.YC] = yc
        r[R.TH] = th
        r[R.VX] = vx
        r[R.VY] = vy
        r[R.OM] = om
        r[R.CONTACT] = 1.0 if any_c else 0.0
        r[R.CX] = cx
        r[R.CY] = cy
        r[R.MIN_DIST] = min_d
        r[R.HEAD_SPEED] = math.sqrt(hvx * hvx + hvy * hvy)
        r[R.COM_SPEED] = com_speed
        r[R.HX] = xc + sh * c
        r[R.HY] = yc + sh * sn
        r[R.TX] = xc + st_ * c
        r[R.TY] = yc + st_ * sn
        rows += 1
        # Stop tests on the state just recorded.
        if not (math.isfinite(vx) and math.isfinite(vy) and math.isfinite(om)):
            code = R.NAN
            break
        if min_d < 0.5 * prm[K.P_A]:
            code = R.PENETRATION
            break
        ylo = yc - half * abs(sn)
        yhi = yc + half * abs(sn)
        if ylo < prm[K.P_Y_LO] or yhi > prm[K.P_Y_HI]:
            code = R.WALL
            break
        if any_c and com_speed < prm[K.P_TRAP_SPEED]:
            if not math.isfinite(stopped_since):
                stopped_since = t
            if t - stopped_since >= prm[K.P_TRAP_TIME]:
                code = R.TRAPPED
                break
        else:
            stopped_since = math.nan
        if mode == 0:
            if min(r[R.HX], r[R.TX]) > prm[K.P_X_STOP]:
                code = R.PASSED
                break
        elif t >= prm[K.P_T_STOP]:
            code = R.TIME_REACHED
            break
        if t >= prm[K.P_T_MAX]:
            code = R.TIME_LIMIT
            break
        # Step size.
        speed = com_speed + abs(om) * half + 1e-12
        free = min_d - prm[K.P_R_CUT]
        disp = min(prm[K.P_MAX_DISP], max(prm[K.P_CONTACT_DISP], 0.5 * free))
        dt = min(disp / speed, prm[K.P_DT_MAX])
        if stiff > 0.0:
            dt = min(dt, 0.5 / (tip_m * stiff))
        if mode == 1 and t + dt > prm[K.P_T_STOP]:
            dt = max(prm[K.P_T_STOP] - t, 1e-12)
        # Midpoint step.
        vx2, vy2, om2, _, _, _, _, _ = rigid_velocity(
            xc + 0.5 * dt * vx,
            yc + 0.5 * dt * vy,
            th + 0.5 * dt * om,
            s,
            pm,
            nm,
            ux,
            uy,
            dx,
            verts,
            pbx,
            pby,
            curves,
            prm,
            bx,
            by,
            u,
            fx,
            fy,
            st,
            dist,
            ft_,
        )
        xc += dt * vx2
        yc += dt * vy2
        th += dt * om2
        if kT > 0.0:
            amp = math.sqrt(2.0 * kT * dt)
            g0 = np.random.standard_normal()  # noqa: NPY002 - Numba RNG
            g1 = np.random.standard_normal()  # noqa: NPY002 - Numba RNG
            g2 = np.random.standard_normal()  # noqa: NPY002 - Numba RNG
            q0 = amp * (chol[0, 0] * g0)
            q1 = amp * (chol[1, 0] * g0 + chol[1, 1] * g1)
            q2 = amp * (chol[2, 0] * g0 + chol[2, 1] * g1 + chol[2, 2] * g2)
            xc += c * q0 - sn * q1
            yc += sn * q0 + c * q1
            th += q2
        t += dt
    state[0] = t
    state[1] = xc
    state[2] = yc
    state[3] = th
    state[4] = stopped_since
    return rows, code
