"""The fluid of a resolved-particle run: populations on a box, one step, the checked kernel calls.

TRT collision with the "magic" Λ = 3/16, so that half-way and interpolated
bounce-back put walls where they are independently of the viscosity; Guo
forcing with a uniform body force; density ρ0 = 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from fibersweep.flow.lattice import E, W
from fibersweep.resolved import kernels, kernels_blocked
from fibersweep.resolved.box import Box, pillar_links, pull_table

__all__ = ["FluidSettings", "Lattice", "body_vector", "SERIAL_BELOW"]

#: Boxes with fewer nodes run on one thread: on a shared machine the fork/join of
#: the parallel loops costs more than it gains (measured 30x slower at 2000 nodes).
SERIAL_BELOW = 200_000


@dataclass(frozen=True)
class FluidSettings:
    """Relaxation of the lattice fluid.

    Attributes
    ----------
    tau : float
        Relaxation time of the even moments; kinematic viscosity ν = (τ − ½)/3.
    magic : float
        TRT product Λ = (τ − ½)(τ⁻ − ½) (3/16: walls at the viscosity-independent place).
    """

    tau: float = 1.0
    magic: float = 3.0 / 16.0

    def __post_init__(self) -> None:
        if not self.tau > 0.5:
            raise ValueError(f"tau must exceed 1/2, got {self.tau}")

    @property
    def nu(self) -> float:
        """Kinematic viscosity [lattice units]."""
        return (self.tau - 0.5) / 3.0

    @property
    def rates(self) -> tuple[float, float]:
        """(ω+, ω−)."""
        tm = self.magic / (self.tau - 0.5) + 0.5
        return 1.0 / self.tau, 1.0 / tm


def body_vector(centre, axis, half_length, radius, velocity, spin) -> np.ndarray:
    """The (14,) body description the particle kernels take (lattice units)."""
    out = np.empty(14)
    out[0:3] = centre
    out[3:6] = axis
    out[6] = half_length
    out[7] = radius
    out[8:11] = velocity
    out[11:14] = spin
    return out


class Lattice:
    """Populations of a :class:`~fibersweep.resolved.box.Box`, stepped with a body force.

    Parameters
    ----------
    box : Box
    fluid : FluidSettings
    force : array_like, shape (3,)
        Body force density on the fluid [lattice units].
    blocked : bool
        True: the blocked collision and row-wise streaming of
        :mod:`fibersweep.resolved.kernels_blocked`; False: the node-wise reference
        kernels of :mod:`fibersweep.resolved.kernels` (equal to round-off; kept for
        the tests and the benchmark; also used for rows shorter than 3 nodes).
    threads : int, optional
        Threads of the parallel kernels; default one below :data:`SERIAL_BELOW`
        nodes, else Numba's thread count.
    """

    def __init__(self, box: Box, fluid: FluidSettings, force=(0.0, 0.0, 0.0), *,
                 blocked: bool = True, threads: int | None = None) -> None:  # fmt: skip
        self.box = box
        self.fluid = fluid
        self.force = np.asarray(force, dtype=np.float64).reshape(3)
        self.blocked = blocked and box.nx >= 3  # a row needs an interior
        self.src = pull_table(box)
        self.rows = kernels_blocked.row_table(self.src, box.nx) if self.blocked else None
        self.links = pillar_links(box)
        self.flags = box.solid_flags()
        self.f = np.repeat(W[:, None], box.nodes, axis=1).astype(np.float64)
        self.fn = self.f.copy()
        self.steps = 0
        if threads is None:
            threads = 1 if box.nodes < SERIAL_BELOW else numba.config.NUMBA_NUM_THREADS
        self.threads = int(threads)
        self._rates = fluid.rates
        b = box
        self.dims = np.array([b.nx, b.ny, b.nz, b.shift, int(b.periodic_y),
                              int(b.z_mode == "periodic"), int(b.z_mode == "symmetric")],
                             dtype=np.int64)  # fmt: skip

    def step(self, body: np.ndarray | None = None) -> np.ndarray:
        """One collide-stream step; with ``body`` (14,) the particle's links too.

        Returns
        -------
        ndarray, shape (43,)
            The particle's hydrodynamic force (3), torque about its centre (3), link
            count and its links' 6 × 6 velocity matrix (row-major), for the solved
            part of the box (:func:`fibersweep.resolved.kernels.particle_links`;
            zeros without a body).
        """
        out = np.zeros(43)
        numba.set_num_threads(self.threads)
        om_p, om_m = self._rates
        if self.blocked:
            kernels_blocked.collide_blocked(self.f, self.flags, self.force, om_p, om_m)
            kernels_blocked.stream_rows(self.f, self.fn, self.rows, self.src,
                                        self.box.wall_velocity)  # fmt: skip
        else:
            kernels.collide(self.f, self.flags, self.force, om_p, om_m)
            kernels.stream(self.f, self.fn, self.src, self.flags, self.box.wall_velocity)
        node, q, t, beyond = self.links
        if node.size:
            kernels.static_links(self.f, self.fn, self.flags, node, q, t, beyond)
        if body is not None:
            kernels.particle_links(self.f, self.fn, self.flags, self.dims, _checked(body), out)
        self.f, self.fn = self.fn, self.f
        self.steps += 1
        return out

    def place(self, body: np.ndarray, reach: float) -> np.ndarray:
        """Update which nodes the body covers (moved at most ``reach``); (6,) impulse to it."""
        out = np.zeros(6)
        kernels.refill(self.f, self.flags, self.dims, _checked(body), float(reach), out)
        return out

    def velocity(self) -> tuple[np.ndarray, np.ndarray]:
        """Density, shape (nz, ny, nx), and velocity, shape (3, nz, ny, nx); zero off the fluid."""
        N = self.box.nodes
        rho, u = np.empty(N), np.empty((3, N))
        numba.set_num_threads(self.threads)
        kernels.moments(self.f, self.flags, self.force, rho, u)
        shp = (self.box.nz, self.box.ny, self.box.nx)
        return rho.reshape(shp), u.reshape((3, *shp))

    def init_velocity(self, u: np.ndarray) -> None:
        """Start from the equilibrium at velocity ``u`` (3, nz, ny, nx) and unit density."""
        uu = np.asarray(u, dtype=np.float64).reshape(3, -1)
        if uu.shape[1] != self.box.nodes:
            raise ValueError("u must have shape (3, nz, ny, nx) of the box")
        eu = E.astype(np.float64) @ uu
        usq = 1.5 * (uu * uu).sum(axis=0)
        self.f[:] = W[:, None] * (1.0 + 3.0 * eu + 4.5 * eu * eu - usq[None, :])
        self.f[:, self.flags == 1] = W[:, None]


def _checked(body: np.ndarray) -> np.ndarray:
    body = np.ascontiguousarray(body, dtype=np.float64)
    if body.shape != (14,):
        raise ValueError(f"body must have shape (14,), got {body.shape}")
    return body
