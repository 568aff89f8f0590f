"""Analytic Stokes flow in a rectangular duct (initial guess, forcing, validation)."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["duct_velocity", "duct_center_velocity"]


def duct_velocity(
    y: np.ndarray, z: np.ndarray, width: float, depth: float, g_over_nu: float, terms: int = 200
) -> np.ndarray:
    """Axial velocity of Poiseuille flow in a rectangular duct (series solution).

    Solves ν ∇²u = −g on 0 < y < width, 0 < z < depth with u = 0 on the walls:

        u = (16 a² g / ν π³) Σ_{n odd} (−1)^((n−1)/2) / n³
            [1 − cosh(nπ ỹ / 2a) / cosh(nπ b / 2a)] cos(nπ z̃ / 2a)

    with a = depth/2, b = width/2, z̃ = z − a, ỹ = y − b (White, Viscous Fluid Flow).

    Parameters
    ----------
    y, z : ndarray
        Positions (broadcastable), any length unit.
    width, depth : float
        Duct sides in the same unit.
    g_over_nu : float
        Body force per unit mass over kinematic viscosity (units of 1/(length·time)).
    terms : int
        Number of odd terms.

    Returns
    -------
    ndarray
        u(y, z), broadcast shape of y and z.
    """
    a = depth / 2.0
    b = width / 2.0
    yt = np.asarray(y, dtype=np.float64) - b
    zt = np.asarray(z, dtype=np.float64) - a
    total = np.zeros(np.broadcast(yt, zt).shape)
    for k in range(terms):
        n = 2 * k + 1
        c = n * math.pi / (2.0 * a)
        # cosh ratio written with exponentials to avoid overflow for wide ducts
        ratio = (
            np.exp(c * (np.abs(yt) - b))
            * (1.0 + np.exp(-2.0 * c * np.abs(yt)))
            / (1.0 + math.exp(-2.0 * c * b))
        )
        total += (-1.0) ** k / n**3 * (1.0 - ratio) * np.cos(c * zt)
    return 16.0 * a * a * g_over_nu / math.pi**3 * total


def duct_center_velocity(width: float, depth: float, g_over_nu: float) -> float:
    """Velocity at the duct centre (y = width/2, z = depth/2)."""
    return float(
        duct_velocity(np.array(width / 2.0), np.array(depth / 2.0), width, depth, g_over_nu)
    )
