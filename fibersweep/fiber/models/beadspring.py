"""The bead-spring fiber model: bead velocities and force Jacobians (docs/flexible.md).

Energy (docs/model.md), t_i = r_i − r_{i−1}, beads b apart (2a by default,
``fiber.bead_spacing``, :mod:`fibersweep.fiber.models.spacing`):
    H = Σ_i (S/2b)(|t_i| − b)² + Σ_i (B/b)(1 − t̂_{i+1}·t̂_i),
S = E π a², B = E π a⁴/4 (:mod:`fibersweep.fiber.models.elastic`, with its length scale b/2).
The bead velocities (positions q = (x0, y0, x1, ...), 2n) are

    f(q) = u(q) + M(q) F(q),

u the background flow at the beads, M the RPY mobility
(:mod:`fibersweep.fiber.hydro.rpy`), F = −∇H plus the pillar contact
(:mod:`fibersweep.fiber.contact.pillar`) and the repulsion of non-neighbouring beads
(``fiber.self_exclusion``, :mod:`fibersweep.fiber.models.exclusion`), so the chain cannot
pass through itself; the effects' stages add their forces and mobilities.

The integrators (:mod:`fibersweep.fiber.integrators.bdf2`,
:mod:`fibersweep.fiber.integrators.rosenbrock`)
take the stiff forces implicitly through J = ∂F/∂q: :func:`force_jacobian`
(analytic springs and pairs, contact by differences) or :func:`force_jacobian_fd`
(springs by differences too, banded: the BDF2 reference's).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fibersweep.fiber import frame as F
from fibersweep.fiber.hydro.rpy import fiber_offsets, rpy_fill
from fibersweep.fiber.kernel import hooks as H
from fibersweep.fiber.models.elastic import elastic_forces, elastic_jacobian
from fibersweep.fiber.models.exclusion import exclusion_forces, exclusion_jacobian

__all__ = [
    "bead_velocity",
    "chain",
    "force_jacobian",
    "force_jacobian_fd",
    "velocity_at",
]


@nb.njit(cache=True)
def bead_velocity(frame, flow, pillar, body, p, w, bw, effects):
    """f(q) = u + M F at the beads ``w.x, w.y`` into ``bw.f`` (2n); M into ``bw.mob``.

    Elastic forces, the self-exclusion of non-neighbouring beads
    (:mod:`fibersweep.fiber.models.exclusion`, off when ``p.excl_gap`` is 0), contact
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
    elastic_forces(x, y, p.half_b, p.stretch, p.bend, fx, fy)
    exclusion_forces(x, y, p.excl_gap, p.excl_cut, p.excl_eq, p.excl_fref, fx, fy)
    n_c, cx, cy = F.contact(frame, pillar, x, y, cfx, cfy, w.st, w.dist)
    any_c = n_c > 0
    for i in range(n):
        fx[i] += cfx[i]
        fy[i] += cfy[i]
    H.each_background(effects, w, u)
    for i in range(n):
        f[2 * i] = u[i, 0]
        f[2 * i + 1] = u[i, 1]
    H.each_bead_forces(effects, body, w, bw, any_c)
    rpy_fill(x, y, p.a, p.mu, mob)
    H.each_bead_mobility(effects, w, bw)
    for r in range(2 * n):
        acc = 0.0
        for j in range(n):
            acc += mob[r, 2 * j] * fx[j] + mob[r, 2 * j + 1] * fy[j]
        f[r] += acc
    return any_c, cx, cy


@nb.njit(cache=True, inline="always")
def velocity_at(frame, flow, pillar, body, p, w, bw, effects, q):
    """:func:`bead_velocity` at positions ``q`` (2n) [µm], copied into ``w.x, w.y`` first.

    Returns (any_contact, cx, cy, min_d): min_d the smallest bead-centre distance
    to a pillar outline [µm].
    """
    n = q.shape[0] // 2
    for i in range(n):
        w.x[i] = q[2 * i]
        w.y[i] = q[2 * i + 1]
    any_c, cx, cy = bead_velocity(frame, flow, pillar, body, p, w, bw, effects)
    min_d = 1e300
    for i in range(n):
        min_d = min(min_d, w.dist[i])
    return any_c, cx, cy, min_d


@nb.njit(cache=True, inline="always")
def _contact_column(frame, pillar, h, x, y, j, comp, jac, scratch):
    """Add column 2j + comp of the contact forces' Jacobian to ``jac``, by central differences.

    The contact force on bead j depends on bead j only: the column has its 2x2
    block's entries (rows 2j, 2j+1), from the contact of bead j alone moved by
    ±h [µm] along x (comp 0) or y (comp 1). ``scratch``: (8, 1).
    """
    one_x = scratch[0]  # bead j alone, moved
    one_y = scratch[1]
    c1 = scratch[2]  # its contact force at +h
    c2 = scratch[3]
    c3 = scratch[4]  # at −h
    c4 = scratch[5]
    d1 = scratch[6]  # stiffness and distance, unused
    d2 = scratch[7]
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

    The elastic part is analytic (:func:`~fibersweep.fiber.models.elastic.elastic_jacobian`,
    block pentadiagonal), and so is the self-exclusion's
    (:func:`~fibersweep.fiber.models.exclusion.exclusion_jacobian`: blocks anywhere, J is
    used dense); the contact part, a 2x2 block per bead in contact
    (``w.st`` > 0, as left by the last :func:`bead_velocity`), by central
    differences with step 1e-6 a. The Rosenbrock integrators' Jacobian;
    :func:`force_jacobian_fd` is the BDF2 reference's.
    """
    jac = bw.jac
    x = w.x
    y = w.y
    n2 = jac.shape[0]
    for i in range(n2):
        for j in range(n2):
            jac[i, j] = 0.0
    elastic_jacobian(x, y, p.half_b, p.stretch, p.bend, jac)
    exclusion_jacobian(x, y, p.excl_gap, p.excl_cut, p.excl_eq, p.excl_fref, jac)
    h = 1e-6 * p.a
    s = np.empty((8, 1))
    for j in range(x.shape[0]):
        if w.st[j] <= 0.0:
            continue
        for comp in range(2):
            _contact_column(frame, pillar, h, x, y, j, comp, jac, s)


@nb.njit(cache=True)
def force_jacobian_fd(frame, pillar, p, w, bw):
    """J = ∂F/∂q (2n, 2n) [pN/µm] into ``bw.jac`` by central differences, banded.

    Elastic forces couple a bead to its two neighbours on each side; the contact
    force on a bead depends on that bead only (a 2x2 diagonal block, computed
    only for beads with a non-zero contact stiffness ``w.st``). Uses
    ``bw.gx, gy, cfx, cfy`` as scratch. The BDF2 reference's Jacobian (its
    results stay those of the source's method); see :func:`force_jacobian`.
    The self-exclusion's blocks are added analytically
    (:func:`~fibersweep.fiber.models.exclusion.exclusion_jacobian`).

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
    a = p.half_b  # the springs' length scale, b/2
    h = 1e-6 * p.a
    for i in range(2 * n):
        for j in range(2 * n):
            jac[i, j] = 0.0
    s = np.empty((8, 1))
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
            # inside the loop: the contact is differenced at the x[j] + h − 2h + h the
            # springs' differences leave (it may be an ulp off x[j])
            if st[j] > 0.0:
                _contact_column(frame, pillar, h, x, y, j, comp, jac, s)
    return exclusion_jacobian(x, y, p.excl_gap, p.excl_cut, p.excl_eq, p.excl_fref, jac)


def chain(
    n: int, half_b: float, x0: float, y0: float, th0: float, beads0: np.ndarray | None = None
) -> np.ndarray:
    """Start positions q (2n,) [µm]: ``beads0`` (n, 2), or a straight chain of n beads
    2 ``half_b`` apart (the bead spacing b [µm]) centred on (x0, y0) [µm] along the angle
    th0 [rad] (bead n−1 the head)."""
    if beads0 is None:
        s = fiber_offsets(n, half_b)
        beads0 = np.column_stack([x0 + s * math.cos(th0), y0 + s * math.sin(th0)])
    return np.ascontiguousarray(beads0, dtype=np.float64).reshape(-1).copy()
