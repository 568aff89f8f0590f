"""In-place LU factorisation and solve against numpy.linalg.solve."""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.fiber.integrators.lu import lu_factor, lu_solve


@pytest.mark.parametrize("m", [1, 2, 7, 44])
def test_lu_solves_like_numpy(m):
    """Random non-symmetric systems (needing row swaps): x within 1e-10 relative of
    numpy's (condition numbers ~1e2-1e3, so round-off is ~1e-13)."""
    rng = np.random.default_rng(m)
    a = rng.normal(size=(m, m)) + np.diag(rng.uniform(-1, 1, m))
    b = rng.normal(size=m)
    lu = a.copy()
    piv = np.zeros(m, dtype=np.int64)
    assert lu_factor(lu, piv)
    x = b.copy()
    lu_solve(lu, piv, x)
    ref = np.linalg.solve(a, b)
    assert np.max(np.abs(x - ref)) < 1e-10 * np.max(np.abs(ref))
    # the factors are reused: a second right-hand side
    b2 = rng.normal(size=m)
    x2 = b2.copy()
    lu_solve(lu, piv, x2)
    assert np.allclose(a @ x2, b2, rtol=0, atol=1e-10 * np.max(np.abs(b2)))


def test_singular_matrix_is_reported():
    a = np.array([[1.0, 2.0], [2.0, 4.0]])
    piv = np.zeros(2, dtype=np.int64)
    assert not lu_factor(a, piv)
