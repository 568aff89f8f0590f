"""Deformation observables of a bead-spring run, from its bead positions (docs/flexible.md).

For beads r_1..r_n with segments t_i = r_i − r_{i−1} (i = 2..n) of contour
length Λ = Σ|t_i|, per recorded configuration:

- curvature at an interior bead: κ_i = φ_i / (½(|t_i| + |t_{i+1}|)) [1/µm], φ_i the
  angle between t_i and t_{i+1} (the discrete turning angle);
- end-to-end ratio |r_n − r_1| / Λ (1 for a straight fiber);
- tension of a segment: the stretching spring's force along it,
  T_i = (S / b)(|t_i| − b) [pN] (positive when stretched, S = E π a² (:mod:`.rod`), b the bead
  spacing: 2a for touching beads);
- wrap angle: the turning of the tangent, Σ φ_i with signs, over the beads
  between the first and last bead within ``r_cut + a/2`` of the pillar's outline
  (the beads touching or hugging it), in degrees; 0 for a straight fiber and
  for a fiber touching with one bead.

A run reports the largest curvature, tension and |wrap angle| and the smallest
end-to-end ratio over its record.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fibersweep.fiber.contact.pillar import shape_distance
from fibersweep.fiber.models.rod import rod
from fibersweep.fiber.models.spacing import spacing_um

__all__ = ["DEFORMATION_FIELDS", "deformation"]

#: RunResult fields filled here, with their units.
DEFORMATION_FIELDS = {
    "max_curvature": "1/µm",
    "min_end_to_end": "",
    "max_tension": "pN",
    "max_wrap": "deg",
}


@nb.njit(cache=True)
def _scan(beads, contact, verts, circle, near, a, stretch):
    """(max κ [1/µm], min end-to-end ratio, max T [pN], max |wrap| [rad]) over the rows.

    ``a``: half the bead spacing b/2 [µm] (the springs' rest length is 2a).

    ``beads`` (rows, n, 2) [µm]; ``contact`` (rows,) 1 where the row is in contact
    (the wrap angle is evaluated only there); ``near`` the distance to the outline
    [µm] within which a bead counts as on the pillar.
    """
    rows = beads.shape[0]
    n = beads.shape[1]
    kmax = 0.0
    e2e = 1e300
    tmax = -1e300
    wmax = 0.0
    phi = np.zeros(n)
    for r in range(rows):
        lam = 0.0
        for i in range(1, n):
            tx = beads[r, i, 0] - beads[r, i - 1, 0]
            ty = beads[r, i, 1] - beads[r, i - 1, 1]
            ln = math.hypot(tx, ty)
            lam += ln
            tmax = max(tmax, stretch / (2.0 * a) * (ln - 2.0 * a))
            if i < n - 1:
                ux = beads[r, i + 1, 0] - beads[r, i, 0]
                uy = beads[r, i + 1, 1] - beads[r, i, 1]
                lu = math.hypot(ux, uy)
                ang = math.atan2(tx * uy - ty * ux, tx * ux + ty * uy)
                phi[i] = ang
                kmax = max(kmax, abs(ang) / (0.5 * (ln + lu)))
        ee = math.hypot(beads[r, n - 1, 0] - beads[r, 0, 0], beads[r, n - 1, 1] - beads[r, 0, 1])
        e2e = min(e2e, ee / lam)
        if contact[r] > 0.5:
            first = -1
            last = -1
            for i in range(n):
                if shape_distance(beads[r, i, 0], beads[r, i, 1], verts, circle) < near:
                    if first < 0:
                        first = i
                    last = i
            if last > first >= 0:
                w = 0.0
                # turning at the interior beads first+1 .. last-1 (between their segments)
                for i in range(max(first, 1), min(last, n - 1)):
                    w += phi[i]
                wmax = max(wmax, abs(w))
    return kmax, e2e, tmax, wmax


def deformation(
    beads: np.ndarray,
    contact: np.ndarray,
    vertices: np.ndarray,
    circle: np.ndarray,
    r_cut: float,
    a: float,
    young_modulus: float,
    spacing: float = 1.0,
) -> dict[str, float]:
    """The run's deformation observables (see the module docstring).

    Parameters
    ----------
    beads : ndarray, shape (rows, n, 2)
        Bead positions of every recorded row [µm].
    contact : ndarray, shape (rows,)
        1 where the row is in contact with the pillar.
    vertices : ndarray, shape (m, 2)
        Pillar polygon (CCW) [µm]; (0, 2) for a circle.
    circle : ndarray, shape (3,)
        (x, y, radius) of a circular pillar [µm]; radius 0 for a polygon.
    r_cut : float
        Contact cutoff [µm].
    a : float
        Bead radius [µm].
    young_modulus : float
        E [Pa] (= pN/µm²).
    spacing : float
        ``fiber.bead_spacing``: bead spacing b as a fraction of 2a (1: touching beads).

    Returns
    -------
    dict
        ``max_curvature`` [1/µm], ``min_end_to_end`` [-], ``max_tension`` [pN],
        ``max_wrap`` [deg].
    """
    b = np.ascontiguousarray(beads, dtype=np.float64)
    if b.ndim != 3 or b.shape[0] == 0 or b.shape[1] < 2:
        raise ValueError(f"beads: need shape (rows >= 1, n >= 2, 2), got {b.shape}")
    kmax, e2e, tmax, wmax = _scan(
        b,
        np.ascontiguousarray(contact, dtype=np.float64),
        np.ascontiguousarray(vertices, dtype=np.float64),
        np.ascontiguousarray(circle, dtype=np.float64),
        float(r_cut + 0.5 * a),
        0.5 * spacing_um(a, spacing),
        float(rod(young_modulus, a).stretch),
    )
    return {
        "max_curvature": float(kmax),
        "min_end_to_end": float(e2e),
        "max_tension": float(tmax),
        "max_wrap": float(math.degrees(wmax)),
    }
