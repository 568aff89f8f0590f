"""The bead spacing of a bead-spring chain: a discretisation of one continuum fiber.

A fiber of length L, radius a and Young's modulus E is a chain of n beads of
radius a (the hydrodynamic radius) whose centres are b apart. The default,
b = 2a, is the source's chain of touching beads. ``fiber.bead_spacing`` sets
b as a fraction of 2a (0 < b/2a <= 1); finer chains have overlapping beads,
whose RPY mobility is defined (:func:`~fibersweep.fiber.hydro.rpy.rpy_scalars`).
Every per-bead quantity is scaled so that the chain has one continuum limit as
b -> 0, the same fiber at every spacing:

- **Length.** The bead surfaces span L = (n − 1) b + 2a, so
  n = round((L − 2a)/b) + 1 (at b = 2a: round(L/2a), the source's rule).
- **Elastic energy** (:mod:`fibersweep.fiber.models.elastic` with its ``a`` set to b/2):
  H = Σ (S/2b)(|t_i| − b)² + Σ (B/b)(1 − t̂_{i+1}·t̂_i), the discretisation of
  ∫ (S/2) ε² + (B/2) κ² ds with strain ε = (|t| − b)/b and curvature κ = φ/b.
  S = Eπa² and B = Eπa⁴/4 are those of the continuum fiber at every b.
- **Drag.** Each bead keeps radius a; the velocity of bead i is Σ_j M_ij F_j
  with F_j = f(s_j) b for a force density f, so it tends to the RPY line
  integral ∫ M(s_i − s) f(s) ds as b -> 0 (the overlapping-bead branch keeps the
  integrand bounded). The drag per unit length therefore converges; it differs
  from the touching chain's only in the O(1) constant beside ln(L/a)
  (tests/validation/test_chain_spacing.py measures both).
- **Pillar contact.** The per-bead law (rough or smooth) is kept and its force
  scale multiplied by b/2a (:func:`bead_force_scale`), so that the force per
  unit length of fiber pressed on the pillar, and the depth at which a given
  load per unit length is held, do not depend on b. The trap and contact rules
  read distances and speeds, not forces, and are unchanged.
- **Self-exclusion** (:mod:`fibersweep.fiber.models.exclusion`). Two beads |i − j| >= g
  repel when closer than χ·2a. Beads whose arc distance |i − j| b is shorter
  than 4a are parts of the same short piece of fiber, overlapping or nearly so
  by construction, and are skipped: g = ceil(4a/b) (:func:`exclusion_gap`, 2 at
  b = 2a as before). A pair at arc distance 4a comes within χ·2a = 2.2a only on
  an arc of centreline radius below 1.16a, which a solid fiber of radius a can
  barely bend to; the folds the exclusion exists for (two arms of a hairpin
  side by side, 2a apart) have every pair across them further apart along the
  arc. The pair force is scaled by (b/2a)² (:func:`exclusion_force_scale`): the
  number of pairs between two arms lying side by side grows as 1/b², so the
  force per unit length between them does not depend on b.

At the default spacing every factor is exactly 1 and every rule the source's,
so runs are bit for bit those of the chain before the setting existed.
"""

from __future__ import annotations

import math

import numpy as np

from fibersweep.fiber.models.exclusion import GAP

__all__ = [
    "DEFAULT_SPACING",
    "EXCLUSION_ARC",
    "bead_force_scale",
    "exclusion_force_scale",
    "exclusion_gap",
    "n_beads",
    "offsets",
    "spacing_um",
]

#: ``fiber.bead_spacing`` of the touching chain, the source's: b = 2a.
DEFAULT_SPACING = 1.0
#: Arc distance [in units of a] below which two beads of a chain never repel.
EXCLUSION_ARC = 4.0


def spacing_um(bead_radius: float, fraction: float = DEFAULT_SPACING) -> float:
    """Bead spacing b [µm] = fraction · 2a (a [µm]); exactly 2a at the default."""
    if fraction == DEFAULT_SPACING:
        return 2.0 * bead_radius
    return float(fraction) * 2.0 * bead_radius


def n_beads(length: float, bead_radius: float, fraction: float = DEFAULT_SPACING) -> int:
    """Beads of a fiber of length L [µm]: round((L − 2a)/b) + 1, at least 1.

    At the default spacing this is the source's round(L / 2a), evaluated as such
    (the two differ at exact halves under round-half-even).
    """
    if fraction == DEFAULT_SPACING:
        return max(1, int(round(length / (2.0 * bead_radius))))
    b = spacing_um(bead_radius, fraction)
    return max(1, int(round((length - 2.0 * bead_radius) / b)) + 1)


def offsets(n: int, bead_radius: float, fraction: float = DEFAULT_SPACING) -> np.ndarray:
    """Signed distances of the bead centres from the centre of a straight chain, (n,) [µm].

    Centres b apart; index n − 1 is the end towards +θ.
    """
    return (np.arange(n) - 0.5 * (n - 1)) * spacing_um(bead_radius, fraction)


def bead_force_scale(fraction: float = DEFAULT_SPACING) -> float:
    """Factor b/2a on the pillar contact's per-bead force scale (1 at the default)."""
    return 1.0 if fraction == DEFAULT_SPACING else float(fraction)


def exclusion_force_scale(fraction: float = DEFAULT_SPACING) -> float:
    """Factor (b/2a)² on the self-exclusion's pair force (1 at the default)."""
    return 1.0 if fraction == DEFAULT_SPACING else float(fraction) ** 2


def exclusion_gap(fraction: float = DEFAULT_SPACING) -> int:
    """Smallest index difference of a repelling pair: ceil(4a / b), at least 2.

    b = 2a: 2; b = a: 4; b = a/2: 8 (module docstring).
    """
    if fraction == DEFAULT_SPACING:
        return GAP
    # 4a / b = EXCLUSION_ARC / (2 fraction); the tolerance keeps 4a/b = 4 at 4
    return max(GAP, math.ceil(EXCLUSION_ARC / (2.0 * float(fraction)) - 1e-9))
