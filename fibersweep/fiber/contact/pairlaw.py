"""The soft-core pair law: the one repulsion between fiber beads and the pillar, and within a fiber.

Two points a distance r apart, closer than a cutoff R, repel along their
separation d (|d| = r) with (SPEC.md §3, docs/model.md)

    F = (F_ref / r_eq) · w⁴ · d,   w = (R² − r²) / (R² − r_eq²),

so that |F| = F_ref at r = r_eq, and F and its first three derivatives vanish
at r = R. Its users, each with its own r_eq (R = χ r_eq):

- the rough pillar (:func:`~fibersweep.fiber.contact.pillar.pillar_forces`): a fiber
  bead and a pillar bead, r_eq = a + a_obs;
- the smooth pillar (same function): a bead centre and the pillar outline, r_eq = a;
- the self-exclusion of a fiber (:mod:`fibersweep.fiber.models.exclusion`, forces and
  Jacobian): two of its beads, r_eq = 2a.

:func:`soft_core` is inlined into each of them (``inline="always"``): what a
caller leaves unused is compiled away, and the law is written once.
"""

from __future__ import annotations

import numba as nb

__all__ = ["soft_core"]


@nb.njit(cache=True, inline="always")
def soft_core(r2: float, r2c: float, den: float, amp: float) -> tuple[float, float, float]:
    """The pair law at squared distance ``r2`` < R² [µm²].

    Parameters
    ----------
    r2 : float
        r², squared distance of the pair [µm²].
    r2c : float
        R², squared cutoff [µm²].
    den : float
        R² − r_eq² [µm²].
    amp : float
        F_ref / r_eq [pN/µm].

    Returns
    -------
    s : float
        amp · w⁴ [pN/µm]: the force on the first point is s · d, with d the
        separation from the second [µm]; its magnitude is s · r.
    g : float
        amp · 8 w³ / den [pN/µm³]: with it the Jacobian of that force with
        respect to the first point, ∂F/∂d = s I − g d dᵀ [pN/µm].
    k : float
        |d|F|/dr| = |amp (w⁴ − 8 w³ r² / den)| [pN/µm], the radial stiffness.
    """
    w = (r2c - r2) / den
    w3 = w * w * w
    s = amp * w3 * w
    g = amp * 8.0 * w3 / den
    k = abs(amp * (w3 * w - 8.0 * w3 * r2 / den))
    return s, g, k
