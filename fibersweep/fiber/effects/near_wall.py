"""``near_wall``: drag and flow push of the pillar's wall on every bead, from theory (1 = it).

A sphere near a plane wall is slowed anisotropically (Brenner; Goldman, Cox &
Brenner: much more across the wall than along it) and is carried by the
wall's flow more slowly than the fluid at its centre, across the wall (Goren &
O'Neill) more than along it (Goldman, Cox & Brenner). This effect applies
those exact sphere–plane results to each bead, with the local plane of the
nearest pillar surface (:mod:`fibersweep.fiber.hydro.nearwall`, which says how the
plane is taken at corners and how several beads and pillars combine). The
value k multiplies every correction (λ − 1, c − 1); 1 is the theory. It
differs from ``pillar_hydro`` (an isotropic first-reflection drag, no push,
k a free multiplier the discrepancy workflow calibrates): both may be on.

Works in the channel and in arrays (every pillar image within reach), for the
rigid model (a one-bead fiber, a sphere, rolls freely; beads of longer fibers
turn with the fiber) and the bead-spring models.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numba as nb
import numpy as np

from fibersweep.fiber.effects.base import DynamicsContext, Effect
from fibersweep.fiber.effects.registry import register
from fibersweep.fiber.hydro.nearwall import (
    bead_wall_mobility,
    new_scratch,
    rigid_wall_body,
    sides_of,
    wall_terms,
)
from fibersweep.fiber.kernel.hooks import implements
from fibersweep.fiber.models.rigid import FD_STEP

__all__ = ["RIGID_REUSE", "NearWall", "NearWallKernel"]

#: The rigid model keeps a bead's wall terms while it stays within this distance [µm] of
#: where they were computed: the finite-difference Jacobian of its integrator moves each
#: bead by at most FD_STEP, and the Jacobian only sets the step's stability. The terms
#: change by about RIGID_REUSE/δ relative over it (1e-4 at a contact gap δ = 0.2 µm).
RIGID_REUSE = 2.0 * FD_STEP


class NearWallKernel(NamedTuple):
    """Kernel record (lengths µm).

    ``z0`` k·6πμa [pN s/µm]; ``a`` bead radius; ``ell`` screening length H/2;
    ``free`` torque-free beads (a one-bead fiber); ``reuse`` the rigid model's
    reuse distance (:data:`RIGID_REUSE`; 0 recomputes every call); the pillar (``kind``,
    ``verts``, ``circle``, ``curves``; ``sides`` the rough polygon's precomputed sides)
    and where its copies stand (``lattice``;
    ``px``, ``py``, ``sy`` periods and row shift; ``bounds`` of the one at the
    origin); scratch: ``roots`` (3,), ``b`` (NROWS, n) where each bead's terms
    were computed, its extra resistance, push map and force
    (:func:`~fibersweep.fiber.hydro.nearwall.wall_terms`), ``nm`` (3, 3) the changed
    body mobility, ``m3`` (3, 3, 3) the rigid form's scratch; ``curved`` the normal
    resistance scaled by the local curvature (``fiber.contact.curvature: local``), ``rc``
    the polygon's corner radius then [µm].
    """

    z0: float
    a: float
    ell: float
    free: bool
    reuse: float
    kind: int
    verts: np.ndarray
    circle: np.ndarray
    curves: np.ndarray
    sides: np.ndarray
    lattice: bool
    px: float
    py: float
    sy: float
    bounds: np.ndarray
    roots: np.ndarray
    b: np.ndarray
    nm: np.ndarray
    m3: np.ndarray
    curved: bool = False
    rc: float = 0.0


@register
@dataclass(frozen=True)
class NearWall(Effect):
    name = "near_wall"
    unit = "multiplier k >= 0 on the sphere-wall theory's drag and push of the pillar (1 = theory)"

    def validate(self) -> None:
        self._require(0.0 <= self.value <= 2.0, "must be in [0, 2]")

    def kernel(self, ctx: DynamicsContext) -> NearWallKernel:
        a = float(ctx.bead_radius)
        n = int(ctx.n_beads)
        pil = ctx.pillar
        if pil is None:  # no pillar known: one with no surface (nothing is ever near it)
            kind, verts, circle, curves = 0, np.zeros((0, 2)), np.zeros(3), np.zeros((0, 3, 2))
            sides = np.zeros((0, 6))
        else:
            kind, verts, circle, curves = pil.kind, pil.verts, pil.circle, pil.curves
            sides = sides_of(pil)
        fr = ctx.frame
        lattice = fr is not None and hasattr(fr, "px")
        px, py, sy = (float(fr.px), float(fr.py), float(fr.sy)) if lattice else (1.0, 1.0, 0.0)
        bounds = np.array(fr.bounds, dtype=np.float64) if lattice else np.zeros(4)
        return NearWallKernel(
            float(self.value) * 6.0 * math.pi * float(ctx.viscosity) * a,
            a,
            0.5 * float(ctx.depth),
            n == 1,
            RIGID_REUSE,
            int(kind),
            np.ascontiguousarray(verts, dtype=np.float64),
            np.ascontiguousarray(circle, dtype=np.float64),
            np.ascontiguousarray(curves, dtype=np.float64),
            sides,
            bool(lattice),
            px,
            py,
            sy,
            bounds,
            np.zeros(3),
            new_scratch(n),
            np.zeros((3, 3)),
            np.zeros((3, 3, 3)),
            bool(ctx.curvature),
            float(ctx.corner_radius),
        )


@nb.njit(cache=True, inline="always")
def _terms(e, w, tol):
    return wall_terms(
        w.x, w.y, w.u, w.dist, e.a, e.z0, e.ell, e.free, e.kind, e.verts, e.circle, e.curves,
        e.roots, e.sides, e.lattice, e.px, e.py, e.sy, e.bounds, tol, e.b, e.curved, e.rc,
    )  # fmt: skip


@implements("rigid_mobility", NearWallKernel)
def rigid_mobility(e, body, w, c, sn, vbx, vby, om, nm_eff):
    """Rigid model: V = (I + N ΔR_b)⁻¹ (V₀ + N E_b), N' = (I + N ΔR_b)⁻¹ N."""
    if _terms(e, w, e.reuse) > 0:
        vbx, vby, om = rigid_wall_body(body.s, nm_eff, c, sn, e.b, vbx, vby, om, e.nm, e.m3)
        return vbx, vby, om, e.nm
    return vbx, vby, om, nm_eff


@implements("bead_mobility", NearWallKernel)
def bead_mobility(e, w, bw):
    """Bead-spring model: M -> M' = (M⁻¹ + Z)⁻¹ and u -> M'(M⁻¹ u + E) (Woodbury)."""
    if _terms(e, w, 0.0) > 0:  # exact: a bead's terms are kept only where it has not moved
        bead_wall_mobility(bw.mob, bw.f, e.b)
