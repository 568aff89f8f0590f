"""Fixed-step BDF2 stepping of the bead-spring fiber: the source's method, the reference.

Linearly implicit second-order BDF on the positions q (2n) of the model
f(q) = u + M F (:mod:`fibersweep.fiber.models.beadspring`), with extrapolation
q* = 2 q^k − q^{k−1}, frozen mobility M* = M(q*) and the Jacobian J = ∂F/∂q of
the elastic and contact forces (:func:`~fibersweep.fiber.models.beadspring.force_jacobian_fd`):

    (I − (2Δt/3) M* J) δ = (2Δt/3) [f(q*) − (q^k − q^{k−1})/Δt],  q^{k+1} = q* + δ.

The first step is the linearly implicit backward Euler. With the stiff modes
implicit, Δt (``fiber.step.dt``, default :data:`~fibersweep.fiber.kernel.bundles.DEFAULT_DT`)
is bounded by accuracy, not by the 1e-7 s spring times.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fibersweep.fiber.kernel import record as R
from fibersweep.fiber.kernel.bundles import Kernel
from fibersweep.fiber.models.beadspring import chain, force_jacobian_fd, velocity_at

__all__ = ["integrate_bdf2", "run_bdf2"]


@nb.njit(cache=True)
def integrate_bdf2(q, qprev, state, k, stride, rec, brec):
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
    dt = p.dt
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
        any_c, cx, cy, min_d = velocity_at(frame, flow, pillar, body, p, w, bw, effects, qs)
        # The current state q (time t) with the velocity estimate v.
        pose = R.bead_pose(q, v, theta)
        theta, _, _, _, _, com_speed, hx, _, tx, _, y_min, y_max, finite, _ = pose
        cflag = 1.0 if any_c else 0.0
        stopped = any_c and com_speed < p.trap_speed and have_prev
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
            R.write_bead_row(rec[rows], brec[rows], t, q, v, pose, cflag, cx, cy, min_d)
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
        delta = np.linalg.solve(lhs, rhs)  # LAPACK: the reference's solve (lu rounds otherwise)
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


def run_bdf2(
    k: Kernel, x0: float, y0: float, th0: float, beads0: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, int]:
    """Integrate a bead-spring run with BDF2 (see :func:`fibersweep.fiber.run.simulate`).

    The default Δt = DEFAULT_DT (5e-5 s) keeps class and δ within the
    tolerances of Δt = 1e-7 s (checked in tests/validation/test_fiber_beadspring.py).

    Returns
    -------
    (rec, beads, code)
        Record rows (record.COLS), bead positions (rows, n, 2) [µm], stop code.
    """
    n = k.body.s.shape[0]
    # About one record row per 1e-4 s (and at every contact change).
    stride = max(1, int(round(1e-4 / k.params.dt)))
    q = chain(n, k.params.half_b, x0, y0, th0, beads0)
    qprev = q.copy()
    state = np.array([0.0, math.nan, 0.0, th0, 0.0])
    return R.collect(  # type: ignore[return-value]
        lambda rec, brec: integrate_bdf2(q, qprev, state, k, stride, rec, brec), n
    )
