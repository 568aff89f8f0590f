"""The coupled time loop: a lattice and one body stepped together, with a record of its path.

Per step: collide, stream, bounce the body's links (force and torque by
momentum exchange), then move the body, its links' velocity term implicit
(Ladd & Verberg 2001), and refill the nodes it uncovered and hand the body
the momentum of those it covered (Aidun, Lu & Ding 1998).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from fibersweep.resolved.lattice import Lattice
from fibersweep.resolved.particle import Body, BodyState, advance

__all__ = ["Coupled", "Record"]

log = logging.getLogger(__name__)

_SEL = np.array([0, 1, 5])  # in-plane force, z torque: what a mirror-plane body keeps
_SEL2 = (_SEL[:, None], _SEL[None, :])

#: An external action on the body: state -> (force (3,), torque (3,), resistance (3, 3) or None).
External = Callable[[BodyState], tuple[np.ndarray, np.ndarray, np.ndarray | None]]


@dataclass(frozen=True)
class Record:
    """A body's path: one row per recorded step.

    Attributes
    ----------
    step : ndarray, shape (m,)
    x, p, u, w, force, torque : ndarray, shape (m, 3)
        Centre (unwrapped), axis, velocity, spin, hydrodynamic force and torque.
    seconds : float
        Wall time of the loop.
    """

    step: np.ndarray
    x: np.ndarray
    p: np.ndarray
    u: np.ndarray
    w: np.ndarray
    force: np.ndarray
    torque: np.ndarray
    seconds: float


class Coupled:
    """A lattice and one resolved body.

    Parameters
    ----------
    lattice : Lattice
    body : Body
    state : BodyState
    motion : str
        "free", "held" or "planar" (:data:`fibersweep.resolved.particle.MOTIONS`);
        a symmetric box needs "planar" or "held" with the centre on its top plane.
    external : callable, optional
        Contact and lubrication forces (:data:`External`).
    constrain : callable, optional
        state -> state applied after each move (a hard contact: keeps a least gap).
    """

    def __init__(self, lattice: Lattice, body: Body, state: BodyState, motion: str = "free",
                 external: External | None = None,
                 constrain: Callable[[BodyState], BodyState] | None = None) -> None:  # fmt: skip
        self.lattice, self.body, self.state, self.motion = lattice, body, state, motion
        self.external, self.constrain = external, constrain
        self.symmetric = lattice.box.z_mode == "symmetric"
        if self.symmetric:
            if motion == "free":
                raise ValueError("a body on the mirror plane moves 'planar' (or is 'held')")
            if abs(state.x[2] - lattice.box.nz) > 1e-9 or abs(state.p[2]) > 1e-12:
                raise ValueError("in a symmetric box the body's centre and axis lie on z = nz")
        self._impulse = np.zeros(6)
        lattice.place(state.vector(body), 0.0)

    def _full(self, out: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Force and torque (6,) and the 6 × 6 link matrix of the whole body."""
        ft = out[0:6].copy()
        z = out[7:43].reshape(6, 6).copy() if out.size >= 43 else np.zeros((6, 6))
        if self.symmetric:  # the mirror half acts alike: in-plane force and z torque double
            ft2, z2 = np.zeros(6), np.zeros((6, 6))
            ft2[_SEL] = 2 * ft[_SEL]
            z2[_SEL2] = 2 * z[_SEL2]
            ft, z = ft2, z2
        return ft, z

    def step(self) -> tuple[np.ndarray, np.ndarray]:
        """One coupled step; returns the hydrodynamic force and torque of the step.

        The links' wall-velocity term is taken implicitly (Ladd & Verberg 2001):
        the measured force holds −Z V of the old velocity, so the body solves
        (M + Z) V' = M V + F + Z V, stable for a neutrally buoyant body.
        """
        st = self.state
        out = self.lattice.step(st.vector(self.body))
        ft, z = self._full(out)
        if self.motion != "held":
            imp = self._impulse
            if self.symmetric:
                imp = np.zeros(6)
                imp[_SEL] = 2 * self._impulse[_SEL]
            v_old = np.concatenate([st.u, st.w])
            total = ft + imp + z @ v_old
            res = z
            if self.external is not None:
                ef, et, lub = self.external(st)
                total = total + np.concatenate([ef, et])
                if lub is not None:
                    res = res.copy()
                    res[:3, :3] += lub
            self.state = advance(self.body, st, total[:3], total[3:], self.motion, res)
            if self.constrain is not None:
                self.state = self.constrain(self.state)
            reach = float(np.linalg.norm(self.state.x - st.x)) + 1e-9
            self._impulse = self.lattice.place(self.state.vector(self.body), reach)
        return ft[:3], ft[3:]

    def run(self, steps: int, every: int = 10, stop: Callable[[BodyState], bool] | None = None
            ) -> Record:  # fmt: skip
        """Step ``steps`` times, recording every ``every`` steps; ``stop(state)`` ends early."""
        rows: list[tuple] = []
        t0 = time.perf_counter()
        for s in range(1, steps + 1):
            f, t = self.step()
            if s % every == 0 or s == steps:
                st = self.state
                rows.append((self.lattice.steps, st.x, st.p, st.u, st.w, f, t))
                if not np.all(np.isfinite(st.u)) or np.abs(st.u).max() > 0.1:
                    raise FloatingPointError(f"body velocity {st.u} at step {s}: unstable")
                if stop is not None and stop(st):
                    break
        secs = time.perf_counter() - t0
        log.info("%d steps in %.1f s", s, secs)
        cols = list(zip(*rows, strict=True))
        return Record(np.array(cols[0]), *(np.array(c) for c in cols[1:]), seconds=secs)
