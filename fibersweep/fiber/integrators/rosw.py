"""Rosenbrock-W methods of the bead-spring fiber: their codes, ROS2's γ, the ROS34PW2 tableau
and its stage arithmetic.

ROS2 (two stages, γ = :data:`GAMMA2` = 1 + 1/√2) is written out in
:mod:`fibersweep.fiber.integrators.rosenbrock`; the rigid fiber's stopped steps use it too
(:mod:`fibersweep.fiber.models.rigid`).

ROS34PW2 (Rang & Angermann 2005, BIT 45:761) is a four-stage Rosenbrock-W
method of order 3 with an embedded method of order 2, L-stable and stiffly
accurate. In the form of Hairer & Wanner (Solving ODEs II, IV.7), for
q' = f(q) and any matrix W (a W-method: its order holds for an inexact W),

    (I − γ h W) k_i = f(q + h Σ_{j<i} α_ij k_j) + h W Σ_{j<i} γ_ij k_j,
    q' = q + h Σ b_i k_i,   q̂' = q + h Σ b̂_i k_i.

:mod:`fibersweep.fiber.integrators.rosenbrock` uses the transformed form that
needs no product with W: with Γ = (γ_ij) (γ_ii = γ) and x = Γ k / γ,

    (I − γ h W) x_i = f(q + h Σ_{j<i} a_ij x_j) + Σ_{j<i} c_ij x_j,
    q' = q + h Σ m_j x_j,   error h Σ e_j x_j,

a = γ α Γ⁻¹, c_ij = −γ (Γ⁻¹)_ij (j < i), m = γ b Γ⁻¹, e = γ (b − b̂) Γ⁻¹.
One LU of I − γhW serves all four stages. The coefficients are the published
ones (16 digits); :func:`w_order_residuals` checks them against the W-method
order conditions (tests/unit/test_fiber_rosw.py).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = [
    "A34",
    "ALPHA",
    "C34",
    "E34",
    "M34",
    "B",
    "BHAT",
    "GAMMA2",
    "GAMMA3",
    "GAMMA_MATRIX",
    "METHODS",
    "ROS2_CODE",
    "ROS34PW2",
    "ROS34PW2_CODE",
    "combine",
    "stage_point",
    "stage_rhs",
    "transformed",
    "w_order_residuals",
]

ROS2_CODE = 0
ROS34PW2_CODE = 1
METHODS = {"ros2": ROS2_CODE, "ros34pw2": ROS34PW2_CODE}
"""``Params.rosw`` of each method, by its ``fiber.integrator`` name."""

GAMMA2 = 1.0 + 1.0 / math.sqrt(2.0)
"""γ of ROS2."""

GAMMA3 = 4.3586652150845900e-01
"""γ of ROS34PW2 (the diagonal of Γ)."""


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype=np.float64)
    a.setflags(write=False)
    return a


ALPHA = _frozen(
    [
        [0.0, 0.0, 0.0, 0.0],
        [8.7173304301691801e-01, 0.0, 0.0, 0.0],
        [8.4457060015369423e-01, -1.1299064236484185e-01, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
    ]
)
"""α_ij of ROS34PW2 (strictly lower triangular)."""

GAMMA_MATRIX = _frozen(
    [
        [GAMMA3, 0.0, 0.0, 0.0],
        [-8.7173304301691801e-01, GAMMA3, 0.0, 0.0],
        [-9.0338057013044082e-01, 5.4180672388095326e-02, GAMMA3, 0.0],
        [2.4212380706095346e-01, -1.2232505839045147e00, 5.4526025533510214e-01, GAMMA3],
    ]
)
"""Γ = (γ_ij) of ROS34PW2, γ on the diagonal."""

B = _frozen([2.4212380706095346e-01, -1.2232505839045147e00, 1.5452602553351020e00, GAMMA3])
"""Weights b_i of the third-order solution."""

BHAT = _frozen([3.7810903145819369e-01, -9.6042292212423178e-02, 0.5, 2.1793326075422950e-01])
"""Weights b̂_i of the embedded second-order solution."""


def transformed(
    alpha: np.ndarray, gamma_matrix: np.ndarray, b: np.ndarray, bhat: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Coefficients (a, c, m, e) of the transformed form (module docstring).

    Parameters
    ----------
    alpha, gamma_matrix : ndarray, shape (s, s)
        α (strictly lower) and Γ (lower, constant diagonal γ).
    b, bhat : ndarray, shape (s,)
        Weights of the solution and of the embedded one.

    Returns
    -------
    a, c : ndarray, shape (s, s)
        Strictly lower triangular.
    m, e : ndarray, shape (s,)
        Weights of the solution and of the error estimate (m − m̂).
    """
    g = float(gamma_matrix[0, 0])
    ginv = np.linalg.inv(gamma_matrix)
    a = np.tril(g * alpha @ ginv, -1)
    c = np.tril(-g * ginv, -1)
    m = g * b @ ginv
    e = g * (b - bhat) @ ginv
    return tuple(_frozen(v) for v in (a, c, m, e))  # type: ignore[return-value]


ROS34PW2 = transformed(ALPHA, GAMMA_MATRIX, B, BHAT)
"""(a, c, m, e) of ROS34PW2, the arrays the Numba kernel reads."""
A34, C34, M34, E34 = ROS34PW2


def w_order_residuals(
    alpha: np.ndarray, gamma_matrix: np.ndarray, b: np.ndarray, order: int
) -> np.ndarray:
    """Residuals of the order conditions of a Rosenbrock-W method (zero when satisfied).

    With 1 = (1, ..., 1), the conditions up to order 3 for any W are
    (Hairer & Wanner II, IV.7; Steihaug & Wolfbrandt 1979): bᵀ1 = 1; bᵀα1 = 1/2,
    bᵀΓ1 = 0; bᵀ(α1)² = 1/3, bᵀαα1 = 1/6, bᵀαΓ1 = 0, bᵀΓα1 = 0, bᵀΓΓ1 = 0.
    (With W = J, the conditions with Γ merge with those of α into the classical
    Rosenbrock ones, e.g. bᵀ(α + Γ)1 = 1/2.)

    Parameters
    ----------
    alpha, gamma_matrix : ndarray, shape (s, s)
    b : ndarray, shape (s,)
    order : {1, 2, 3}
        Conditions up to this order: 1, 3 or 8 residuals.
    """
    one = np.ones(len(b))
    res = [b @ one - 1.0]
    if order >= 2:
        res += [b @ alpha @ one - 0.5, b @ gamma_matrix @ one]
    if order >= 3:
        ca = alpha @ one
        res += [
            b @ ca**2 - 1.0 / 3.0,
            b @ alpha @ ca - 1.0 / 6.0,
            b @ alpha @ gamma_matrix @ one,
            b @ gamma_matrix @ ca,
            b @ gamma_matrix @ gamma_matrix @ one,
        ]
    return np.array(res)


@nb.njit(cache=True)
def stage_point(q, h, a, xs, i, out):
    """``out`` = q + h Σ_{j<i} a[i, j] xs[j] (the argument of stage i's f) [µm]."""
    for r in range(q.shape[0]):
        acc = 0.0
        for j in range(i):
            acc += a[i, j] * xs[j, r]
        out[r] = q[r] + h * acc


@nb.njit(cache=True)
def stage_rhs(c, xs, i, fi):
    """``fi`` += Σ_{j<i} c[i, j] xs[j] (stage i's right-hand side, before the solve)."""
    for r in range(fi.shape[0]):
        acc = 0.0
        for j in range(i):
            acc += c[i, j] * xs[j, r]
        fi[r] += acc


@nb.njit(cache=True)
def combine(q, h, w, xs, out):
    """``out`` = q + h Σ_j w[j] xs[j]; ``q`` may be a zero vector (the error estimate)."""
    for r in range(q.shape[0]):
        acc = 0.0
        for j in range(w.shape[0]):
            acc += w[j] * xs[j, r]
        out[r] = q[r] + h * acc
