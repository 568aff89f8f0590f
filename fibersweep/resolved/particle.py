"""A rigid resolved body (sphere or capsule), its state, and its explicit Newton–Euler update.

The body is a capsule: the points within ``radius`` of a segment of half-length
``half_length`` along its unit axis (a sphere when the half-length is 0; a
short rod with hemispherical ends otherwise). Lengths, velocities and forces
are in lattice units (Δx = Δt = ρ0 = 1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import lru_cache

import numpy as np

from fibersweep.resolved.lattice import body_vector

__all__ = ["Body", "BodyState", "advance", "MOTIONS"]

#: "free": force- and torque-free; "held": velocity and spin prescribed, geometry fixed;
#: "planar": free in x, y and about z only (a body on the mirror plane of a symmetric box);
#: "spin": held in place and orientation, its spin torque-free (the quasi-steady
#: rotation rate at that orientation).
MOTIONS = ("free", "held", "planar", "spin")


@dataclass(frozen=True)
class Body:
    """Shape and density of a rigid body.

    Attributes
    ----------
    radius : float
        Radius of the sphere or of the rod's cross-section and caps [lattice units].
    half_length : float
        Half-length of the rod's straight part (0: a sphere) [lattice units].
    density_ratio : float
        ρ_p/ρ_f (sets only the body's relaxation time, a Stokes number).
    """

    radius: float
    half_length: float = 0.0
    density_ratio: float = 1.0

    def __post_init__(self) -> None:
        if not (self.radius > 0 and self.half_length >= 0 and self.density_ratio > 0):
            raise ValueError("radius and density_ratio must be positive, half_length >= 0")

    @property
    def volume(self) -> float:
        a, ell = self.radius, self.half_length
        return 4.0 / 3.0 * math.pi * a**3 + math.pi * a * a * 2.0 * ell

    @property
    def mass(self) -> float:
        return self.density_ratio * self.volume

    def inertia(self) -> tuple[float, float]:
        """Moments of inertia about the axis and across it through the centre."""
        a, ell, rho = self.radius, self.half_length, self.density_ratio
        mc = rho * math.pi * a * a * 2.0 * ell
        mh = rho * 2.0 / 3.0 * math.pi * a**3  # one hemisphere
        i_ax = mc * a * a / 2.0 + 2.0 * mh * 2.0 / 5.0 * a * a
        i_cyl = mc * (a * a / 4.0 + (2.0 * ell) ** 2 / 12.0)
        # hemisphere about a diameter through its base: 2/5 m a²; moved by its centroid 3a/8
        d = 3.0 * a / 8.0
        i_h = 2.0 / 5.0 * mh * a * a - mh * d * d + mh * (ell + d) ** 2
        return i_ax, i_cyl + 2.0 * i_h

    @property
    def length(self) -> float:
        """Tip-to-tip length 2 (half_length + radius)."""
        return 2.0 * (self.half_length + self.radius)


@dataclass(frozen=True)
class BodyState:
    """Position and motion of a body.

    Attributes
    ----------
    x : ndarray, shape (3,)
        Centre, unwrapped (it keeps counting across periodic faces) [lattice units].
    p : ndarray, shape (3,)
        Unit axis.
    u, w : ndarray, shape (3,)
        Velocity and angular velocity [lattice units].
    """

    x: np.ndarray
    p: np.ndarray = field(default_factory=lambda: np.array([1.0, 0.0, 0.0]))
    u: np.ndarray = field(default_factory=lambda: np.zeros(3))
    w: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        for name in ("x", "p", "u", "w"):
            v = np.asarray(getattr(self, name), dtype=np.float64).reshape(3).copy()
            v.setflags(write=False)
            object.__setattr__(self, name, v)
        n = float(np.linalg.norm(self.p))
        if not n > 0:
            raise ValueError("the axis p must be nonzero")

    def vector(self, body: Body) -> np.ndarray:
        """The kernels' (14,) description of the body in this state."""
        return body_vector(self.x, self.p / np.linalg.norm(self.p), body.half_length,
                           body.radius, self.u, self.w)  # fmt: skip


def _rotate(p: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``p`` turned by the rotation vector ``w`` (Rodrigues), renormalised."""
    th = float(np.linalg.norm(w))
    if th == 0.0:
        return p
    k = w / th
    # np.cross, without its per-call checks
    kxp = np.array([k[1] * p[2] - k[2] * p[1], k[2] * p[0] - k[0] * p[2],
                    k[0] * p[1] - k[1] * p[0]])  # fmt: skip
    out = p * math.cos(th) + kxp * math.sin(th) + k * np.dot(k, p) * (1 - math.cos(th))
    return out / np.linalg.norm(out)


@lru_cache(maxsize=64)
def _inertia(body: Body) -> tuple[float, float]:
    return body.inertia()


_KEEP = {"planar": np.array([0, 1, 5]), "spin": np.arange(3, 6), "free": np.arange(6)}


def advance(body: Body, state: BodyState, force: np.ndarray, torque: np.ndarray,
            motion: str = "free", resistance: np.ndarray | None = None) -> BodyState:  # fmt: skip
    """One step (Δt = 1) of Newton–Euler for the body, its linear drag implicit.

    Solves (M + Z) V' = M V + (F, T) for V' = (U', Ω'), M = diag(m, m, m, I)
    (I the inertia tensor of the current axis; the gyroscopic term, O(Re), is
    left out), then moves the centre by U' and turns the axis by Ω'.

    Parameters
    ----------
    force, torque : ndarray, shape (3,)
        Force and torque on the body this step, less the part −Z V' (what is
        linear in the new velocity).
    motion : str
        One of :data:`MOTIONS`.
    resistance : ndarray, shape (6, 6), optional
        Z: the links' wall-velocity term and any lubrication correction.

    Returns
    -------
    BodyState
        The new state (``held``: unchanged).
    """
    if motion not in MOTIONS:
        raise ValueError(f"motion must be one of {MOTIONS}, got {motion!r}")
    if motion == "held":
        return state
    i_ax, i_perp = _inertia(body)
    p = state.p / np.linalg.norm(state.p)
    mass = np.zeros((6, 6))
    idx = np.arange(3)
    mass[idx, idx] = body.mass
    mass[3:, 3:] = (i_ax - i_perp) * (p[:, None] * p[None, :])
    mass[idx + 3, idx + 3] += i_perp
    lhs = mass + (resistance if resistance is not None else 0.0)
    rhs = mass @ np.concatenate([state.u, state.w]) + np.concatenate([force, torque])
    keep = _KEEP[motion]
    v = np.zeros(6)
    v[keep] = np.linalg.solve(lhs[keep[:, None], keep[None, :]], rhs[keep])
    u, w = v[:3], v[3:]
    if motion == "spin":
        return replace(state, w=w)
    return replace(state, x=state.x + u, p=_rotate(p, w), u=u, w=w)
