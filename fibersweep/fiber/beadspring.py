"""The source's bead-spring fiber: stretching + bending springs, RPY mobility, BDF2 stepping.

Energy (docs/model.md), t_i = r_i − r_{i−1}:
    H = Σ_i (S/4a)(|t_i| − 2a)² + Σ_i (B/2a)(1 − t̂_{i+1}·t̂_i),
S = E π a², B = E π a⁴/4. Bead velocities U = u(r) + M(r) F(r). F also holds the
pillar contact and the repulsion of non-neighbouring beads (``fiber.self_exclusion``,
:mod:`fibersweep.fiber.exclusion`), so the chain cannot pass through itself.

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
from numba import literal_unroll

from fibersweep.fiber import frame as F
from fibersweep.fiber import hooks as H
from fibersweep.fiber import record as R
from fibersweep.fiber.bundles import DEFAULT_DT, Kernel
from fibersweep.fiber.elastic import elastic_forces, elastic_jacobian
from fibersweep.fiber.exclusion import exclusion_forces, exclusion_jacobian
from fibersweep.fiber.mobility import fiber_offsets, rpy_fill

__all__ = [
    "DEFAULT_DT",
    "bead_velocity",
    "force_jacobian",
    "force_jacobian_fd",
    "integrate_bead_spring",
    "run_bead_spring",
]

CHUNK = 20_000


@nb.njit(cache=True)
def bead_velocity(frame, flow, pillar, body, p, w, bw, effects):
    """f(q) = u + M F at the beads ``w.x, w.y`` into ``bw.f`` (2n); M into ``bw.mob``.

    Elastic forces, the self-exclusion of non-neighbouring beads
    (:mod:`fibersweep.fiber.exclusion`, off when ``p.excl_gap`` is 0), contact
    forces, the background flow, then the effects' stages:
    ``bead_forces`` (extra forces, e.g. friction) before the mobility is built,
    ``bead_mobility`` (e.g. pillar hydrodynamics: f = (I + M Z)⁻¹ u + M' F with
    mob holding M') after. Returns (any_contact, cx, cy).
    """
    x = w.x
    y = w.y
    u = w.u
    fx = w.fx
    fy = w.fy
    cfx = bw.cfx
    cfy = bw.cfy
    f = bw.f
    mob = bw.mob
    n = x.shape[0]
    F.velocity(frame, flow, x, y, u)
    elastic_forces(x, y, p.a, p.stretch, p.bend, fx, fy)
    exclusion_forces(x, y, p.excl_gap, p.excl_cut, p.excl_eq, p.excl_fref, fx, fy)
    n_c, cx, cy = F.contact(frame, pillar, x, y, cfx, cfy, w.st, w.dist)
    any_c = n_c > 0
    for i in range(n):
        fx[i] += cfx[i]
        fy[i] += cfy[i]
    for e in literal_unroll(effects):
        H.background(e, u)
    for i in range(n):
        f[2 * i] = u[i, 0]
        f[2 * i + 1] = u[i, 1]
    for e in literal_unroll(effects):
        H.bead_forces(e, body, w, bw, any_c)
    rpy_fill(x, y, p.a, p.mu, mob)
    for e in literal_unroll(effects):
        H.bead_mobility(e, w, bw)
    for r in range(2 * n):
        acc = 0.0
        for j in range(n):
            acc += mob[r, 2 * j] * fx[j] + mob[r, 2 * j + 1] * fy[j]
        f[r] += acc
    return any_c, cx, cy


@nb.njit(cache=True)
def _contact_jacobian(frame, pillar, h, w, bw):
    """Add the contact forces' 2x2 diagonal blocks to ``bw.jac`` by central differences.

    The contact force on a bead depends on that bead only; only beads with a
    non-zero contact stiffness ``w.st`` are differenced (step h [µm]).
    """
    x = w.x
    y = w.y
    jac = bw.jac
    one_x = np.empty(1)
    one_y = np.empty(1)
    c1 = np.empty(1)
    c2 = np.empty(1)
    c3 = np.empty(1)
    c4 = np.empty(1)
    d1 = np.empty(1)
    d2 = np.empty(1)
    for j in range(x.shape[0]):
        if w.st[j] <= 0.0:
            continue
        for comp in range(2):
            col = 2 * j + comp
            one_x[0] = x[j] + (h if comp == 0 else 0.0)
            one_y[0] = y[j] + (h if comp == 1 else 0.0)
            F.contact(frame, pillar, one_x, one_y, c1, c2, d1, d2)
            one_x[0] = x[j] - (h if comp == 0 else 0.0)
            one_y[0] = y[j] - (h if comp == 1 else 0.0)
            F.contact(frame, pillar, one_x, one_y, c3, c4, d1, d2)
            jac[2 * j, col] += (c1[0] - c3[0]) / (2.0 * h)
            jac[2 * j + 1, col] += (c2[0] - c4[0]) / (2.0 * h)


@nb.njit(cache=True)
def force_jacobian(frame, pillar, p, w, bw):
    """J = ∂F/∂q (2n, 2n) [pN/µm] of the elastic and contact forces at ``w.x, w.y`` into ``bw.jac``.

    The elastic part is analytic (:func:`~fibersweep.fiber.elastic.elastic_jacobian`,
    block pentadiagonal), and so is the self-exclusion's
    (:func:`~fibersweep.fiber.exclusion.exclusion_jacobian`: blocks anywhere, J is
    used dense); the contact part, a 2x2 block per bead in contact
    (``w.st`` > 0, as left by the last :func:`bead_velocity`), by central
    differences with step 1e-6 a. Used by ``bead-spring-ros2``;
    :func:`force_jacobian_fd` is the all-differences version of the fixed-step model.
    """
    jac = bw.jac
    n2 = jac.shape[0]
    for i in range(n2):
        for j in range(n2):
            jac[i, j] = 0.0
    elastic_jacobian(w.x, w.y, p.a, p.stretch, p.bend, jac)
    exclusion_jacobian(w.x, w.y, p.excl_gap, p.excl_cut, p.excl_eq, p.excl_fref, jac)
    _contact_jacobian(frame, pillar, 1e-6 * p.a, w, bw)


@nb.njit(cache=True)
def force_jacobian_fd(frame, pillar, p, w, bw):
    """J = ∂F/∂q (2n, 2n) [pN/µm] into ``bw.jac`` by central differences, banded.

    Elastic forces couple a bead to its two neighbours on each side; the contact
    force on a bead depends on that bead only (a 2x2 diagonal block, computed
    only for beads with a non-zero contact stiffness ``w.st``). Uses
    ``bw.gx, gy, cfx, cfy`` as scratch. The fixed-step model's Jacobian (kept, so
    that its results stay those of the reference); see :func:`force_jacobian`.
    The self-exclusion's blocks are added analytically
    (:func:`~fibersweep.fiber.exclusion.exclusion_jacobian`).

    Returns
    -------
    bool
        Whether J has blocks outside the pentadiagonal band (an active
        self-exclusion pair |i − j| > 2): then W = M J must be taken dense.
    """
    x = w.x
    y = w.y
    jac = bw.jac
    fx = bw.gx
    fy = bw.gy
    gx = bw.cfx
    gy = bw.cfy
    st = w.st
    n = x.shape[0]
    a = p.a
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
            elastic_forces(x, y, a, p.stretch, p.bend, fx, fy)
            if comp == 0:
                x[j] -= 2.0 * h
            else:
                y[j] -= 2.0 * h
            elastic_forces(x, y, a, p.stretch, p.bend, gx, gy)
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
                F.contact(frame, pillar, one_x, one_y, c1, c2, d1, d2)
                one_x[0] = x[j] - (h if comp == 0 else 0.0)
                one_y[0] = y[j] - (h if comp == 1 else 0.0)
                F.contact(frame, pillar, one_x, one_y, c3, c4, d1, d2)
                jac[2 * j, col] += (c1[0] - c3[0]) / (2.0 * h)
                jac[2 * j + 1, col] += (c2[0] - c4[0]) / (2.0 * h)
    return exclusion_jacobian(x, y, p.excl_gap, p.excl_cut, p.excl_eq, p.excl_fref, jac)


@nb.njit(cache=True)
def integrate_bead_spring(q, qprev, state, k, stride, rec, brec):
    """Advance a bead-spring fiber with fixed Δt until a stop condition or ``rec`` is full.

    Parameters
    ----------
    q, qprev : ndarray, shape (2n,)
        Positions at the current and previous step (x0, y0, x1, ...) [µm]; updated.
    state : ndarray, shape (5,)
        [t, stopped_since, have_prev (0/1), theta (unwrapped) [rad], step] (updated).
    k : bundles.Kernel
        The run's inputs (compiled once per set of active effects); Δt is ``k.params.dt``.
    stride : int
        Record every ``stride`` steps, and at every change of the contact flag.
    rec : ndarray, shape (cap, record.NCOLS)
    brec : ndarray, shape (cap, n, 2)
        Bead positions of each recorded row.

    Returns
    -------
    (rows, code)
    """
    flow, pillar, body, p, w, bw, effects, frame = k
    n2 = q.shape[0]
    n = n2 // 2
    dt = p.dt
    x = w.x
    y = w.y
    dist = w.dist
    f = bw.f
    lhs = bw.lhs
    rhs = bw.rhs
    qs = bw.qs
    v = bw.v
    mob = bw.mob
    jac = bw.jac
    t = state[0]
    stopped_since = state[1]
    have_prev = state[2] > 0.5
    theta = state[3]
    step = int(state[4])
    cap = rec.shape[0]
    rows = 0
    code = np.int64(R.CHUNK_FULL)
    last_contact = -1.0
    last_stopped = -1.0
    for k2 in range(n2):
        v[k2] = (q[k2] - qprev[k2]) / dt if have_prev else 0.0
    while rows < cap:
        # Extrapolated state (BDF2) or the current one (first step: backward Euler).
        for k2 in range(n2):
            qs[k2] = 2.0 * q[k2] - qprev[k2] if have_prev else q[k2]
        for i in range(n):
            x[i] = qs[2 * i]
            y[i] = qs[2 * i + 1]
        any_c, cx, cy = bead_velocity(frame, flow, pillar, body, p, w, bw, effects)
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
        stopped = any_c and com_speed < p.trap_speed and have_prev
        finite = True
        for k2 in range(n2):
            if not math.isfinite(q[k2]):
                finite = False
        y_min = 1e300
        y_max = -1e300
        for i in range(n):
            y_min = min(y_min, q[2 * i + 1])
            y_max = max(y_max, q[2 * i + 1])
        code, stopped_since = R.stop_test(
            p, t, finite, min_d, y_min, y_max, stopped, stopped_since, min(hx, tx), 0.5 * dt
        )
        # Record every `stride` steps, at every change of the contact or stopped flag,
        # and the final state, so that classify() on the record sees what the kernel saw.
        sflag = 1.0 if stopped else 0.0
        if (
            step % stride == 0
            or cflag != last_contact
            or sflag != last_stopped
            or code != R.CHUNK_FULL
        ):
            ex = hx - tx
            ey = hy - ty
            om = (ex * (v[2 * n - 1] - v[1]) - ey * (v[2 * n - 2] - v[0])) / (ex * ex + ey * ey)
            R.write_row(
                rec[rows], t, xc, yc, theta, vxc, vyc, om, cflag, cx, cy, min_d,
                math.hypot(v[2 * n - 2], v[2 * n - 1]), com_speed, hx, hy, tx, ty,
            )  # fmt: skip
            for i in range(n):
                brec[rows, i, 0] = q[2 * i]
                brec[rows, i, 1] = q[2 * i + 1]
            rows += 1
        last_contact = cflag
        last_stopped = sflag
        if code != R.CHUNK_FULL:
            break
        # Linearly implicit step.
        dense = force_jacobian_fd(frame, pillar, p, w, bw)
        c = 2.0 * dt / 3.0 if have_prev else dt
        for i2 in range(n2):
            for j2 in range(n2):
                acc = 0.0
                # J is banded: bead j couples to beads j-2..j+2 only, unless a
                # self-exclusion pair couples distant beads (then all of J's column).
                lo = 0 if dense else max(0, 2 * (j2 // 2) - 4)
                hi = n2 if dense else min(n2, 2 * (j2 // 2) + 6)
                for k2 in range(lo, hi):
                    acc += mob[i2, k2] * jac[k2, j2]
                lhs[i2, j2] = -c * acc
            lhs[i2, i2] += 1.0
            if have_prev:
                rhs[i2] = c * (f[i2] - (q[i2] - qprev[i2]) / dt)
            else:
                rhs[i2] = c * f[i2]
        delta = np.linalg.solve(lhs, rhs)
        for k2 in range(n2):
            qnew = qs[k2] + delta[k2]
            if have_prev:
                v[k2] = (3.0 * qnew - 4.0 * q[k2] + qprev[k2]) / (2.0 * dt)
            else:
                v[k2] = (qnew - q[k2]) / dt
            qprev[k2] = q[k2]
            q[k2] = qnew
        have_prev = True
        t += dt
        step += 1
    state[0] = t
    state[1] = stopped_since
    state[2] = 1.0 if have_prev else 0.0
    state[3] = theta
    state[4] = step
    return rows, code


def run_bead_spring(
    k: Kernel, x0: float, y0: float, th0: float, beads0: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, int]:
    """Integrate a bead-spring run (see :func:`fibersweep.fiber.run.simulate`).

    The default Δt = DEFAULT_DT (5e-5 s) keeps class and δ within the
    tolerances of Δt = 1e-7 s (checked in tests/validation/test_fiber_beadspring.py).

    Returns
    -------
    (rec, beads, code)
        Record rows (record.COLS), bead positions (rows, n, 2) [µm], stop code.
    """
    n = k.body.s.shape[0]
    dt = k.params.dt
    # About one record row per 1e-4 s (and at every contact change).
    stride = max(1, int(round(1e-4 / dt)))
    if beads0 is None:
        s = fiber_offsets(n, k.params.a)
        beads0 = np.column_stack([x0 + s * math.cos(th0), y0 + s * math.sin(th0)])
    q = np.ascontiguousarray(beads0, dtype=np.float64).reshape(-1).copy()
    qprev = q.copy()
    state = np.array([0.0, math.nan, 0.0, th0, 0.0])
    recs, brecs = [], []
    while True:
        rec = np.empty((CHUNK, R.NCOLS))
        brec = np.empty((CHUNK, n, 2))
        rows, code = integrate_bead_spring(q, qprev, state, k, stride, rec, brec)
        recs.append(rec[:rows])
        brecs.append(brec[:rows])
        if code != R.CHUNK_FULL:
            return np.concatenate(recs), np.concatenate(brecs), code
