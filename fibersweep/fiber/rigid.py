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
from numba import literal_unroll

from fibersweep.fiber import hooks as H
from fibersweep.fiber import record as R
from fibersweep.fiber.contact import pillar_forces
from fibersweep.fiber.mobility import body_velocity
from fibersweep.flow.field import interpolate_ib

__all__ = ["CHUNK", "integrate_rigid", "rigid_velocity", "run_rigid", "seed_numba"]

CHUNK = 20_000  # record rows per kernel call


@nb.njit(cache=True)
def seed_numba(seed: int) -> None:
    """Seed Numba's own random generator (used for Brownian increments)."""
    np.random.seed(seed)  # noqa: NPY002 - Numba has its own per-thread RNG


@nb.njit(cache=True)
def rigid_velocity(flow, pillar, body, w, effects, xc, yc, th):
    """Lab-frame body velocity of a rigid fiber at (xc, yc, th).

    Parameters
    ----------
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
    (vx, vy, om, any_contact, cx, cy, min_dist, stiff_sum)
        Velocity [µm/s, rad/s], contact flag and point [µm], smallest distance to
        the pillar [µm], summed contact stiffness [pN/µm].
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
    interpolate_ib(flow.ux, flow.uy, flow.dx, x, y, u)
    any_c, cx, cy = pillar_forces(pillar, x, y, fx, fy, st, dist)
    for e in literal_unroll(effects):
        H.background(e, u)
    min_d = 1e300
    stiff = 0.0
    for i in range(n):
        if dist[i] < min_d:
            min_d = dist[i]
        stiff += st[i]
    ub = u.reshape(2 * n)
    vbx, vby, om = body_velocity(c, sn, s, body.pm, body.nm, ub, fx, fy, any_c)
    nm_eff = body.nm
    for e in literal_unroll(effects):
        vbx, vby, om, nm_eff = H.rigid_mobility(e, body, w, vbx, vby, om, nm_eff)
    for e in literal_unroll(effects):
        vbx, vby, om = H.rigid_contact(e, body, w, c, sn, any_c, vbx, vby, om, nm_eff)
    vx = c * vbx - sn * vby
    vy = sn * vbx + c * vby
    return vx, vy, om, any_c, cx, cy, min_d, stiff


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
    flow, pillar, body, p, w, _, effects = k
    s = body.s
    n = s.shape[0]
    t = state[0]
    xc = state[1]
    yc = state[2]
    th = state[3]
    stopped_since = state[4]
    r_cut = pillar.r_cut
    tip_m = body.tip_m
    half = 0.5 * (s[n - 1] - s[0])
    sh = s[n - 1]
    st_ = s[0]
    rows = 0
    code = np.int64(R.CHUNK_FULL)
    cap = rec.shape[0]
    while rows < cap:
        vx, vy, om, any_c, cx, cy, min_d, stiff = rigid_velocity(
            flow, pillar, body, w, effects, xc, yc, th
        )
        c = math.cos(th)
        sn = math.sin(th)
        hvx = vx - om * sh * sn
        hvy = vy + om * sh * c
        com_speed = math.sqrt(vx * vx + vy * vy)
        hx = xc + sh * c
        tx = xc + st_ * c
        R.write_row(
            rec[rows], t, xc, yc, th, vx, vy, om, 1.0 if any_c else 0.0, cx, cy, min_d,
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
            any_c and com_speed < p.trap_speed,
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
        if stiff > 0.0:
            dt = min(dt, 0.5 / (tip_m * stiff))
        if p.mode == 1 and t + dt > p.t_stop:
            dt = max(p.t_stop - t, 1e-12)
        # Midpoint step.
        xm = xc + 0.5 * dt * vx
        ym = yc + 0.5 * dt * vy
        thm = th + 0.5 * dt * om
        vx2, vy2, om2, _, _, _, _, _ = rigid_velocity(flow, pillar, body, w, effects, xm, ym, thm)
        xc += dt * vx2
        yc += dt * vy2
        th += dt * om2
        for e in literal_unroll(effects):
            xc, yc, th = H.rigid_noise(e, body, dt, c, sn, xc, yc, th)
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
    chunks = []
    while True:
        rec = np.empty((CHUNK, R.NCOLS))
        rows, code = integrate_rigid(state, k, rec)
        chunks.append(rec[:rows])
        if code != R.CHUNK_FULL:
            return np.concatenate(chunks), None, code
