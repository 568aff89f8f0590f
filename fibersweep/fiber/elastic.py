"""Elastic energy and forces of the bead-spring fiber (docs/model.md).

H = Σ_i (S/4a)(|t_i| − 2a)² + Σ_i (B/2a)(1 − t̂_{i+1}·t̂_i), t_i = r_i − r_{i−1},
S = E π a² [pN], B = E π a⁴/4 [pN·µm²]; F = −∇H.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = ["elastic_energy", "elastic_forces"]


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
