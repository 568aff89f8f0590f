"""Adaptive linearly implicit (ROS2) stepping of the bead-spring fiber (docs/flexible.md).

Same model as :mod:`fibersweep.fiber.beadspring` (stretching + bending springs,
RPY mobility, pillar contact, the effects' stages), other time stepping. With
f(q) = u(q) + M(q) F(q) the bead velocities (2n) and W = M J, J = ∂F/∂q the
banded Jacobian of the elastic and contact forces (the mobility and the flow
are lagged: their derivatives are left out of W), one step of length h is the
two-stage Rosenbrock-W method ROS2 (Verwer et al. 1999), γ = 1 + 1/√2:

    (I − γ h W) k1 = f(q),
    (I − γ h W) k2 = f(q + h k1) − 2 k1,
    q' = q + (3/2) h k1 + (1/2) h k2.

ROS2 is second order for any W (a W-method), so lagging the mobility costs no
order, and it is L-stable, so the spring times (~1e-7 s) do not bound h. The
difference to the embedded first-order solution q + h k1, e = h |k1 + k2| / 2
(largest over the beads [µm]), controls h: a step is accepted when
e <= ``Params.tol`` and the next h is h · min(2, max(0.2, 0.9 √(tol / e))).
The displacement of a bead per step is also kept below ``Params.max_disp``
and, approaching the pillar, below half the gap to the contact cutoff (so that
the step does not jump into contact), but not below ``Params.contact_disp``.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fibersweep.fiber import record as R
from fibersweep.fiber.beadspring import _jacobian, bead_velocity
from fibersweep.fiber.bundles import Kernel
from fibersweep.fiber.mobility import fiber_offsets

__all__ = ["GAMMA", "integrate_ros2", "run_bead_spring_ros2"]

GAMMA = 1.0 + 1.0 / math.sqrt(2.0)
CHUNK = 20_000


@nb.njit(cache=True)
def _velocity(frame, flow, pillar, body, p, w, bw, effects, q, fext, has_ext, out):
    """f(q) (+ M fext if ``has_ext``) into ``out`` (2n); returns (any_contact, cx, cy, min_d)."""
    n = q.shape[0] // 2
    for i in range(n):
        w.x[i] = q[2 * i]
        w.y[i] = q[2 * i + 1]
    any_c, cx, cy = bead_velocity(frame, flow, pillar, body, p, w, bw, effects)
    for r in range(2 * n):
        out[r] = bw.f[r]
    if has_ext:
        for r in range(2 * n):
            acc = 0.0
            for c in range(2 * n):
                acc += bw.mob[r, c] * fext[c]
            out[r] += acc
    min_d = 1e300
    for i in range(n):
        min_d = min(min_d, w.dist[i])
    return any_c, cx, cy, min_d


@nb.njit(cache=True)
def _system(p, bw, h):
    """``bw.lhs`` = I − γ h M J (mobility and Jacobian as left in ``bw``)."""
    mob = bw.mob
    jac = bw.jac
    lhs = bw.lhs
    n2 = lhs.shape[0]
    c = GAMMA * h
    for i2 in range(n2):
        for j2 in range(n2):
            acc = 0.0
            # J is banded: bead j couples to beads j-2..j+2 only.
            for k2 in range(max(0, 2 * (j2 // 2) - 4), min(n2, 2 * (j2 // 2) + 6)):
                acc += mob[i2, k2] * jac[k2, j2]
            lhs[i2, j2] = -c * acc
        lhs[i2, i2] += 1.0


@nb.njit(cache=True)
def integrate_ros2(q, state, k, rec, brec, f0, k1, k2, qn, fext):
    """Advance a bead-spring fiber with adaptive ROS2 steps until a stop or ``rec`` is full.

    Parameters
    ----------
    q : ndarray, shape (2n,)
        Bead positions (x0, y0, x1, ...) [µm]; updated.
    state : ndarray, shape (4,)
        [t [s], stopped_since [s] (NaN), theta (unwrapped) [rad], next step h [s]]; updated.
    k : bundles.Kernel
    rec : ndarray, shape (cap, record.NCOLS)
        One row per accepted step, from row 0.
    brec : ndarray, shape (cap, n, 2)
        Bead positions of each row [µm].
    f0, k1, k2, qn : ndarray, shape (2n,)
        Scratch.
    fext : ndarray, shape (2n,)
        External forces on the beads [pN], constant (zeros in the sweep's runs; the
        beam-deflection validation loads the fiber with them).

    Returns
    -------
    (rows, code)
    """
    flow, pillar, body, p, w, bw, effects, frame = k
    n2 = q.shape[0]
    n = n2 // 2
    t = state[0]
    stopped_since = state[1]
    theta = state[2]
    h = state[3]
    r_cut = pillar.r_cut
    has_ext = False
    for r in range(n2):
        if fext[r] != 0.0:
            has_ext = True
    cap = rec.shape[0]
    rows = 0
    code = np.int64(R.CHUNK_FULL)
    while rows < cap:
        any_c, cx, cy, min_d = _velocity(
            frame, flow, pillar, body, p, w, bw, effects, q, fext, has_ext, f0
        )
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
        y_min = 1e300
        y_max = -1e300
        finite = True
        vmax = 0.0
        for i in range(n):
            xc += q[2 * i] / n
            yc += q[2 * i + 1] / n
            vxc += f0[2 * i] / n
            vyc += f0[2 * i + 1] / n
            y_min = min(y_min, q[2 * i + 1])
            y_max = max(y_max, q[2 * i + 1])
            vmax = max(vmax, math.hypot(f0[2 * i], f0[2 * i + 1]))
            if not (math.isfinite(q[2 * i]) and math.isfinite(q[2 * i + 1])):
                finite = False
            if not (math.isfinite(f0[2 * i]) and math.isfinite(f0[2 * i + 1])):
                finite = False
        com_speed = math.hypot(vxc, vyc)
        ex = hx - tx
        ey = hy - ty
        om = (ex * (f0[2 * n - 1] - f0[1]) - ey * (f0[2 * n - 2] - f0[0])) / (ex * ex + ey * ey)
        R.write_row(
            rec[rows], t, xc, yc, theta, vxc, vyc, om, 1.0 if any_c else 0.0, cx, cy, min_d,
            math.hypot(f0[2 * n - 2], f0[2 * n - 1]), com_speed, hx, hy, tx, ty,
        )  # fmt: skip
        for i in range(n):
            brec[rows, i, 0] = q[2 * i]
            brec[rows, i, 1] = q[2 * i + 1]
        rows += 1
        code, stopped_since = R.stop_test(
            p, t, finite, min_d, y_min, y_max, any_c and com_speed < p.trap_speed,
            stopped_since, min(hx, tx), 0.0,
        )  # fmt: skip
        if code != R.CHUNK_FULL:
            break
        # Step bounds: displacement far from / approaching the pillar, largest step.
        free = min_d - r_cut
        disp = min(p.max_disp, max(p.contact_disp, 0.5 * free))
        h_cap = min(disp / (vmax + 1e-12), p.dt_max)
        # W = M(q) J(q): the top of the loop left M(q) in bw.mob and the contact
        # stiffness of q in w.st; f at the stage point overwrites bw.mob, so keep M(q).
        _jacobian(frame, pillar, p, w, bw)
        mob0 = bw.mob.copy()
        while True:
            h = min(h, h_cap)
            if p.mode == 1 and t + h > p.t_stop:
                h = max(p.t_stop - t, 1e-15)
            bw.mob[:, :] = mob0
            _system(p, bw, h)
            lhs = bw.lhs.copy()
            s1 = np.linalg.solve(lhs, f0)
            for r in range(n2):
                k1[r] = s1[r]
                qn[r] = q[r] + h * k1[r]
            _velocity(frame, flow, pillar, body, p, w, bw, effects, qn, fext, has_ext, k2)
            for r in range(n2):
                k2[r] -= 2.0 * k1[r]
            s2 = np.linalg.solve(lhs, k2)
            err = 0.0
            for i in range(n):
                ex_ = 0.5 * h * (k1[2 * i] + s2[2 * i])
                ey_ = 0.5 * h * (k1[2 * i + 1] + s2[2 * i + 1])
                err = max(err, math.hypot(ex_, ey_))
            if not math.isfinite(err):
                err = 1e300
            fac = 0.9 * math.sqrt(p.tol / max(err, 1e-300))
            fac = min(2.0, max(0.2, fac))
            if err <= p.tol or h <= 1e-12:
                for r in range(n2):
                    q[r] = q[r] + 1.5 * h * k1[r] + 0.5 * h * s2[r]
                t += h
                h = h * fac
                break
            h = h * fac
    state[0] = t
    state[1] = stopped_since
    state[2] = theta
    state[3] = h
    return rows, code


def run_bead_spring_ros2(
    k: Kernel, x0: float, y0: float, th0: float, beads0: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, int]:
    """Integrate a bead-spring run with adaptive ROS2 steps (see :func:`integrate_ros2`).

    Returns
    -------
    (rec, beads, code)
        Record rows (record.COLS), bead positions (rows, n, 2) [µm], stop code.
    """
    n = k.body.s.shape[0]
    if beads0 is None:
        s = fiber_offsets(n, k.params.a)
        beads0 = np.column_stack([x0 + s * math.cos(th0), y0 + s * math.sin(th0)])
    q = np.ascontiguousarray(beads0, dtype=np.float64).reshape(-1).copy()
    h0 = min(1e-5, k.params.dt_max)
    state = np.array([0.0, math.nan, th0, h0])
    scratch = [np.zeros(2 * n) for _ in range(5)]
    recs, brecs = [], []
    while True:
        rec = np.empty((CHUNK, R.NCOLS))
        brec = np.empty((CHUNK, n, 2))
        rows, code = integrate_ros2(q, state, k, rec, brec, *scratch)
        recs.append(rec[:rows])
        brecs.append(brec[:rows])
        if code != R.CHUNK_FULL:
            return np.concatenate(recs), np.concatenate(brecs), code
