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

How it is read: the field's discrete Laplacian is precomputed once per run on
the field's own lattice (the 5-point stencil, x periodic and zero beyond the
field's y edges, exactly as :func:`~fibersweep.flow.field.interpolate_ib` reads
the field), and read at the beads with the same interpolation and frame as u.
Because the interpolation is linear and shift-invariant on the lattice, this is
exactly the 5-point Laplacian (step Δx) of the interpolated field at the bead,
and exact for a quadratic flow. Cost: one more interpolation per bead and call.

The value k multiplies the term (1 = Faxén's law). With ``near_wall`` also on,
Goren & O'Neill's push across the wall (c_n) already holds the Faxén term of a
flow towards the wall (its far field 1 + 9/8 x + (81/64 + 1/3) x², the 1/3 x²
being Faxén's): the two overlap on the normal component, by at most that term
(docs/validation/near-contact.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from fibersweep.fiber import frame as F
from fibersweep.fiber.effects.base import DynamicsContext, Effect
from fibersweep.fiber.effects.registry import register
from fibersweep.fiber.kernel.hooks import implements

__all__ = ["Faxen", "FaxenKernel", "LaplacianField", "lattice_laplacian"]


class LaplacianField(NamedTuple):
    """The field's in-plane Laplacian, read like a field: ``ux, uy`` (nx, ny) [1/(µm s)]
    on nodes ``dx`` [µm] apart (the frame's ``velocity`` stage reads it as it reads u)."""

    ux: np.ndarray
    uy: np.ndarray
    dx: float


class FaxenKernel(NamedTuple):
    """Kernel record.

    ``c`` k a²/6 [µm²]; ``frame`` the run's frame record (its own scratch); ``lap`` the
    field's in-plane Laplacian on the field's lattice (:class:`LaplacianField`); ``lu``
    (n, 2) scratch: the Laplacian read at the beads [1/(µm s)].
    """

    c: float
    frame: Any
    lap: LaplacianField
    lu: np.ndarray


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

    def kernel(self, ctx: DynamicsContext) -> FaxenKernel:
        a = float(ctx.bead_radius)
        n = int(ctx.n_beads)
        flow = ctx.flow
        if flow is None:  # no field known: a flow with no curvature (the term vanishes)
            lx = ly = np.zeros((4, 4))
            dx = 1.0
        else:
            lx, ly = lattice_laplacian(flow.ux, flow.uy, float(flow.dx))
            dx = float(flow.dx)
        fr = ctx.frame
        if fr is None or not hasattr(fr, "px"):
            fr = F.CHANNEL
        else:  # own scratch: the run's frame fills its own between the stages
            fr = fr._replace(**{k: np.zeros(n) for k in ("xs", "ys", "fxs", "fys", "sts", "dists")})
        lap = LaplacianField(lx, ly, dx)
        return FaxenKernel(float(self.value) * a * a / 6.0, fr, lap, np.zeros((n, 2)))


@implements("background", FaxenKernel)
def background(e, w, u):
    """Both models: u += c ∇²u, the Laplacian read where u was read."""
    m = u.shape[0]
    lu = e.lu[:m]
    F.velocity(e.frame, e.lap, w.x[:m], w.y[:m], lu)
    for i in range(m):
        u[i, 0] += e.c * lu[i, 0]
        u[i, 1] += e.c * lu[i, 1]
