"""Near-pillar hydrodynamic drag (the ``pillar_hydro`` effect) for both fiber models.

The baseline neglects the hydrodynamic interaction of the fiber with the
pillar. Here it enters as an extra drag on every bead near the pillar,
opposing the bead's motion relative to the pillar (which is at rest):

    F_w,i = −ζ_i U_i,
    ζ_i = k · 6πμa · β_i / (1 − β_i) · exp(−(h_i − a) / ℓ),   β_i = (9/16) a / h_i,

with h_i = max(d_i, a) the distance from the bead centre to the pillar
outline. β/(1 − β) is the first-reflection (Faxén) increase of the drag of a
sphere moving parallel to a plane wall; the exponential screens it beyond
ℓ = H_ch, the channel depth, over which the confining walls cut off the
pillar's disturbance. k = 1 is that estimate; k scales it. Only resistance
is added, so every bead near the pillar is slowed and the fiber turns about
its near-pillar end, as the source describes for fiber-pillar interactions
(about 10 % slower near contact, a little more rotation). The flow's own
push on a bead near a wall, which a full treatment would also correct, is
left as the baseline has it.

Two exact forms of the same law:

- rigid body (body frame, K_i the 2x3 map from (V_x, V_y, Ω) to the velocity
  of bead i at axis offset s_i): (R + ΔR) V = R V₀, with R = N⁻¹,
  ΔR = Σ ζ_i K_iᵀK_i and V₀ the baseline body velocity; i.e.
  V = A⁻¹ V₀, A = I + N ΔR, and the body mobility becomes N' = A⁻¹ N (used
  by the friction solve);
- free beads: U = (I + M Z)⁻¹ (u + M F) = (I + M Z)⁻¹ u + M' F with
  M' = (M⁻¹ + Z)⁻¹, both by the Woodbury identity over the beads with a
  non-negligible ζ only.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = [
    "NEGLIGIBLE",
    "mobility_with_wall_drag",
    "rigid_wall_velocity",
    "solve_body",
    "wall_drag",
]

#: ζ_i below this fraction of the Stokes drag 6πμa is dropped.
NEGLIGIBLE = 1e-6


@nb.njit(cache=True)
def wall_drag(dist, a, strength, length, mu, zeta):
    """Extra drag coefficient of each bead near the pillar.

    Parameters
    ----------
    dist : ndarray, shape (n,)
        Bead-centre distance to the pillar outline [µm].
    a : float
        Bead radius [µm].
    strength : float
        k, multiplier on the Faxén wall correction [-].
    length : float
        Screening length ℓ [µm].
    mu : float
        Viscosity [pN s/µm²].
    zeta : ndarray, shape (n,)
        Written: ζ_i [pN s/µm]; exactly 0 where negligible.

    Returns
    -------
    int
        Number of beads with ζ_i > 0.
    """
    z0 = 6.0 * math.pi * mu * a
    count = 0
    for i in range(dist.shape[0]):
        h = max(dist[i], a)
        beta = 0.5625 * a / h
        g = strength * beta / (1.0 - beta) * math.exp(-(h - a) / length)
        if g > NEGLIGIBLE:
            zeta[i] = z0 * g
            count += 1
        else:
            zeta[i] = 0.0
    return count


@nb.njit(cache=True)
def _inv3(m, out):
    """Inverse of a 3x3 matrix by cofactors (``m`` is well conditioned here: I + N ΔR)."""
    c00 = m[1, 1] * m[2, 2] - m[1, 2] * m[2, 1]
    c01 = m[1, 2] * m[2, 0] - m[1, 0] * m[2, 2]
    c02 = m[1, 0] * m[2, 1] - m[1, 1] * m[2, 0]
    det = m[0, 0] * c00 + m[0, 1] * c01 + m[0, 2] * c02
    out[0, 0] = c00 / det
    out[1, 0] = c01 / det
    out[2, 0] = c02 / det
    out[0, 1] = (m[0, 2] * m[2, 1] - m[0, 1] * m[2, 2]) / det
    out[1, 1] = (m[0, 0] * m[2, 2] - m[0, 2] * m[2, 0]) / det
    out[2, 1] = (m[0, 1] * m[2, 0] - m[0, 0] * m[2, 1]) / det
    out[0, 2] = (m[0, 1] * m[1, 2] - m[0, 2] * m[1, 1]) / det
    out[1, 2] = (m[0, 2] * m[1, 0] - m[0, 0] * m[1, 2]) / det
    out[2, 2] = (m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0]) / det


@nb.njit(cache=True, inline="always")
def solve_body(a, ainv, nm, nm_out, b0, b1, b2):
    """With ``a`` = I + N ΔR_b (3, 3): N' = a⁻¹ N into ``nm_out``, and a⁻¹ (b0, b1, b2).

    ``ainv`` (3, 3) is scratch for a⁻¹; ``nm`` is the body mobility N (body frame).
    The rigid body's velocity with an added resistance, shared by ``pillar_hydro``
    and ``near_wall``.
    """
    _inv3(a, ainv)
    for i in range(3):
        for j in range(3):
            nm_out[i, j] = ainv[i, 0] * nm[0, j] + ainv[i, 1] * nm[1, j] + ainv[i, 2] * nm[2, j]
    return (
        ainv[0, 0] * b0 + ainv[0, 1] * b1 + ainv[0, 2] * b2,
        ainv[1, 0] * b0 + ainv[1, 1] * b1 + ainv[1, 2] * b2,
        ainv[2, 0] * b0 + ainv[2, 1] * b1 + ainv[2, 2] * b2,
    )


@nb.njit(cache=True)
def rigid_wall_velocity(s, nm, zeta, vbx, vby, om, nm_out):
    """Body velocity of a rigid fiber with the extra wall drag ζ (see the module docstring).

    Parameters
    ----------
    s : ndarray, shape (n,)
        Bead offsets along the axis [µm].
    nm : ndarray, shape (3, 3)
        Body mobility N (body frame).
    zeta : ndarray, shape (n,)
        Extra drag coefficients [pN s/µm] (from :func:`wall_drag`).
    vbx, vby, om : float
        Baseline body velocity V₀ (body frame) [µm/s, rad/s].
    nm_out : ndarray, shape (3, 3)
        Written: the body mobility with the wall drag, N' = A⁻¹ N.

    Returns
    -------
    (vbx, vby, om)
        Corrected body velocity A⁻¹ V₀ (body frame).
    """
    # ΔR = Σ ζ_i K_iᵀK_i with K_i = [[1, 0, 0], [0, 1, s_i]]
    r00 = 0.0
    r12 = 0.0
    r22 = 0.0
    for i in range(s.shape[0]):
        z = zeta[i]
        r00 += z
        r12 += z * s[i]
        r22 += z * s[i] * s[i]
    a = np.empty((3, 3))
    for i in range(3):
        a[i, 0] = nm[i, 0] * r00
        a[i, 1] = nm[i, 1] * r00 + nm[i, 2] * r12
        a[i, 2] = nm[i, 1] * r12 + nm[i, 2] * r22
        a[i, i] += 1.0
    return solve_body(a, np.empty((3, 3)), nm, nm_out, vbx, vby, om)


@nb.njit(cache=True)
def mobility_with_wall_drag(mob, zeta, vel):
    """Add the wall drag to free beads in place: M -> (M⁻¹ + Z)⁻¹, u -> (I + M Z)⁻¹ u.

    With A the beads with ζ_i > 0 and W = (Z_A⁻¹ + M_AA)⁻¹ (Woodbury):
    M' = M − M[:, A] W M[A, :] and (I + M Z)⁻¹ u = u − M[:, A] W u_A.

    Parameters
    ----------
    mob : ndarray, shape (2n, 2n)
        Bead mobility M [µm/(pN s)] (symmetric); overwritten with M'.
    zeta : ndarray, shape (n,)
        Extra drag coefficients [pN s/µm].
    vel : ndarray, shape (2n,)
        Background velocities u of the beads [µm/s]; overwritten with (I + M Z)⁻¹ u.
    """
    n = zeta.shape[0]
    k = 0
    for i in range(n):
        if zeta[i] > 0.0:
            k += 1
    if k == 0:
        return
    idx = np.empty(2 * k, dtype=np.int64)
    j = 0
    for i in range(n):
        if zeta[i] > 0.0:
            idx[2 * j] = 2 * i
            idx[2 * j + 1] = 2 * i + 1
            j += 1
    m2 = 2 * k
    small = np.empty((m2, m2))
    rhs = np.empty((m2, 2 * n + 1))  # [M[A, :] | u_A]
    for p in range(m2):
        for q in range(m2):
            small[p, q] = mob[idx[p], idx[q]]
        small[p, p] += 1.0 / zeta[idx[p] // 2]
        for r in range(2 * n):
            rhs[p, r] = mob[idx[p], r]
        rhs[p, 2 * n] = vel[idx[p]]
    w = np.linalg.solve(small, rhs)
    for r in range(2 * n):
        acc_u = 0.0
        for p in range(m2):
            acc_u += mob[r, idx[p]] * w[p, 2 * n]
        for q in range(2 * n):
            acc = 0.0
            for p in range(m2):
                acc += rhs[p, r] * w[p, q]  # M[r, A] = M[A, r] (symmetric)
            mob[r, q] -= acc
        vel[r] -= acc_u
