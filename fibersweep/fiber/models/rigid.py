"""Rigid multiblob fiber: body velocity from the background flow and contact, adaptive RK2.

For a straight rigid fiber of n beads (body frame: beads on the x axis at
offsets s_i), the body velocity (V, Ω) is
    (V_b, Ω) = P u_b + N (F_b, τ),   P = N Kᵀ M⁻¹,  N = (Kᵀ M⁻¹ K)⁻¹,
with u_b the beads' background velocities rotated into the body frame and
(F, τ) the total contact force and torque (see :mod:`fibersweep.fiber.hydro.rpy`).

Time stepping: explicit midpoint (RK2). The step is bounded by
- a bead displacement: ``max_disp`` far away, shrinking to ``contact_disp``
  as the closest bead approaches the contact layer (half the remaining free
  distance per step, so a step never carries a bead through the layer);
- the contact stiffness: Δt ≤ 0.5 / λ, λ the contact force's decay rate
  (:mod:`fibersweep.fiber.integrators.contact_rate`): m_tip Σ_i k_i, with m_tip the
  largest bead mobility of the rigid body and k_i = Σ_pairs |d|F|/dr|, or, where an
  effect changed the body mobility (``near_wall``, ``pillar_hydro``), Σ_i k_i g_iᵀ N' g_i
  along each bead's contact normal (stability of the explicit step, whose real stability
  interval is [−2, 0]);
- ``dt_max``.

While the fiber is *stopped* (in contact and slower than ``trap_speed``) it
sits in the stiff well of the contact force, and the stiffness bound would make
the explicit step thousands of times shorter than the displacement bound (3e-5 s
against ``dt_max`` = 0.1 s at the defaults). There, when
``stopped_implicit`` is on, the step is a linearly implicit two-stage
Rosenbrock step (ROS2, γ = 1 + 1/√2: second order for any Jacobian, L-stable)
with the 3×3 Jacobian of (ẋ, ẏ, θ̇) by forward differences, bounded by the
displacement and ``dt_max`` only, and by the end of the trap time so that a
trapped run ends exactly trap_time after it stopped. A step that would leave
the fiber moving faster than ``trap_speed`` (or out of contact) is not taken:
the explicit step handles the way out of a stop (stick-slip under friction),
and later implicit steps are shortened. Its fixed points are the ODE's (zero
velocity gives a zero step), so without friction where a fiber comes to rest
does not depend on the step; with Coulomb friction every place where it sticks
is a rest, and which one it reaches depends on the path (validation: 0.05 µm).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fibersweep.fiber import frame as F
from fibersweep.fiber.hydro.rpy import body_velocity
from fibersweep.fiber.integrators.contact_rate import contact_rate
from fibersweep.fiber.integrators.rosw import GAMMA2
from fibersweep.fiber.kernel import hooks as H
from fibersweep.fiber.kernel import record as R

__all__ = ["integrate_rigid", "rigid_velocity", "ros2_step", "run_rigid", "seed_numba"]

FD_STEP = 1e-5  # finite-difference step of the Jacobian [µm] (angle: this / half-length)


@nb.njit(cache=True)
def seed_numba(seed: int) -> None:
    """Seed Numba's own random generator (used for Brownian increments)."""
    np.random.seed(seed)  # noqa: NPY002 - Numba has its own per-thread RNG


@nb.njit(cache=True)
def rigid_velocity(frame, flow, pillar, body, w, effects, xc, yc, th):
    """Lab-frame body velocity of a rigid fiber at (xc, yc, th).

    Parameters
    ----------
    frame : a :mod:`fibersweep.fiber.frame` record
        Where the pillars stand and how the field is read (channel or array).
    flow, pillar, body : bundles.FlowArrays, contact.PillarArrays, bundles.BodyArrays
    w : bundles.Work
        Receives the bead positions, background velocities, contact forces,
        stiffnesses and distances.
    effects : tuple
        Kernel records of the active effects (``Kernel.effects``).
    xc, yc, th : float
        Centre [µm] and angle [rad] of the axis (towards bead n-1).

    Returns
    -------
    (vx, vy, om, n_pillars, cx, cy, min_dist, rate)
        Velocity [µm/s, rad/s], pillars in contact (int) and the contact point
        [µm], smallest distance to a pillar [µm], the contact force's decay rate
        [1/s] (:func:`~fibersweep.fiber.integrators.contact_rate.contact_rate`).
    """
    # Bind the arrays once (each read of a bundle's field costs a reference count).
    s = body.s
    x = w.x
    y = w.y
    u = w.u
    fx = w.fx
    fy = w.fy
    st = w.st
    dist = w.dist
    n = s.shape[0]
    c = math.cos(th)
    sn = math.sin(th)
    for i in range(n):
        x[i] = xc + s[i] * c
        y[i] = yc + s[i] * sn
    F.velocity(frame, flow, x, y, u)
    n_c, cx, cy = F.contact(frame, pillar, x, y, fx, fy, st, dist)
    any_c = n_c > 0
    H.each_background(effects, w, u)
    min_d = 1e300
    for i in range(n):
        if dist[i] < min_d:
            min_d = dist[i]
    ub = u.reshape(2 * n)
    vbx, vby, om = body_velocity(c, sn, s, body.pm, body.nm, ub, fx, fy, any_c)
    nm_eff = body.nm
    vbx, vby, om, nm_eff = H.each_rigid_mobility(effects, body, w, c, sn, vbx, vby, om, nm_eff)
    vbx, vby, om = H.each_rigid_contact(effects, body, w, c, sn, any_c, vbx, vby, om, nm_eff)
    vx = c * vbx - sn * vby
    vy = sn * vbx + c * vby
    rate = contact_rate(s, body.nm, nm_eff, body.tip_m, c, sn, fx, fy, st) if any_c else 0.0
    return vx, vy, om, n_c, cx, cy, min_d, rate


@nb.njit(cache=True)
def _solve3(a, b0, b1, b2):
    """Solve the 3×3 system ``a`` x = b by Cramer's rule (``a`` well conditioned: I − γΔt J)."""
    c00 = a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]
    c01 = a[1, 2] * a[2, 0] - a[1, 0] * a[2, 2]
    c02 = a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]
    det = a[0, 0] * c00 + a[0, 1] * c01 + a[0, 2] * c02
    x0 = (b0 * c00 + b1 * (a[0, 2] * a[2, 1] - a[0, 1] * a[2, 2])
          + b2 * (a[0, 1] * a[1, 2] - a[0, 2] * a[1, 1])) / det  # fmt: skip
    x1 = (b0 * c01 + b1 * (a[0, 0] * a[2, 2] - a[0, 2] * a[2, 0])
          + b2 * (a[0, 2] * a[1, 0] - a[0, 0] * a[1, 2])) / det  # fmt: skip
    x2 = (b0 * c02 + b1 * (a[0, 1] * a[2, 0] - a[0, 0] * a[2, 1])
          + b2 * (a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0])) / det  # fmt: skip
    return x0, x1, x2


@nb.njit(cache=True)
def ros2_step(frame, flow, pillar, body, w, effects, xc, yc, th, vx, vy, om, dt, dth):
    """One linearly implicit Rosenbrock step (ROS2) of the rigid fiber.

    (I − γΔt J) k₁ = f(q),  (I − γΔt J) k₂ = f(q + Δt k₁) − 2k₁,
    q ← q + Δt (3k₁ + k₂)/2, with q = (xc, yc, th), f the lab-frame body
    velocity and J = ∂f/∂q by forward differences. Second order for any J; J only
    sets the stability, so the finite-difference error costs no accuracy.

    Parameters
    ----------
    frame, flow, pillar, body, w, effects : as :func:`rigid_velocity`
    xc, yc, th : float
        State [µm, µm, rad].
    vx, vy, om : float
        f(q), already evaluated [µm/s, rad/s].
    dt : float
        Step [s].
    dth : float
        Finite-difference step of the angle [rad] (``FD_STEP`` over the half-length).

    Returns
    -------
    (xc, yc, th) : the state after the step.
    """
    a = np.empty((3, 3))
    for j in range(3):
        h = dth if j == 2 else FD_STEP
        qx = xc + (h if j == 0 else 0.0)
        qy = yc + (h if j == 1 else 0.0)
        qt = th + (h if j == 2 else 0.0)
        fx, fy, fo, _, _, _, _, _ = rigid_velocity(
            frame, flow, pillar, body, w, effects, qx, qy, qt
        )
        g = GAMMA2 * dt / h
        a[0, j] = -g * (fx - vx)
        a[1, j] = -g * (fy - vy)
        a[2, j] = -g * (fo - om)
    for j in range(3):
        a[j, j] += 1.0
    k0, k1, k2 = _solve3(a, vx, vy, om)
    f0, f1, f2, _, _, _, _, _ = rigid_velocity(
        frame, flow, pillar, body, w, effects, xc + dt * k0, yc + dt * k1, th + dt * k2
    )
    m0, m1, m2 = _solve3(a, f0 - 2.0 * k0, f1 - 2.0 * k1, f2 - 2.0 * k2)
    return (xc + dt * (1.5 * k0 + 0.5 * m0), yc + dt * (1.5 * k1 + 0.5 * m1),
            th + dt * (1.5 * k2 + 0.5 * m2))  # fmt: skip


@nb.njit(cache=True)
def integrate_rigid(state, k, rec):
    """Advance a rigid fiber until a stop condition or until ``rec`` is full.

    Parameters
    ----------
    state : ndarray, shape (5,)
        [t, xc, yc, th, t_stopped_since] (updated in place; the last is NaN when
        the fiber is not in a stopped contact).
    k : bundles.Kernel
        The run's inputs (compiled once per set of active effects).
    rec : ndarray, shape (cap, record.NCOLS)
        One row per step, written from row 0.

    Returns
    -------
    (rows, code) : (int, int)
        Rows written and the stop code (record.CHUNK_FULL when ``rec`` filled up).
    """
    flow, pillar, body, p, w, _, effects, frame = k
    s = body.s
    n = s.shape[0]
    t = state[0]
    xc = state[1]
    yc = state[2]
    th = state[3]
    stopped_since = state[4]
    r_cut = pillar.r_cut
    half = 0.5 * (s[n - 1] - s[0])
    # finite-difference angle step (a one-bead fiber, a sphere in an array: no arm)
    dth = FD_STEP / max(half, FD_STEP)
    sh = s[n - 1]
    st_ = s[0]
    rows = 0
    code = np.int64(R.CHUNK_FULL)
    cap = rec.shape[0]
    # f at the current state, when an accepted implicit step has evaluated it already
    have_f = False
    shrink = 1.0  # implicit steps are shortened after a rejected one
    vx = vy = om = cx = cy = min_d = rate = 0.0
    n_c = np.int64(0)
    while rows < cap:
        if not have_f:
            vx, vy, om, n_c, cx, cy, min_d, rate = rigid_velocity(
                frame, flow, pillar, body, w, effects, xc, yc, th
            )
        have_f = False
        c = math.cos(th)
        sn = math.sin(th)
        hvx = vx - om * sh * sn
        hvy = vy + om * sh * c
        com_speed = math.sqrt(vx * vx + vy * vy)
        hx = xc + sh * c
        tx = xc + st_ * c
        R.write_row(
            rec[rows], t, xc, yc, th, vx, vy, om, float(n_c), cx, cy, min_d,
            math.sqrt(hvx * hvx + hvy * hvy), com_speed, hx, yc + sh * sn, tx, yc + st_ * sn,
        )  # fmt: skip
        rows += 1
        # Stop tests on the state just recorded.
        code, stopped_since = R.stop_test(
            p,
            t,
            math.isfinite(vx) and math.isfinite(vy) and math.isfinite(om),
            min_d,
            yc - half * abs(sn),
            yc + half * abs(sn),
            n_c > 0 and com_speed < p.trap_speed,
            stopped_since,
            min(hx, tx),
            0.0,
        )
        if code != R.CHUNK_FULL:
            break
        # Step size.
        speed = com_speed + abs(om) * half + 1e-12
        free = min_d - r_cut
        disp = min(p.max_disp, max(p.contact_disp, 0.5 * free))
        dt = min(disp / speed, p.dt_max)
        if p.mode == 1 and t + dt > p.t_stop:
            dt = max(p.t_stop - t, 1e-12)
        if p.stopped_implicit and math.isfinite(stopped_since):
            # land on the end of the trap time, not past it
            dti = max(min(dt * shrink, stopped_since + p.trap_time - t), 1e-12)
            xi, yi, ti = ros2_step(frame, flow, pillar, body, w, effects, xc, yc, th, vx, vy, om,
                                   dti, dth)  # fmt: skip
            fi = rigid_velocity(frame, flow, pillar, body, w, effects, xi, yi, ti)
            # Accepted only if the fiber is still stopped: leaving the stop (stick-slip
            # under friction, a slow slide off the pillar) is left to the explicit step.
            if fi[3] > 0 and math.sqrt(fi[0] * fi[0] + fi[1] * fi[1]) < p.trap_speed:
                vx, vy, om, n_c, cx, cy, min_d, rate = fi
                have_f = True
                xc = xi
                yc = yi
                th = ti
                t += dti
                shrink = min(1.0, 2.0 * shrink)
                continue
            # Rejected: shorter implicit steps next time; now an explicit step (which
            # needs only f(q), not the buffers in w).
            shrink *= 0.25
        if rate > 0.0:
            dt = min(dt, 0.5 / rate)
        # Midpoint step.
        xm = xc + 0.5 * dt * vx
        ym = yc + 0.5 * dt * vy
        thm = th + 0.5 * dt * om
        vx2, vy2, om2, _, _, _, _, _ = rigid_velocity(
            frame, flow, pillar, body, w, effects, xm, ym, thm
        )
        xc += dt * vx2
        yc += dt * vy2
        th += dt * om2
        xc, yc, th = H.each_rigid_noise(effects, body, dt, c, sn, xc, yc, th)
        t += dt
    state[0] = t
    state[1] = xc
    state[2] = yc
    state[3] = th
    state[4] = stopped_since
    return rows, code


def run_rigid(
    k, x0: float, y0: float, th0: float, beads0: np.ndarray | None = None
) -> tuple[np.ndarray, None, int]:
    """Integrate a rigid run from centre (x0, y0) [µm] and angle th0 [rad] (``beads0`` unused).

    Returns
    -------
    (rec, None, code)
        Record rows (record.COLS) and the stop code.
    """
    state = np.array([0.0, x0, y0, th0, math.nan])
    return R.collect(lambda rec, _: integrate_rigid(state, k, rec))  # type: ignore[return-value]
