"""Rotne–Prager–Yamakawa mobility of equal beads in a plane, and the rigid-fiber body mobility.

All beads lie in the plane z = const, so the in-plane 2x2 blocks of the 3x3 RPY
tensor decouple from z and are all a planar problem needs.

Units: lengths µm, viscosity pN·s/µm², forces pN, velocities µm/s, so the
mobility is in µm/(pN·s).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numba as nb
import numpy as np

__all__ = [
    "BodyMobility",
    "body_mobility",
    "body_velocity",
    "fiber_offsets",
    "rigid_map",
    "rpy_fill",
    "rpy_matrix",
    "rpy_pair",
    "rpy_scalars",
]


@nb.njit(cache=True, inline="always")
def rpy_scalars(r: float, a: float, mu: float) -> tuple[float, float]:
    """RPY pair mobility as f I + g r̂r̂ for centre distance r; returns (f, g) [µm/(pN·s)].

    r = 0 gives the self term 1/(6πμa) I.
    """
    m0 = 1.0 / (6.0 * math.pi * mu * a)
    if r == 0.0:
        return m0, 0.0
    if r >= 2.0 * a:
        c = 1.0 / (8.0 * math.pi * mu * r)
        q = a * a / (r * r)
        return c * (1.0 + 2.0 * q / 3.0), c * (1.0 - 2.0 * q)
    return m0 * (1.0 - 9.0 * r / (32.0 * a)), m0 * (3.0 * r / (32.0 * a))


@nb.njit(cache=True)
def rpy_fill(x: np.ndarray, y: np.ndarray, a: float, mu: float, out: np.ndarray) -> None:
    """Write the grand RPY mobility of beads at (x, y) (n,) [µm] into ``out`` (2n, 2n)."""
    n = x.shape[0]
    for i in range(n):
        for j in range(i, n):
            dx = x[j] - x[i]
            dy = y[j] - y[i]
            r = math.sqrt(dx * dx + dy * dy)
            f, g = rpy_scalars(r, a, mu)
            if r > 0.0:
                ex = dx / r
                ey = dy / r
            else:
                ex = 0.0
                ey = 0.0
            mxx = f + g * ex * ex
            mxy = g * ex * ey
            myy = f + g * ey * ey
            out[2 * i, 2 * j] = mxx
            out[2 * i, 2 * j + 1] = mxy
            out[2 * i + 1, 2 * j] = mxy
            out[2 * i + 1, 2 * j + 1] = myy
            out[2 * j, 2 * i] = mxx
            out[2 * j, 2 * i + 1] = mxy
            out[2 * j + 1, 2 * i] = mxy
            out[2 * j + 1, 2 * i + 1] = myy


def rpy_pair(r_vec: np.ndarray, a: float, mu: float) -> np.ndarray:
    """In-plane RPY block between two beads separated by ``r_vec`` (shape (2,)), shape (2, 2)."""
    r_vec = np.asarray(r_vec, dtype=np.float64)
    if r_vec.shape != (2,):
        raise ValueError(f"r_vec must have shape (2,), got {r_vec.shape}")
    r = float(np.hypot(*r_vec))
    f, g = rpy_scalars(r, float(a), float(mu))
    e = r_vec / r if r > 0 else np.zeros(2)
    return f * np.eye(2) + g * np.outer(e, e)


def rpy_matrix(positions: np.ndarray, a: float, mu: float) -> np.ndarray:
    """Grand in-plane RPY mobility of beads at ``positions`` (n, 2) µm, shape (2n, 2n).

    Rows/columns are ordered (x0, y0, x1, y1, ...).
    """
    p = np.ascontiguousarray(positions, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"positions must have shape (n, 2), got {p.shape}")
    out = np.empty((2 * p.shape[0], 2 * p.shape[0]))
    rpy_fill(np.ascontiguousarray(p[:, 0]), np.ascontiguousarray(p[:, 1]), a, mu, out)
    return out


def fiber_offsets(n: int, a: float) -> np.ndarray:
    """Signed distances of the bead centres from the centre of a straight fiber, shape (n,) [µm].

    Beads touch: centres 2a apart. Index n-1 is the end at +θ direction.
    """
    return (np.arange(n) - 0.5 * (n - 1)) * 2.0 * a


def rigid_map(offsets: np.ndarray) -> np.ndarray:
    """K in the body frame, shape (2n, 3): bead velocities from (V_x, V_y, Ω) of a fiber on x."""
    n = offsets.shape[0]
    k = np.zeros((2 * n, 3))
    k[0::2, 0] = 1.0
    k[1::2, 1] = 1.0
    k[1::2, 2] = offsets  # Ω ẑ × (s, 0) = (0, Ω s)
    return k


@dataclass(frozen=True)
class BodyMobility:
    """Body-frame rigid multiblob mobility of a straight fiber of n beads along x.

    Attributes
    ----------
    n : int
    a, mu : float
        Bead radius [µm], viscosity [pN·s/µm²].
    offsets : ndarray, shape (n,)
        Bead positions along the axis [µm].
    N : ndarray, shape (3, 3)
        (Kᵀ M⁻¹ K)⁻¹: (V_x, V_y, Ω) from (F_x, F_y, τ) [µm/(pN·s), rad/(pN·µm·s), ...].
    P : ndarray, shape (3, 2n)
        N Kᵀ M⁻¹: body velocity from the beads' background velocities (body frame).
    chol : ndarray, shape (3, 3)
        Lower Cholesky factor of N (Brownian increments).
    tip_mobility : float
        Largest eigenvalue over beads of the bead's own rigid-motion mobility
        K_i N K_iᵀ [µm/(pN·s)] (for the contact stiffness time-step bound).
    """

    n: int
    a: float
    mu: float
    offsets: np.ndarray
    N: np.ndarray
    P: np.ndarray
    chol: np.ndarray
    tip_mobility: float


@functools.lru_cache(maxsize=128)
def body_mobility(n: int, a: float, mu: float) -> BodyMobility:
    """Precompute (and cache per process) the body mobility of an n-bead fiber."""
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n}")
    s = fiber_offsets(n, a)
    pos = np.column_stack([s, np.zeros(n)])
    m = rpy_matrix(pos, a, mu)
    k = rigid_map(s)
    minv_k = np.linalg.solve(m, k)  # M⁻¹ K, (2n, 3)
    r = k.T @ minv_k  # resistance, (3, 3)
    if n == 1:
        # A single sphere cannot be torqued by bead forces: give it its free rotation.
        r[2, 2] = 8.0 * math.pi * mu * a**3
    r = 0.5 * (r + r.T)
    big_n = np.linalg.inv(r)
    big_n = 0.5 * (big_n + big_n.T)
    p = big_n @ minv_k.T  # N Kᵀ M⁻¹ (M symmetric)
    tip = 0.0
    for i in range(n):
        ki = k[2 * i : 2 * i + 2]
        tip = max(tip, float(np.linalg.eigvalsh(ki @ big_n @ ki.T).max()))
    for arr in (s, big_n, p):
        arr.setflags(write=False)
    chol = np.linalg.cholesky(big_n)
    chol.setflags(write=False)
    return BodyMobility(n, float(a), float(mu), s, big_n, p, chol, tip)


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
