"""``faxen``: a bead is carried by the flow averaged over its surface, u + k (a²/6) ∇²u (1 = Faxén).

Faxén's first law: a force-free sphere of radius a in a Stokes flow u moves with
u + (a²/6)∇²u taken at its centre, exactly when u is at most quadratic (a
Poiseuille profile, a shear; higher terms vanish for a quadratic flow). The
model reads the flow at the bead's centre; this effect adds the surface
average's correction, in the plane of the motion: ∇² is the in-plane Laplacian
∂²/∂x² + ∂²/∂y² of the midplane field. The depth's own curvature
(∂²/∂z² of the Hele-Shaw profile) scales every midplane velocity by one factor,
1 − 4a²/(3H²), and moves no streamline; it is left out (``off_midplane`` and the
field's z-average set the layer's speed).

How it is read: the field's discrete Laplacian is computed once per run on
the field's own lattice (the 5-point stencil, x periodic and zero beyond the
field's y edges, exactly as :func:`~fibersweep.flow.field.interpolate_ib` reads
the field) and added to the node velocities the beads sample
(:meth:`Faxen.sample_flow`): u + c ∇²u on every node, c = k a²/6. Because the
interpolation is linear and shift-invariant on the lattice, reading that sum
at a bead is exactly u plus c times the 5-point Laplacian (step Δx) of the
interpolated field there, exact for a quadratic flow, in every frame (an
array's cell is read folded, the sum with it). Cost: one Laplacian of the
field per run (milliseconds), nothing per step. The other effects' records
see the field itself (``ctx.flow``).

The value k multiplies the term (1 = Faxén's law). With ``near_wall`` also on,
Goren & O'Neill's push across the wall (c_n) already holds the Faxén term of a
flow towards the wall (its far field 1 + 9/8 x + (81/64 + 1/3) x², the 1/3 x²
being Faxén's): the two overlap on the normal component, by at most that term
(docs/validation/near-contact.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from fibersweep.fiber.effects.base import Effect
from fibersweep.fiber.effects.registry import register

__all__ = ["Faxen", "lattice_laplacian"]


def lattice_laplacian(ux: np.ndarray, uy: np.ndarray, dx: float) -> tuple[np.ndarray, np.ndarray]:
    """The 5-point in-plane Laplacian of a node field, read as the interpolation reads it.

    Parameters
    ----------
    ux, uy : ndarray, shape (nx, ny)
        Node velocities [µm/s]; x periodic, zero beyond 0..ny-1 in y (as
        :func:`~fibersweep.flow.field.interpolate_ib`).
    dx : float
        Node spacing [µm].

    Returns
    -------
    lx, ly : ndarray, shape (nx, ny)
        (u[i+1,j] + u[i-1,j] + u[i,j+1] + u[i,j-1] − 4u[i,j]) / Δx² [1/(µm s)].
    """
    ux = np.asarray(ux, dtype=np.float64)
    uy = np.asarray(uy, dtype=np.float64)
    if ux.ndim != 2 or ux.shape != uy.shape:
        raise ValueError(f"ux, uy must be equal 2-D arrays, got {ux.shape} and {uy.shape}")
    if not dx > 0.0:
        raise ValueError(f"dx must be > 0, got {dx!r}")

    def lap(f: np.ndarray) -> np.ndarray:
        p = np.pad(f, ((0, 0), (1, 1)))  # zero beyond the y edges
        out = np.roll(f, 1, axis=0) + np.roll(f, -1, axis=0) - 4.0 * f
        out += p[:, 2:] + p[:, :-2]
        return np.ascontiguousarray(out / (dx * dx))

    return lap(ux), lap(uy)


@register
@dataclass(frozen=True)
class Faxen(Effect):
    name = "faxen"
    unit = "multiplier k in [0, 2] on Faxén's surface-average term k (a²/6) ∇²u (1 = Faxén)"

    def validate(self) -> None:
        self._require(0.0 <= self.value <= 2.0, "must be in [0, 2]")

    def sample_flow(self, flow: NamedTuple, bead_radius: float) -> NamedTuple:
        """``flow`` with ux, uy replaced by u + k (a²/6) ∇²u (:func:`lattice_laplacian`).

        Parameters
        ----------
        flow : FlowArrays
            ``ux, uy`` (nx, ny) [µm/s] on nodes ``dx`` [µm] apart, as the kernels read them.
        bead_radius : float
            a [µm].
        """
        c = float(self.value) * bead_radius * bead_radius / 6.0
        lx, ly = lattice_laplacian(flow.ux, flow.uy, float(flow.dx))
        return flow._replace(
            ux=np.ascontiguousarray(flow.ux + c * lx), uy=np.ascontiguousarray(flow.uy + c * ly)
        )
