"""The source's bead-spring fiber: stretching + bending springs, RPY mobility, BDF2 stepping.

Energy (SPEC section 3), t_i = r_i − r_{i−1}:
    H = Σ_i (S/4a)(|t_i| − 2a)² + Σ_i (B/2a)(1 − t̂_{i+1}·t̂_i),
S = E π a², B = E π a⁴/4. Bead velocities U = u(r) + M(r) F(r).

Time stepping: linearly implicit second-order BDF on the positions q (2n),
with extrapolation q* = 2 q^k − q^{k−1}, frozen mobility M* = M(q*) and the
Jacobian J = ∂F/∂q of the elastic and contact forces (central differences):
    (I − (2Δt/3) M* J) δ = (2Δt/3) [f(q*) − (q^k − q^{k−1})/Δt],  q^{k+1} = q* + δ.
The first step is the linearly implicit backward Euler. With the stiff modes
implicit, Δt is bounded by accuracy, not by the 1e-7 s spring times.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fibersweep.errors import InputError
from fibersweep.fiber import kparams as K
from fibersweep.fiber import record as R
from fibersweep.fiber.contact import pillar_forces
from fibersweep.fiber.elastic import elastic_forces
from fibersweep.fiber.mobility import _rpy_fill, body_mobility, fiber_offsets
from fibersweep.fiber.rigid import body_velocity, coulomb_friction
from fibersweep.fiber.setup import kernel_arrays
from fibersweep.fiber.wallhydro import mobility_with_wall_drag, wall_drag
from fibersweep.flow.field import interpolate_ib

__all__ = [
    "DEFAULT_DT",
    "integrate_bead_spring",
    "run_bead_spring",
]

DEFAULT_DT = 5e-5  # s; see run_bead_spring and the dt-convergence test
CHUNK = 20_000


@nb.njit(cache=True)
def _forces(x, y, prm, verts, pbx, pby, curves, fx, fy, cfx, cfy, st, dist):
    """Elastic + contact forces; returns (any_contact, cx, cy)."""
    elastic_forces(x, y, prm[K.P_A], prm[K.P_STRETCH], prm[K.P_BEND], fx, fy)
    any_c, cx, cy = pillar_forces(
        int(prm[K.P_KIND]), x, y, verts, pbx, pby, curves, prm[K.P_R_CUT], prm[K.P_R_EQ],
        prm[K.P_F_REF], cfx, cfy, st, dist,
    )  # fmt: skip
    for i in range(x.shape[0]):
        fx[i] += cfx[i]
        fy[i] += cfy[i]
    return any_c, cx, cy


@nb.njit(cache=True)
def _velocity(x, y, ux, uy, dx, prm, verts, pbx, pby, curves, mob, u, f, fx, fy, cfx, cfy, st,
              dist, s_off, pm, nm, fric):  # fmt: skip
    """f(q) = u + M F at (x, y) into f (2n); M into mob. Returns (any_c, cx, cy).

    With ``pillar_hydro`` on, f = (I + M Z)⁻¹ u + M' F and mob holds M'
    (:func:`wallhydro.mobility_with_wall_drag`); friction then still uses the
    baseline rigid-body N.

    Friction (if on) is the rigid model's (:func:`rigid.coulomb_friction`) for
    the rigid body the nearly rigid fiber moves as: body axis from tail to head,
    offsets ``s_off``, body-frame ``pm`` (P) and ``nm`` (N); the frictionless
    body velocity is P u_b + N (F_c, τ_c). ``fric`` receives the tangential forces.
    """
    n = x.shape[0]
    a = prm[K.P_A]
    interpolate_ib(ux, uy, dx, x, y, u)
    any_c, cx, cy = _forces(x, y, prm, verts, pbx, pby, curves, fx, fy, cfx, cfy, st, dist)
    vs = prm[K.P_VSCALE]
    for i in range(n):
        f[2 * i] = vs * u[i, 0]
        f[2 * i + 1] = vs * u[i, 1]
    mu_f = prm[K.P_MU_F]
    if any_c and mu_f > 0.0:
        # Friction as for the rigid body the (nearly rigid) fiber moves as: body frame
        # from the end-to-end axis, frictionless body velocity P u_b + N (F_c, τ_c).
        ex = x[n - 1] - x[0]
        ey = y[n - 1] - y[0]
        le = math.hypot(ex, ey)
        c = ex / le
        sn = ey / le
        vbx, vby, om = body_velocity(c, sn, s_off, pm, nm, f, cfx, cfy, True)
        coulomb_friction(c, sn, s_off, nm, cfx, cfy, mu_f, vbx, vby, om, fric)
        for i in range(n):
            fn = math.hypot(cfx[i], cfy[i])
            if fn > 0.0:
                fx[i] += fric[i] * (-cfy[i] / fn)
                fy[i] += fric[i] * (cfx[i] / fn)
    _rpy_fill(x, y, a, prm[K.P_MU], mob)
    hs = prm[K.P_HYD_S]
    if hs > 0.0:
        zeta = np.empty(n)
        if wall_drag(dist, a, hs, prm[K.P_HYD_L], prm[K.P_MU], zeta) > 0:
            mobility_with_wall_drag(mob, zeta, f)  # f = (I + MZ)⁻¹u; the step uses M'
    for r in range(2 * n):
        acc = 0.0
        for j in range(n):
            acc += mob[r, 2 * j] * fx[j] + mob[r, 2 * j + 1] * fy[j]
        f[r] += acc
    return any_c, cx, cy


@nb.njit(cache=True)
def _jacobian(x, y, prm, verts, pbx, pby, curves, jac, fx, fy, gx, gy, st):
    """J = ∂F/∂q (2n, 2n) by central differences, banded.

    Elastic forces couple a bead to its two neighbours on each side; the contact
    force on a bead depends on that bead only (a 2x2 diagonal block, computed
    only for beads with a non-zero contact stiffness ``st``).
    """
    n = x.shape[0]
    a = prm[K.P_A]
    h = 1e-6 * a
    for i in range(2 * n):
        for j in range(2 * n):
            jac[i, j] = 0.0
    one_x = np.empty(1)
    one_y = np.empty(1)
    c1 = np.empty(1)
    c2 = np.empty(1)
    c3 = np.empty(1)
    c4 = np.empty(1)
    d1 = np.empty(1)
    d2 = np.empty(1)
    for j in range(n):
        lo = max(0, j - 2)
        hi = min(n, j + 3)
        for comp in range(2):
            col = 2 * j + comp
            if comp == 0:
                x[j] += h
            else:
                y[j] += h
            elastic_forces(x, y, a, prm[K.P_STRETCH], prm[K.P_BEND], fx, fy)
            if comp == 0:
                x[j] -= 2.0 * h
            else:
                y[j] -= 2.0 * h
            elastic_forces(x, y, a, prm[K.P_STRETCH], prm[K.P_BEND], gx, gy)
            if comp == 0:
                x[j] += h
            else:
                y[j] += h
            for i in range(lo, hi):
                jac[2 * i, col] = (fx[i] - gx[i]) / (2.0 * h)
                jac[2 * i + 1, col] = (fy[i] - gy[i]) / (2.0 * h)
            if st[j] > 0.0:
                one_x[0] = x[j] + (h if comp == 0 else 0.0)
                one_y[0] = y[j] + (h if comp == 1 else 0.0)
                pillar_forces(
                    int(prm[K.P_KIND]), one_x, one_y, verts, pbx, pby, curves, prm[K.P_R_CUT],
                    prm[K.P_R_EQ], prm[K.P_F_REF], c1, c2, d1, d2,
                )  # fmt: skip
                one_x[0] = x[j] - (h if comp == 0 else 0.0)
                one_y[0] = y[j] - (h if comp == 1 else 0.0)
                pillar_forces(
                    int(prm[K.P_KIND]), one_x, one_y, verts, pbx, pby, curves, prm[K.P_R_CUT],
                    prm[K.P_R_EQ], prm[K.P_F_REF], c3, c4, d1, d2,
                )  # fmt: skip
                jac[2 * j, col] += (c1[0] - c3[0]) / (2.0 * h)
                jac[2 * j + 1, col] += (c2[0] - c4[0]) / (2.0 * h)


@nb.njit(cache=True)
def integrate_bead_spring(q, qprev, state, ux, uy, dx, verts, pbx, pby, curves, prm, stride,
                          rec, brec, s_off, pm, nm):  # fmt: skip
    """Advance a bead-spring fiber with fixed Δt until a stop condition or ``rec`` is full.

    Parameters
    ----------
    q, qprev : ndarray, shape (2n,)
        Positions at the current and previous step (x0, y0, x1, ...) [µm]; updated.
    state : ndarray, shape (5,)
        [t, stopped_since, have_prev (0/1), theta (unwrapped) [rad], step] (updated).
    ux, uy, dx, verts, pbx, pby, curves, prm : as in the rigid integrator.
    stride : int
        Record every ``stride`` steps, and at every change of the contact flag.
    rec : ndarray, shape (cap, record.NCOLS)
    brec : ndarray, shape (cap, n, 2)
        Bead positions of each recorded row.
    s_off, pm, nm : ndarray, shapes (n,), (3, 2n), (3, 3)
        Rigid-body bead offsets, P and N (friction only).

    Returns
    -------
    (rows, code)
    """
    n2 = q.shape[0]
    n = n2 // 2
    dt = prm[K.P_DT]
    a = prm[K.P_A]
    x = np.empty(n)
    y = np.empty(n)
    u = np.empty((n, 2))
    f = np.empty(n2)
    fx = np.empty(n)
    fy = np.empty(n)
    gx = np.empty(n)
    gy = np.empty(n)
    cfx = np.empty(n)
    cfy = np.empty(n)
    st = np.empty(n)
    dist = np.empty(n)
    mob = np.empty((n2, n2))
    jac = np.empty((n2, n2))
    lhs = np.empty((n2, n2))
    rhs = np.empty(n2)
    qs = np.empty(n2)
    v = np.zeros(n2)
    fric = np.zeros(n)
    t = state[0]
    stopped_since = state[1]
    have_prev = state[2] > 0.5
    theta = state[3]
    step = int(state[4])
    mode = int(prm[K.P_MODE])
    cap = rec.shape[0]
    rows = 0
    code = R.CHUNK_FULL
    last_contact = -1.0
    last_stopped = -1.0
    if have_prev:
        for k in range(n2):
            v[k] = (q[k] - qprev[k]) / dt
    while rows < cap:
        # Extrapolated state (BDF2) or the current one (first step: backward Euler).
        for k in range(n2):
            qs[k] = 2.0 * q[k] - qprev[k] if have_prev else q[k]
        for i in range(n):
            x[i] = qs[2 * i]
            y[i] = qs[2 * i + 1]
        any_c, cx, cy = _velocity(
            x, y, ux, uy, dx, prm, verts, pbx, pby, curves, mob, u, f, fx, fy, cfx, cfy, st,
            dist, s_off, pm, nm, fric,
        )  # fmt: skip
        min_d = 1e300
        for i in range(n):
            min_d = min(min_d, dist[i])
        # Record the current state q (time t) with the velocity estimate v.
        hx = q[2 * n - 2]
        hy = q[2 * n - 1]
        tx = q[0]
        ty = q[1]
        ang = math.atan2(hy - ty, hx - tx)
        theta += (ang - theta + math.pi) % (2.0 * math.pi) - math.pi
        xc = 0.0
        yc = 0.0
        vxc = 0.0
        vyc = 0.0
        for i in range(n):
            xc += q[2 * i] / n
            yc += q[2 * i + 1] / n
            vxc += v[2 * i] / n
            vyc += v[2 * i + 1] / n
        com_speed = math.hypot(vxc, vyc)
        cflag = 1.0 if any_c else 0.0
        stopped = any_c and com_speed < prm[K.P_TRAP_SPEED] and have_prev
        # Stop tests (on the state about to be recorded).
        code = R.CHUNK_FULL
        finite = True
        for k in range(n2):
            if not math.isfinite(q[k]):
                finite = False
        out = False
        for i in range(n):
            if q[2 * i + 1] < prm[K.P_Y_LO] or q[2 * i + 1] > prm[K.P_Y_HI]:
                out = True
        if stopped:
            if not math.isfinite(stopped_since):
                stopped_since = t
        else:
            stopped_since = math.nan
        if not finite:
            code = R.NAN
        elif min_d < 0.5 * a:
            code = R.PENETRATION
        elif out:
            code = R.WALL
        elif stopped and t - stopped_since >= prm[K.P_TRAP_TIME]:
            code = R.TRAPPED
        elif mode == 0 and min(hx, tx) > prm[K.P_X_STOP]:
            code = R.PASSED
        elif mode == 1 and t >= prm[K.P_T_STOP] - 0.5 * dt:
            code = R.TIME_REACHED
        elif t >= prm[K.P_T_MAX]:
            code = R.TIME_LIMIT
        # Record every `stride` steps, at every change of the contact or stopped flag,
        # and the final state, so that classify() on the record sees what the kernel saw.
        sflag = 1.0 if stopped else 0.0
        if (
            step % stride == 0
            or cflag != last_contact
            or sflag != last_stopped
            or code != R.CHUNK_FULL
        ):
            r = rec[rows]
            r[R.T] = t
            r[R.XC] = xc
            r[R.YC] = yc
            r[R.TH] = theta
            r[R.VX] = vxc
            r[R.VY] = vyc
            ex = hx - tx
            ey = hy - ty
            r[R.OM] = (ex * (v[2 * n - 1] - v[1]) - ey * (v[2 * n - 2] - v[0])) / (
                ex * ex + ey * ey
            )
            r[R.CONTACT] = cflag
            r[R.CX] = cx
            r[R.CY] = cy
            r[R.MIN_DIST] = min_d
            r[R.HEAD_SPEED] = math.hypot(v[2 * n - 2], v[2 * n - 1])
            r[R.COM_SPEED] = com_speed
            r[R.HX] = hx
            r[R.HY] = hy
            r[R.TX] = tx
            r[R.TY] = ty
            for i in range(n):
                brec[rows, i, 0] = q[2 * i]
                brec[rows, i, 1] = q[2 * i + 1]
            rows += 1
        last_contact = cflag
        last_stopped = sflag
        if code != R.CHUNK_FULL:
            break
        # Linearly implicit step.
        _jacobian(x, y, prm, verts, pbx, pby, curves, jac, gx, gy, cfx, cfy, st)
        c = 2.0 * dt / 3.0 if have_prev else dt
        for i2 in range(n2):
            for j2 in range(n2):
                acc = 0.0
                # J is banded: bead j couples to beads j-2..j+2 only.
                for k in range(max(0, 2 * (j2 // 2) - 4), min(n2, 2 * (j2 // 2) + 6)):
                    acc += mob[i2, k] * jac[k, j2]
                lhs[i2, j2] = -c * acc
            lhs[i2, i2] += 1.0
            if have_prev:
                rhs[i2] = c * (f[i2] - (q[i2] - qprev[i2]) / dt)
            else:
                rhs[i2] = c * f[i2]
        delta = np.linalg.solve(lhs, rhs)
        for k in range(n2):
            qnew = qs[k] + delta[k]
            if have_prev:
                v[k] = (3.0 * qnew - 4.0 * q[k] + qprev[k]) / (2.0 * dt)
            else:
                v[k] = (qnew - q[k]) / dt
            qprev[k] = q[k]
            q[k] = qnew
        have_prev = True
        t += dt
        step += 1
    state[0] = t
    state[1] = stopped_since
    state[2] = 1.0 if have_prev else 0.0
    state[3] = theta
    state[4] = step
    return rows, code


def run_bead_spring(setup, prm: np.ndarray, x0: float, y0: float, th0: float, beads0=None):
    """Integrate a bead-spring run (see :func:`fibersweep.fiber.run.simulate`).

    The default Δt = DEFAULT_DT (5e-5 s) keeps class and δ within the
    tolerances of Δt = 1e-7 s (checked in tests/validation/test_fiber_beadspring.py).

    Returns
    -------
    (rec, beads, code)
        Record rows (record.COLS), bead positions (rows, n, 2) [µm], stop code.
    """
    if setup.params.kT > 0.0:
        raise InputError("effects.brownian: only the rigid model has Brownian motion")
    st = setup.settings
    n = setup.n
    prm = prm.copy()
    dt = st.step.dt if st.step.dt is not None else DEFAULT_DT
    prm[K.P_DT] = dt
    # About one record row per 1e-4 s (and at every contact change).
    stride = max(1, int(round(1e-4 / dt)))
    if beads0 is None:
        s = fiber_offsets(n, st.bead_radius)
        beads0 = np.column_stack([x0 + s * math.cos(th0), y0 + s * math.sin(th0)])
    q = np.ascontiguousarray(beads0, dtype=np.float64).reshape(-1).copy()
    qprev = q.copy()
    state = np.array([0.0, math.nan, 0.0, th0, 0.0])
    arrays = kernel_arrays(setup)
    bm = body_mobility(n, float(st.bead_radius), float(setup.field.fluid.viscosity))
    recs, brecs = [], []
    while True:
        rec = np.empty((CHUNK, R.NCOLS))
        brec = np.empty((CHUNK, n, 2))
        rows, code = integrate_bead_spring(
            q, qprev, state, *arrays, prm, stride, rec, brec, bm.offsets, bm.P, bm.N
        )
        recs.append(rec[:rows])
        brecs.append(brec[:rows])
        if code != R.CHUNK_FULL:
            return np.concatenate(recs), np.concatenate(brecs), code
