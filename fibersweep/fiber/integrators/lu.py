"""Small dense LU factorisation with partial pivoting, in place: the Rosenbrock integrators' solve.

A Rosenbrock-W step (:mod:`fibersweep.fiber.integrators.rosenbrock`) solves two (ROS2) or
four (ROS34PW2) systems with the same matrix I − γhW (2n ≈ 40–100 unknowns):
one factorisation, a triangular solve per stage, and no allocation per step
(``np.linalg.solve`` copies the matrix and factorises it at every call).
Checked against ``np.linalg.solve`` in tests/unit/test_fiber_lu.py.
"""

from __future__ import annotations

import numba as nb
import numpy as np

__all__ = ["lu_factor", "lu_solve"]


@nb.njit(cache=True)
def lu_factor(a: np.ndarray, piv: np.ndarray) -> bool:
    """Factorise ``a`` (m, m) in place as P a = L U (unit L below, U on and above the diagonal).

    ``piv`` (m,) int64 receives the row swapped with row k at step k. Returns
    False when a pivot is exactly zero (singular matrix), True otherwise.
    """
    m = a.shape[0]
    for k in range(m):
        p = k
        big = abs(a[k, k])
        for i in range(k + 1, m):
            v = abs(a[i, k])
            if v > big:
                big = v
                p = i
        piv[k] = p
        if big == 0.0:
            return False
        if p != k:
            for j in range(m):
                tmp = a[k, j]
                a[k, j] = a[p, j]
                a[p, j] = tmp
        inv = 1.0 / a[k, k]
        # Row views let Numba vectorise the update (twice as fast as a[i, j] indexing).
        rowk = a[k, k + 1 :]
        for i in range(k + 1, m):
            lik = a[i, k] * inv
            a[i, k] = lik
            rowi = a[i, k + 1 :]
            for j in range(rowk.shape[0]):
                rowi[j] -= lik * rowk[j]
    return True


@nb.njit(cache=True)
def lu_solve(lu: np.ndarray, piv: np.ndarray, b: np.ndarray) -> None:
    """Solve a x = b in place (``b`` (m,) becomes x) with the factors of :func:`lu_factor`."""
    m = lu.shape[0]
    for k in range(m):
        p = piv[k]
        if p != k:
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
    for i in range(m):
        acc = b[i]
        for j in range(i):
            acc -= lu[i, j] * b[j]
        b[i] = acc
    for i in range(m - 1, -1, -1):
        acc = b[i]
        for j in range(i + 1, m):
            acc -= lu[i, j] * b[j]
        b[i] = acc / lu[i, i]
