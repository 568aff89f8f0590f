"""Excluded volume between non-neighbouring beads of one bead-spring fiber (docs/flexible.md).

The chain's springs keep neighbours 2a apart but nothing else stops a soft
fiber from passing through itself. Two beads i, j with |i − j| >= ``gap``
whose centres are closer than the cutoff R repel each other with the pillar's
contact law (:func:`~fibersweep.fiber.contact.pairlaw.soft_core`), with the bead
diameter in place of the bead-to-pillar distance:

    F_i = −F_j = (F_ref / r_eq) · w⁴ · (r_i − r_j),
    w = (R² − r²) / (R² − r_eq²),  r = |r_i − r_j| < R,

r_eq = 2a (|F| = F_ref at contact of the bead surfaces), R = χ · 2a, and χ,
F_ref those of the pillar contact (``fiber.contact.chi``, ``fiber.contact.f_ref``,
default 6πμaU). The force is exactly zero at and beyond R (pairs there are
skipped, so a fiber whose distant beads never come that close runs bit for bit
as without it) and continuous with three derivatives at R.

Index gap: ``gap`` = 2 (:data:`GAP`). Beads i, i+1 are held at 2a by their
spring and are never paired. Beads i, i+2 are 4a·cos(φ/2) apart when the chain
turns by φ at bead i+1; they come within R = 2.2a only when φ > 113°, a
radius of curvature 2a/φ below 1.01a, which a solid fiber of radius a cannot
reach (its inner side would fold over itself). So the pair force never acts on
a physically bent chain, and it stops the single-bead kinks (hairpins at one
bead) that the bending spring, whose restoring force ∝ sin φ weakens past 90°,
lets through under load. A gap of 3 would leave those kinks free.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from fibersweep.fiber.contact.pairlaw import soft_core

__all__ = ["GAP", "exclusion_forces", "exclusion_jacobian", "min_self_distance"]

GAP = 2
"""Smallest index difference |i − j| of a repelling pair (module docstring)."""


@nb.njit(cache=True)
def exclusion_forces(
    x: np.ndarray,
    y: np.ndarray,
    gap: int,
    r_cut: float,
    r_eq: float,
    f_ref: float,
    fx: np.ndarray,
    fy: np.ndarray,
) -> int:
    """Add the pair forces [pN] of beads at (x, y) [µm] to ``fx, fy``; return the active pairs.

    Parameters
    ----------
    x, y : ndarray, shape (n,)
        Bead centres [µm].
    gap : int
        Pairs with |i − j| >= gap interact (0: none).
    r_cut, r_eq : float
        Cutoff R and the distance where |F| = F_ref [µm].
    f_ref : float
        Force scale [pN].
    fx, fy : ndarray, shape (n,)
        Forces [pN]; only beads of active pairs are touched.

    Returns
    -------
    int
        Number of pairs closer than R.
    """
    n = x.shape[0]
    if gap <= 0:
        return 0
    r2c = r_cut * r_cut
    den = r2c - r_eq * r_eq
    amp = f_ref / r_eq
    pairs = 0
    for i in range(n):
        xi = x[i]
        yi = y[i]
        for j in range(i + gap, n):
            dx = xi - x[j]
            if dx >= r_cut or dx <= -r_cut:
                continue
            dy = yi - y[j]
            r2 = dx * dx + dy * dy
            if r2 >= r2c:
                continue
            s, _, _ = soft_core(r2, r2c, den, amp)
            fx[i] += s * dx
            fy[i] += s * dy
            fx[j] -= s * dx
            fy[j] -= s * dy
            pairs += 1
    return pairs


@nb.njit(cache=True, inline="always")
def _add_sym(jac: np.ndarray, p: int, q: int, kxx: float, kxy: float, kyy: float) -> None:
    """jac[2p:2p+2, 2q:2q+2] += [[kxx, kxy], [kxy, kyy]]."""
    jac[2 * p, 2 * q] += kxx
    jac[2 * p, 2 * q + 1] += kxy
    jac[2 * p + 1, 2 * q] += kxy
    jac[2 * p + 1, 2 * q + 1] += kyy


@nb.njit(cache=True)
def exclusion_jacobian(
    x: np.ndarray,
    y: np.ndarray,
    gap: int,
    r_cut: float,
    r_eq: float,
    f_ref: float,
    jac: np.ndarray,
) -> bool:
    """Add ∂F/∂q [pN/µm] of :func:`exclusion_forces` into ``jac`` (2n, 2n), analytically.

    With d = r_i − r_j, F_i = amp w⁴ d, ∂w/∂r_i = −2d/den (den = R² − r_eq²):
        K = ∂F_i/∂r_i = amp (w⁴ I − (8 w³/den) d dᵀ) = s I − g d dᵀ
    (s, g of :func:`~fibersweep.fiber.contact.pairlaw.soft_core`),
    entering +K on the diagonal blocks (i, i), (j, j) and −K on (i, j), (j, i):
    symmetric, and translations are zero modes. Unlike the springs' Jacobian it is
    not banded: a pair can couple any two beads |i − j| >= gap apart.

    Returns
    -------
    bool
        Whether a pair with |i − j| > 2 is active (a block outside the springs'
        pentadiagonal band was written).
    """
    n = x.shape[0]
    far = False
    if gap <= 0:
        return far
    r2c = r_cut * r_cut
    den = r2c - r_eq * r_eq
    amp = f_ref / r_eq
    for i in range(n):
        for j in range(i + gap, n):
            dx = x[i] - x[j]
            if dx >= r_cut or dx <= -r_cut:
                continue
            dy = y[i] - y[j]
            r2 = dx * dx + dy * dy
            if r2 >= r2c:
                continue
            s0, g, _ = soft_core(r2, r2c, den, amp)
            s1 = -g
            kxx = s0 + s1 * dx * dx
            kxy = s1 * dx * dy
            kyy = s0 + s1 * dy * dy
            _add_sym(jac, i, i, kxx, kxy, kyy)
            _add_sym(jac, j, j, kxx, kxy, kyy)
            _add_sym(jac, i, j, -kxx, -kxy, -kyy)
            _add_sym(jac, j, i, -kxx, -kxy, -kyy)
            if j - i > 2:
                far = True
    return far


def min_self_distance(beads: np.ndarray, gap: int = GAP) -> float:
    """Smallest centre distance [µm] between beads |i − j| >= gap apart, over all rows.

    Parameters
    ----------
    beads : ndarray, shape (n, 2) or (rows, n, 2)
        Bead centres [µm].
    gap : int

    Returns
    -------
    float
        inf when the chain has fewer than gap + 1 beads.
    """
    b = np.asarray(beads, dtype=np.float64)
    if b.ndim == 2:
        b = b[None]
    n = b.shape[1]
    i, j = np.triu_indices(n, k=gap)
    if i.size == 0:
        return float("inf")
    d = np.linalg.norm(b[:, i, :] - b[:, j, :], axis=-1)
    return float(d.min())
