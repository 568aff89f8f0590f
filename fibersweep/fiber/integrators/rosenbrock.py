"""Adaptive linearly implicit (Rosenbrock-W) stepping of the bead-spring fiber (docs/flexible.md).

The model is :mod:`fibersweep.fiber.models.beadspring`: f(q) = u(q) + M(q) F(q) the
bead velocities (2n), and W = M J with J = ∂F/∂q the Jacobian of the elastic,
self-exclusion and contact forces (the mobility and the flow are lagged: their
derivatives are left out of W). ``fiber.integrator`` picks the method
(``Params.rosw``); both are W-methods, whose order holds for any W, so lagging
the mobility costs no order, and L-stable, so the spring times (~1e-7 s) do not
bound the step h:

- ``ros2`` (Verwer et al. 1999), two stages, order 2, γ = 1 + 1/√2:

      (I − γ h W) k1 = f(q),
      (I − γ h W) k2 = f(q + h k1) − 2 k1,
      q' = q + (3/2) h k1 + (1/2) h k2,

  error estimate e = h |k1 + k2| / 2 (against the first-order q + h k1);
- ``ros34pw2``, four stages, order 3 (embedded order 2), in the transformed
  form of :mod:`fibersweep.fiber.integrators.rosw`.

Everything else is shared by :func:`integrate_rosenbrock`: the record row and
stop test, W = M J and one LU factorisation of I − γhW per try
(:func:`system`, :mod:`fibersweep.fiber.integrators.lu`) whose factors serve every stage,
and the step control. The error e is the largest over the beads [µm]; a step is
accepted when e <= ``Params.tol`` and the next h is
h · min(2, max(0.2, 0.9 (tol / e)^(1/p))), p = 2 (ros2) or 3 (ros34pw2). The
displacement of a bead per step is also kept below ``Params.max_disp`` and,
approaching the pillar, below half the gap to the contact cutoff (so that the
step does not jump into contact), but not below ``Params.contact_disp``.

Cost of a ROS2 step (scripts/benchmarks/profile_flexible.py): two evaluations of f (each
rebuilds the RPY mobility), the analytic Jacobian
(:func:`~fibersweep.fiber.models.beadspring.force_jacobian`), W = M J by one BLAS
product, and the one LU; a rejected step redoes the LU and the stage
evaluations only. The mobility is lagged in W only: f itself always uses M at
its own argument.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fibersweep.fiber.integrators.lu import lu_factor, lu_solve
from fibersweep.fiber.integrators.rosw import (
    A34,
    C34,
    E34,
    GAMMA2,
    GAMMA3,
    M34,
    ROS34PW2_CODE,
    combine,
    stage_point,
    stage_rhs,
)
from fibersweep.fiber.kernel import record as R
from fibersweep.fiber.kernel.bundles import Kernel
from fibersweep.fiber.models.beadspring import chain, force_jacobian, velocity_at

__all__ = [
    "integrate_rosenbrock",
    "run_rosenbrock",
    "system",
    "w_matrix",
]

KEEP_H = 1.2
"""With a reused W, a proposed step up to this factor above the factored one keeps it."""


@nb.njit(cache=True)
def _velocity(frame, flow, pillar, body, p, w, bw, effects, q, fext, has_ext, out):
    """f(q) (+ M fext if ``has_ext``) into ``out`` (2n); returns (any_contact, cx, cy, min_d)."""
    any_c, cx, cy, min_d = velocity_at(frame, flow, pillar, body, p, w, bw, effects, q)
    n2 = q.shape[0]
    for r in range(n2):
        out[r] = bw.f[r]
    if has_ext:
        for r in range(n2):
            acc = 0.0
            for c in range(n2):
                acc += bw.mob[r, c] * fext[c]
            out[r] += acc
    return any_c, cx, cy, min_d


@nb.njit(cache=True)
def w_matrix(bw):
    """W = M J into ``bw.jac`` (2n, 2n), from the mobility ``bw.mob`` and Jacobian ``bw.jac``.

    A dense BLAS product (``bw.lhs`` is scratch): at 2n ≈ 44 it is ~5 times faster
    than a loop over J's band (scripts/benchmarks/profile_flexible.py).
    """
    np.dot(bw.mob, bw.jac, bw.lhs)
    bw.jac[:, :] = bw.lhs


@nb.njit(cache=True)
def system(bw, h, piv, gamma):
    """``bw.lhs`` = LU factors of I − γ h W (W in ``bw.jac``, see :func:`w_matrix`).

    ``gamma``: the method's γ (:data:`~fibersweep.fiber.integrators.rosw.GAMMA2` for ROS2,
    :data:`~fibersweep.fiber.integrators.rosw.GAMMA3` for ROS34PW2).
    Returns False when the matrix is singular.
    """
    w = bw.jac
    lhs = bw.lhs
    n2 = lhs.shape[0]
    c = gamma * h
    for i2 in range(n2):
        for j2 in range(n2):
            lhs[i2, j2] = -c * w[i2, j2]
        lhs[i2, i2] += 1.0
    return lu_factor(lhs, piv)


@nb.njit(cache=True)
def _bead_max(h, v):
    """Largest |h v_i| over the beads of v (2n) [µm]."""
    err = 0.0
    for i in range(v.shape[0] // 2):
        err = max(err, math.hypot(h * v[2 * i], h * v[2 * i + 1]))
    return err


@nb.njit(cache=True)
def _try_ros2(k, q, f0, fext, has_ext, h, piv, ok, k1, k2, qn, qnew):
    """One ROS2 try from q with the factors of I − γhW in ``bw.lhs``.

    Writes the new positions into ``qnew``; returns the error estimate [µm].
    """
    flow, pillar, body, p, w, bw, effects, frame = k
    n2 = q.shape[0]
    n = n2 // 2
    for r in range(n2):
        k1[r] = f0[r]
    if ok:
        lu_solve(bw.lhs, piv, k1)
        for r in range(n2):
            qn[r] = q[r] + h * k1[r]
        _velocity(frame, flow, pillar, body, p, w, bw, effects, qn, fext, has_ext, k2)
        for r in range(n2):
            k2[r] -= 2.0 * k1[r]
        lu_solve(bw.lhs, piv, k2)
    else:
        for r in range(n2):
            k2[r] = 0.0
    err = 0.0
    for i in range(n):
        ex_ = 0.5 * h * (k1[2 * i] + k2[2 * i])
        ey_ = 0.5 * h * (k1[2 * i + 1] + k2[2 * i + 1])
        err = max(err, math.hypot(ex_, ey_))
    for r in range(n2):
        qnew[r] = q[r] + 1.5 * h * k1[r] + 0.5 * h * k2[r]
    return err


@nb.njit(cache=True)
def _try_ros34pw2(k, q, f0, fext, has_ext, h, piv, ok, xs, qn, qnew):
    """One ROS34PW2 try (:mod:`fibersweep.fiber.integrators.rosw`), four stages on one LU.

    ``xs`` (4, 2n) receives the transformed stages. Writes the new positions into
    ``qnew``; returns the error estimate h |Σ e_j x_j| (largest over the beads) [µm].
    """
    flow, pillar, body, p, w, bw, effects, frame = k
    n2 = q.shape[0]
    if not ok:
        return 1e300
    for r in range(n2):
        xs[0, r] = f0[r]
    lu_solve(bw.lhs, piv, xs[0])
    for i in range(1, 4):
        stage_point(q, h, A34, xs, i, qn)
        _velocity(frame, flow, pillar, body, p, w, bw, effects, qn, fext, has_ext, xs[i])
        stage_rhs(C34, xs, i, xs[i])
        lu_solve(bw.lhs, piv, xs[i])
    combine(q, h, M34, xs, qnew)
    for r in range(n2):
        qn[r] = 0.0
    combine(qn, 1.0, E34, xs, qn)
    return _bead_max(h, qn)


@nb.njit(cache=True)
def integrate_rosenbrock(q, state, k, rec, brec, f0, k1, k2, qn, fext):
    """Advance a bead-spring fiber with adaptive Rosenbrock-W steps until a stop or ``rec`` is full.

    The method is ``k.params.rosw`` (:data:`fibersweep.fiber.integrators.rosw.METHODS`): ROS2 or
    ROS34PW2 (module docstring); only their stages differ (:func:`_try_ros2`,
    :func:`_try_ros34pw2`).

    Parameters
    ----------
    q : ndarray, shape (2n,)
        Bead positions (x0, y0, x1, ...) [µm]; updated.
    state : ndarray, shape (5,)
        [t [s], stopped_since [s] (NaN), theta (unwrapped) [rad], next step h [s],
        rejected steps so far]; updated.
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
    rejected = state[4]
    piv = np.empty(n2, dtype=np.int64)
    third = p.rosw == ROS34PW2_CODE
    gamma = GAMMA3 if third else GAMMA2
    xs = np.empty((4 if third else 0, n2))
    qnew = np.empty(n2)
    r_cut = pillar.r_cut
    has_ext = False
    for r in range(n2):
        if fext[r] != 0.0:
            has_ext = True
    cap = rec.shape[0]
    order = 3.0 if third else 2.0
    w_age = p.w_reuse  # no W yet: build one at the first step
    w_sig = -1
    w_nc = -1
    h_lu = 0.0
    err_prev = p.tol
    last_rejected = False
    rows = 0
    code = np.int64(R.CHUNK_FULL)
    while rows < cap:
        any_c, cx, cy, min_d = _velocity(
            frame, flow, pillar, body, p, w, bw, effects, q, fext, has_ext, f0
        )
        pose = R.bead_pose(q, f0, theta)
        theta, _, _, _, _, com_speed, hx, _, tx, _, y_min, y_max, fin_q, fin_v = pose
        R.write_bead_row(rec[rows], brec[rows], t, q, f0, pose, 1.0 if any_c else 0.0, cx, cy,
                         min_d)  # fmt: skip
        rows += 1
        code, stopped_since = R.stop_test(
            p, t, fin_q and fin_v, min_d, y_min, y_max, any_c and com_speed < p.trap_speed,
            stopped_since, min(hx, tx), 0.0,
        )  # fmt: skip
        if code != R.CHUNK_FULL:
            break
        # Step bounds: displacement far from / approaching the pillar, largest step.
        vmax = 0.0
        for i in range(n):
            vmax = max(vmax, math.hypot(f0[2 * i], f0[2 * i + 1]))
        free = min_d - r_cut
        disp = min(p.max_disp, max(p.contact_disp, 0.5 * free))
        h_cap = min(disp / (vmax + 1e-12), p.dt_max)
        # W = M(q) J(q), from M(q) left in bw.mob by the top of the loop and the contact
        # stiffness of q in w.st; one LU of I − γhW serves every stage of a try. With
        # p.w_reuse > 1 a W (and its LU, while h stays) serves several steps: the
        # methods keep their order for any W (W-methods); W is refreshed after a
        # rejection, when the beads in contact change, or when it is w_reuse steps old.
        n_c = 0
        c_sig = 0
        for i in range(n):
            if w.st[i] > 0.0:
                n_c += 1
                c_sig += (i + 1) * (i + 1)
        if w_age >= p.w_reuse or c_sig != w_sig or n_c != w_nc:
            force_jacobian(frame, pillar, p, w, bw)
            w_matrix(bw)
            w_age = 0
            w_sig = c_sig
            w_nc = n_c
            h_lu = 0.0
        w_age += 1
        while True:
            h = min(h, h_cap)
            if p.mode == 1 and t + h > p.t_stop:
                h = max(p.t_stop - t, 1e-15)
            if p.w_reuse > 1 and h_lu > 0.0 and h_lu <= h <= KEEP_H * h_lu:
                h = h_lu  # keep the factored step rather than refactor for a small change
            if h != h_lu:
                ok = system(bw, h, piv, gamma)
                h_lu = h if ok else 0.0
            else:
                ok = True
            if third:
                err = _try_ros34pw2(k, q, f0, fext, has_ext, h, piv, ok, xs, qn, qnew)
            else:
                err = _try_ros2(k, q, f0, fext, has_ext, h, piv, ok, k1, k2, qn, qnew)
            if not (ok and math.isfinite(err)):
                err = 1e300
            ratio = p.tol / max(err, 1e-300)
            fac = 0.9 * (ratio ** (1.0 / 3.0) if third else math.sqrt(ratio))
            if p.pi_control and err <= p.tol and not last_rejected:
                # Gustafsson's PI controller: (tol/e_n)^(0.7/k) (e_{n-1}/tol)^(0.4/k)
                fac = 0.9 * ratio ** (0.7 / order) * (err_prev / p.tol) ** (0.4 / order)
            fac = min(2.0, max(0.2, fac))
            if err <= p.tol or h <= 1e-12:
                for r in range(n2):
                    q[r] = qnew[r]
                t += h
                if p.pi_control and last_rejected:
                    fac = min(fac, 1.0)  # no growth right after a rejection
                h = h * fac
                err_prev = max(err, 1e-4 * p.tol)
                last_rejected = False
                break
            rejected += 1
            h = h * fac
            last_rejected = True
            if w_age > 1:
                # W is from an earlier step: refresh it at q before the retry. The stage
                # evaluations overwrote w (positions, contact stiffness) and bw.mob.
                _velocity(frame, flow, pillar, body, p, w, bw, effects, q, fext, has_ext, f0)
                force_jacobian(frame, pillar, p, w, bw)
                w_matrix(bw)
                w_age = 1
                h_lu = 0.0
    state[0] = t
    state[1] = stopped_since
    state[2] = theta
    state[3] = h
    state[4] = rejected
    return rows, code


def run_rosenbrock(
    k: Kernel, x0: float, y0: float, th0: float, beads0: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, int]:
    """Integrate a bead-spring run with adaptive Rosenbrock-W steps (:func:`integrate_rosenbrock`).

    ROS2 or ROS34PW2 as ``k.params.rosw`` says (``fiber.integrator``).

    Returns
    -------
    (rec, beads, code)
        Record rows (record.COLS), bead positions (rows, n, 2) [µm], stop code.
    """
    n = k.body.s.shape[0]
    q = chain(n, k.params.half_b, x0, y0, th0, beads0)
    h0 = min(1e-5, k.params.dt_max)
    state = np.array([0.0, math.nan, th0, h0, 0.0])
    scratch = [np.zeros(2 * n) for _ in range(5)]
    return R.collect(  # type: ignore[return-value]
        lambda rec, brec: integrate_rosenbrock(q, state, k, rec, brec, *scratch), n
    )
