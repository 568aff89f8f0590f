"""The contact force's decay rate, which bounds the rigid model's explicit step.

The explicit midpoint step is stable on a decaying mode of rate λ while Δt λ ≤ 2 (its
real stability interval is [−2, 0]); the rigid model keeps Δt ≤ 0.5 / λ. The stiff
mode is the contact force's: bead i, pushed along its contact normal n_i with the
radial stiffness k_i = |d|F|/dr| of the pair law, moves the body (V, Ω) by N' g_i per
unit force, g_i = K_iᵀ n_i (the body-frame force and torque of a unit force along n_i at
bead i; K_i as in :func:`~fibersweep.fiber.hydro.rpy.rigid_map`) and N' the body
mobility that the run's mobility hooks leave (the wall's with ``near_wall``, the
pillar's drag with ``pillar_hydro``). The
Jacobian of the body velocity by the body's coordinates is then −N' G, G = Σ_i k_i g_i g_iᵀ
(symmetric, positive semi-definite), whose largest eigenvalue is at most the trace of
N'^½ G N'^½:

    λ ≤ Σ_i k_i g_iᵀ N' g_i.

Without a mobility hook, g_iᵀ N g_i ≤ m_tip (the largest eigenvalue of the bead's own
mobility K_i N K_iᵀ), and the rate kept is the former bound m_tip Σ_i k_i, bit for bit.
Beside a wall (``near_wall``) N' is smaller across the wall by the lubrication's λ⊥,
the ratio of the gap to the bead radius near contact: the thin contact layer of the gap
law (k ∝ 1/δ_r) no longer sets the step there, the displacement bound does.

n_i is the direction of bead i's contact force (with several pairs on one bead, the
rough pillar, their resultant; beside a surface the pairs' directions differ by a few
degrees); the tangential stiffness of the pair law, |F|/r, is left out as before (it is
δ_r/4r of the radial one near contact). Both are inside the factor 4 of 0.5 against 2.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = ["contact_rate"]


@nb.njit(cache=True)
def contact_rate(
    s: np.ndarray,
    nm: np.ndarray,
    nm_eff: np.ndarray,
    tip_m: float,
    c: float,
    sn: float,
    fx: np.ndarray,
    fy: np.ndarray,
    st: np.ndarray,
) -> float:
    """Bound on the contact force's decay rate of a rigid fiber [1/s] (module docstring).

    Parameters
    ----------
    s : ndarray, shape (n,)
        Bead offsets along the axis [µm].
    nm : ndarray, shape (3, 3)
        The body's own mobility N (body frame).
    nm_eff : ndarray, shape (3, 3)
        The body mobility after the effects' hooks, N' (body frame).
    tip_m : float
        Largest eigenvalue over beads of K_i N K_iᵀ [µm/(pN·s)].
    c, sn : float
        cos and sin of the fiber angle.
    fx, fy : ndarray, shape (n,)
        Contact forces on the beads, lab frame [pN].
    st : ndarray, shape (n,)
        Summed radial stiffness of each bead's contact pairs [pN/µm].

    Returns
    -------
    float
        m_tip Σ_i k_i when N' equals N (the former bound, bit for bit), else
        Σ_i k_i g_iᵀ N' g_i; 0 without contact.
    """
    n = s.shape[0]
    stiff = 0.0
    for i in range(n):
        stiff += st[i]
    if stiff <= 0.0:
        return 0.0
    same = True
    for a in range(3):
        for b in range(3):
            if nm_eff[a, b] != nm[a, b]:
                same = False
    if same:
        return tip_m * stiff
    rate = 0.0
    for i in range(n):
        if st[i] <= 0.0:
            continue
        f = math.sqrt(fx[i] * fx[i] + fy[i] * fy[i])
        if f <= 0.0:  # no direction: the bead's largest mobility
            rate += st[i] * tip_m
            continue
        # unit normal in the body frame; g = (n_x, n_y, s n_y) (torque of (n_x, n_y) at (s, 0))
        gx = (c * fx[i] + sn * fy[i]) / f
        gy = (-sn * fx[i] + c * fy[i]) / f
        gt = s[i] * gy
        q = (
            gx * (nm_eff[0, 0] * gx + nm_eff[0, 1] * gy + nm_eff[0, 2] * gt)
            + gy * (nm_eff[1, 0] * gx + nm_eff[1, 1] * gy + nm_eff[1, 2] * gt)
            + gt * (nm_eff[2, 0] * gx + nm_eff[2, 1] * gy + nm_eff[2, 2] * gt)
        )
        rate += st[i] * q
    return rate
