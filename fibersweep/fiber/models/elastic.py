"""Elastic energy and forces of the bead-spring fiber (docs/model.md).

H = Σ_i (S/4a)(|t_i| − 2a)² + Σ_i (B/2a)(1 − t̂_{i+1}·t̂_i), t_i = r_i − r_{i−1},
S = E π a² [pN], B = E π a⁴/4 [pN·µm²]; F = −∇H.

The functions' length ``a`` is half the springs' rest length: the bead radius for
the source's chain of touching beads, b/2 for beads b apart
(:mod:`fibersweep.fiber.models.spacing`), where H is Σ (S/2b)(|t_i| − b)² + Σ (B/b)(1 − c_i),
the discretised ∫ (S/2) ε² + (B/2) κ² ds with S and B the radius-a fiber's.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = ["elastic_energy", "elastic_forces", "elastic_jacobian"]


@nb.njit(cache=True)
def elastic_energy(x: np.ndarray, y: np.ndarray, a: float, S: float, B: float) -> float:
    """H [pN·µm] of beads at (x, y) [µm] with stretching S [pN] and bending B [pN·µm²]."""
    n = x.shape[0]
    e = 0.0
    for i in range(1, n):
        ln = math.hypot(x[i] - x[i - 1], y[i] - y[i - 1])
        e += S / (4.0 * a) * (ln - 2.0 * a) ** 2
    for i in range(1, n - 1):
        ax = x[i] - x[i - 1]
        ay = y[i] - y[i - 1]
        bx = x[i + 1] - x[i]
        by = y[i + 1] - y[i]
        c = (ax * bx + ay * by) / (math.hypot(ax, ay) * math.hypot(bx, by))
        e += B / (2.0 * a) * (1.0 - c)
    return e


@nb.njit(cache=True)
def elastic_forces(
    x: np.ndarray, y: np.ndarray, a: float, S: float, B: float, fx: np.ndarray, fy: np.ndarray
) -> None:
    """F = −∇H into fx, fy [pN] (overwritten)."""
    n = x.shape[0]
    for i in range(n):
        fx[i] = 0.0
        fy[i] = 0.0
    for i in range(1, n):
        tx = x[i] - x[i - 1]
        ty = y[i] - y[i - 1]
        ln = math.hypot(tx, ty)
        g = S / (2.0 * a) * (ln - 2.0 * a) / ln  # dH/dt_i = g t_i
        fx[i] -= g * tx
        fy[i] -= g * ty
        fx[i - 1] += g * tx
        fy[i - 1] += g * ty
    kb = B / (2.0 * a)
    for i in range(1, n - 1):
        ax = x[i] - x[i - 1]
        ay = y[i] - y[i - 1]
        bx = x[i + 1] - x[i]
        by = y[i + 1] - y[i]
        la = math.hypot(ax, ay)
        lb = math.hypot(bx, by)
        c = (ax * bx + ay * by) / (la * lb)
        # d(t̂a·t̂b)/dta = (t̂b − c t̂a)/|ta|; dH = −kb d(c)
        gax = -kb * (bx / lb - c * ax / la) / la
        gay = -kb * (by / lb - c * ay / la) / la
        gbx = -kb * (ax / la - c * bx / lb) / lb
        gby = -kb * (ay / la - c * by / lb) / lb
        # ta = r_i − r_{i−1}, tb = r_{i+1} − r_i
        fx[i] -= gax - gbx
        fy[i] -= gay - gby
        fx[i - 1] += gax
        fy[i - 1] += gay
        fx[i + 1] -= gbx
        fy[i + 1] -= gby


@nb.njit(cache=True, inline="always")
def _add_block(jac, p, q, s, k00, k01, k10, k11):
    """jac[2p:2p+2, 2q:2q+2] += s K for the 2x2 block K = [[k00, k01], [k10, k11]]."""
    jac[2 * p, 2 * q] += s * k00
    jac[2 * p, 2 * q + 1] += s * k01
    jac[2 * p + 1, 2 * q] += s * k10
    jac[2 * p + 1, 2 * q + 1] += s * k11


@nb.njit(cache=True)
def elastic_jacobian(
    x: np.ndarray, y: np.ndarray, a: float, S: float, B: float, jac: np.ndarray
) -> None:
    """Add J = ∂F/∂q = −∇²H of the elastic forces into ``jac`` (2n, 2n) [pN/µm], analytically.

    q = (x0, y0, x1, ...). Stretching spring i (t = r_i − r_{i−1}, l = |t|) has
    force −g t on bead i with g = (S/2a)(1 − 2a/l), so its stiffness is
    K = g I + (S/l³) t tᵀ, entering +K on the off-diagonal and −K on the diagonal
    blocks of beads i−1, i. Bending term kb(1 − c), kb = B/2a, c = t̂a·t̂b with
    ta = r_i − r_{i−1}, tb = r_{i+1} − r_i: with da = ∂c/∂ta = (t̂b − c t̂a)/la,
    db = (t̂a − c t̂b)/lb and P = I − t̂t̂ᵀ,
        ∂da/∂ta = −(t̂a daᵀ + da t̂aᵀ)/la − c Pa/la²,
        ∂da/∂tb = (Pb/lb − t̂a dbᵀ)/la,
        ∂db/∂tb = −(t̂b dbᵀ + db t̂bᵀ)/lb − c Pb/lb²,
    and ∂²H/∂ta∂tb = −kb ∂da/∂tb etc., mapped to the beads i−1, i, i+1 through
    ∂ta/∂r = (−I, I, 0), ∂tb/∂r = (0, −I, I). The result is block pentadiagonal
    (bead j couples to j−2..j+2). Checked against central differences of
    :func:`elastic_forces` in tests/unit/test_fiber_elastic_jacobian.py.
    """
    n = x.shape[0]
    for i in range(1, n):
        tx = x[i] - x[i - 1]
        ty = y[i] - y[i - 1]
        ln = math.hypot(tx, ty)
        g = S / (2.0 * a) * (1.0 - 2.0 * a / ln)
        c3 = S / (ln * ln * ln)
        kxx = g + c3 * tx * tx
        kxy = c3 * tx * ty
        kyy = g + c3 * ty * ty
        _add_block(jac, i, i, -1.0, kxx, kxy, kxy, kyy)
        _add_block(jac, i - 1, i - 1, -1.0, kxx, kxy, kxy, kyy)
        _add_block(jac, i, i - 1, 1.0, kxx, kxy, kxy, kyy)
        _add_block(jac, i - 1, i, 1.0, kxx, kxy, kxy, kyy)
    kb = B / (2.0 * a)
    for i in range(1, n - 1):
        ax = x[i] - x[i - 1]
        ay = y[i] - y[i - 1]
        bx = x[i + 1] - x[i]
        by = y[i + 1] - y[i]
        la = math.hypot(ax, ay)
        lb = math.hypot(bx, by)
        ux = ax / la
        uy = ay / la
        vx = bx / lb
        vy = by / lb
        c = ux * vx + uy * vy
        dax = (vx - c * ux) / la
        day = (vy - c * uy) / la
        dbx = (ux - c * vx) / lb
        dby = (uy - c * vy) / lb
        # Haa = ∂²H/∂ta² = −kb ∂da/∂ta, Hab = ∂²H/∂ta∂tb, Hbb = ∂²H/∂tb²
        s = kb / la
        s2 = kb * c / (la * la)
        aaxx = s * 2.0 * ux * dax + s2 * (1.0 - ux * ux)
        aaxy = s * (ux * day + dax * uy) - s2 * ux * uy
        aayy = s * 2.0 * uy * day + s2 * (1.0 - uy * uy)
        s = kb / lb
        s2 = kb * c / (lb * lb)
        bbxx = s * 2.0 * vx * dbx + s2 * (1.0 - vx * vx)
        bbxy = s * (vx * dby + dbx * vy) - s2 * vx * vy
        bbyy = s * 2.0 * vy * dby + s2 * (1.0 - vy * vy)
        s = -kb / la
        abxx = s * ((1.0 - vx * vx) / lb - ux * dbx)
        abxy = s * (-vx * vy / lb - ux * dby)
        abyx = s * (-vy * vx / lb - uy * dbx)
        abyy = s * ((1.0 - vy * vy) / lb - uy * dby)
        # J = −∂²H/∂r∂r with ca = (−1, 1, 0), cb = (0, −1, 1) over beads (i−1, i, i+1)
        for pp in range(3):
            cap = (-1.0, 1.0, 0.0)[pp]
            cbp = (0.0, -1.0, 1.0)[pp]
            for qq in range(3):
                caq = (-1.0, 1.0, 0.0)[qq]
                cbq = (0.0, -1.0, 1.0)[qq]
                p = i - 1 + pp
                q = i - 1 + qq
                _add_block(jac, p, q, -cap * caq, aaxx, aaxy, aaxy, aayy)
                _add_block(jac, p, q, -cbp * cbq, bbxx, bbxy, bbxy, bbyy)
                _add_block(jac, p, q, -cap * cbq, abxx, abxy, abyx, abyy)
                _add_block(jac, p, q, -cbp * caq, abxx, abyx, abxy, abyy)
