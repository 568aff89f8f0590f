"""A run's trajectory and the class names: what the analysis functions work on.

The fiber integrators fill a :class:`Trajectory` (``fibersweep.fiber``), the
sweep stores it, and classification and observables read it; it lives here so
that the analysis depends on nothing of the simulation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["CLASSES", "Trajectory"]

#: The four classes of the source, in its order.
CLASSES = ("Below", "Above", "Pole-vaulting", "Trapping")


@dataclass(frozen=True)
class Trajectory:
    """Thinned record of a run (time-ordered samples).

    Attributes
    ----------
    t : ndarray, shape (m,)
        Time [s].
    x, y : ndarray, shape (m,)
        Centre of mass [µm].
    theta : ndarray, shape (m,)
        Directed angle of the tail-to-head vector from +x, unwrapped [degrees];
        the head is the bead that leads at the start (so theta starts at theta0).
    head : ndarray, shape (m, 2)
        Head bead position [µm].
    tail : ndarray, shape (m, 2)
        Tail bead position [µm].
    head_speed : ndarray, shape (m,)
        Head bead speed [µm/s].
    com_speed : ndarray, shape (m,)
        Centre-of-mass speed [µm/s].
    contact : ndarray, shape (m,), bool
        Contact force non-zero at the sample.
    beads : ndarray or None, shape (m, n, 2)
        All bead positions [µm] when recorded.
    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    theta: np.ndarray
    head: np.ndarray
    tail: np.ndarray
    head_speed: np.ndarray
    com_speed: np.ndarray
    contact: np.ndarray
    beads: np.ndarray | None = None

    def columns(self) -> dict[str, np.ndarray]:
        """Flat columns for a table (beads excluded; see ``beads``)."""
        return {
            "t": self.t,
            "x": self.x,
            "y": self.y,
            "theta": self.theta,
            "head_x": self.head[:, 0],
            "head_y": self.head[:, 1],
            "tail_x": self.tail[:, 0],
            "tail_y": self.tail[:, 1],
            "head_speed": self.head_speed,
            "com_speed": self.com_speed,
            "contact": self.contact,
        }
