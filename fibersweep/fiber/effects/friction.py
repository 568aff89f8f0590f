"""``friction``: Coulomb friction on the pillar surface (value = coefficient μ_f ≥ 0).

Each fiber bead in contact gets, besides its repulsion F_n, a tangential force
F_t with |F_t| ≤ μ_f |F_n| that opposes its tangential motion and at most stops
it (stick) — never reverses it. Rigid model: the tangential forces of all
contacting beads are solved together (projected Gauss-Seidel on the rigid-body
mobility, normal forces fixed). Bead-spring model: the same solve for the rigid
body the (nearly rigid) fiber moves as, body axis from tail to head. Works on
both pillars; on the rough pillar it adds to the roughness the discrete pillar
beads already give. The source's trapping example needs μ_f ≈ 0.3 at dx = 4 µm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numba as nb
import numpy as np

from fibersweep.fiber.effects.base import DynamicsContext, Effect
from fibersweep.fiber.effects.registry import register
from fibersweep.fiber.hydro.rpy import body_velocity
from fibersweep.fiber.kernel.hooks import implements

__all__ = ["Friction", "FrictionKernel", "coulomb_friction"]


class FrictionKernel(NamedTuple):
    """Kernel record: the friction coefficient μ_f [-] and the beads' tangential
    forces (n,) [pN] (scratch of the solve)."""

    mu_f: float
    tang: np.ndarray


@register
@dataclass(frozen=True)
class Friction(Effect):
    name = "friction"
    unit = "friction coefficient tangential/normal force, >= 0"

    def validate(self) -> None:
        self._require(self.value >= 0.0, "must be >= 0")

    def kernel(self, ctx: DynamicsContext) -> FrictionKernel:
        return FrictionKernel(float(self.value), np.zeros(ctx.n_beads))


@nb.njit(cache=True)
def coulomb_friction(c, sn, s, nm, fx, fy, mu_f, vbx, vby, om, ft):
    """Coulomb friction on the contacting beads of a rigid fiber (projected Gauss-Seidel).

    Each bead's tangential force (along t̂ = ẑ × n̂, n̂ the direction of its
    contact force) is set to stop its tangential motion, clipped to ±μ_f |F_n|
    (stick or slide); the normal forces are fixed. All in the body frame.

    Parameters
    ----------
    c, sn : float
        cos and sin of the fiber angle.
    s : ndarray, shape (n,)
        Bead offsets [µm].
    nm : ndarray, shape (3, 3)
        Body mobility N.
    fx, fy : ndarray, shape (n,)
        Contact forces (lab frame) [pN].
    mu_f : float
        Friction coefficient.
    vbx, vby, om : float
        Frictionless body velocity (body frame) [µm/s, rad/s].
    ft : ndarray, shape (n,)
        Written with each bead's tangential force along its t̂ [pN].

    Returns
    -------
    (vbx, vby, om)
        Body velocity with friction (body frame).
    """
    n = s.shape[0]
    for i in range(n):
        ft[i] = 0.0
    for _ in range(30):
        change = 0.0
        for i in range(n):
            fnx = c * fx[i] + sn * fy[i]
            fny = -sn * fx[i] + c * fy[i]
            fn = math.sqrt(fnx * fnx + fny * fny)
            if fn == 0.0:
                continue
            tx = -fny / fn
            ty = fnx / fn
            vt = vbx * tx + (vby + om * s[i]) * ty
            # m_t = t̂ᵀ K_i N K_iᵀ t̂ with K_iᵀ t̂ = (tx, ty, s_i ty)
            kz = s[i] * ty
            g0 = nm[0, 0] * tx + nm[0, 1] * ty + nm[0, 2] * kz
            g1 = nm[1, 0] * tx + nm[1, 1] * ty + nm[1, 2] * kz
            g2 = nm[2, 0] * tx + nm[2, 1] * ty + nm[2, 2] * kz
            mt = tx * g0 + ty * g1 + kz * g2
            lim = mu_f * fn
            new = min(lim, max(-lim, ft[i] - vt / mt))
            d = new - ft[i]
            if d != 0.0:
                ft[i] = new
                vbx += g0 * d
                vby += g1 * d
                om += g2 * d
                change = max(change, abs(d) / lim)
        if change < 1e-6:
            break
    return vbx, vby, om


@implements("rigid_contact", FrictionKernel)
def rigid_contact(e, body, w, c, sn, any_c, vbx, vby, om, nm_eff):
    """Rigid model: the tangential forces of the contacting beads, solved together."""
    if any_c:
        vbx, vby, om = coulomb_friction(
            c, sn, body.s, nm_eff, w.fx, w.fy, e.mu_f, vbx, vby, om, e.tang
        )
    return vbx, vby, om


@implements("bead_forces", FrictionKernel)
def bead_forces(e, body, w, bw, any_c):
    """Bead-spring model: the rigid-body solve for the body the (nearly rigid) fiber moves as.

    Body frame from the end-to-end axis; frictionless body velocity P u_b + N (F_c, τ_c)
    with u_b the background velocities ``bw.f``; the tangential forces are added
    to the total forces ``w.fx, fy``.
    """
    if any_c:
        x = w.x
        y = w.y
        fx = w.fx
        fy = w.fy
        tang = e.tang
        cfx = bw.cfx
        cfy = bw.cfy
        n = x.shape[0]
        ex = x[n - 1] - x[0]
        ey = y[n - 1] - y[0]
        le = math.hypot(ex, ey)
        c = ex / le
        sn = ey / le
        vbx, vby, om = body_velocity(c, sn, body.s, body.pm, body.nm, bw.f, cfx, cfy, True)
        coulomb_friction(c, sn, body.s, body.nm, cfx, cfy, e.mu_f, vbx, vby, om, tang)
        for i in range(n):
            fn = math.hypot(cfx[i], cfy[i])
            if fn > 0.0:
                fx[i] += tang[i] * (-cfy[i] / fn)
                fy[i] += tang[i] * (cfx[i] / fn)
