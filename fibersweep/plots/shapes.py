"""The fiber as drawn: every bead of a flexible fiber, the straight rod of a rigid one.

Every figure that draws a fiber (chronophotographs, animations, the explorer)
takes its points from :func:`fiber_points`, so a bead-spring fiber is never drawn
as the chord between its ends: its stored beads (``fiber.record.all_beads``) are
drawn, all of them, or nothing is drawn and :class:`ShapeNotStored` says how to
get them.
"""

from __future__ import annotations

import math

import numpy as np

from fibersweep.errors import InputError

__all__ = ["ShapeNotStored", "fiber_points", "is_flexible", "shape_hint"]


class ShapeNotStored(InputError):
    """A bead-spring run whose bead positions were not kept: its shape cannot be drawn."""


def is_flexible(model: object) -> bool:
    """Whether ``model`` (a fiber model name) bends: any model but ``rigid``."""
    return bool(model) and str(model) != "rigid"


def shape_hint(what: str = "this run") -> str:
    """How to get the bead positions that drawing a flexible fiber needs."""
    return (
        f"{what} is a bead-spring fiber stored without its bead positions, so its shape "
        "cannot be drawn (a straight chord would cut through the pillar it bends around); "
        "run the sweep with fiber.record.all_beads=true (a setting of the run: new run ids, "
        "so into another output folder), or draw the one run with fibersweep simulate "
        "CONFIG --theta0 .. --y0 .. --length .. --plot FILE, which keeps them"
    )


def fiber_points(
    model: object,
    n_beads: int,
    beads: np.ndarray | None = None,
    *,
    centre: tuple[float, float] | None = None,
    angle: float | None = None,
    half_length: float | None = None,
    ends: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """Points of the fiber drawn at one sample, shape (m, 2) [µm].

    Parameters
    ----------
    model : str
        Fiber model of the run.
    n_beads : int
        Beads of the fiber.
    beads : ndarray, shape (n_beads, 2) or (2 n_beads,), optional
        Stored bead centres at this sample.
    centre, angle, half_length : optional
        A rigid rod by its centre [µm], angle [rad] and half length [µm] ...
    ends : (tail, head), optional
        ... or by its end beads [µm].

    Returns
    -------
    ndarray
        Every bead (m = n_beads) when they are stored; else, for a rigid fiber, its
        two ends (m = 2; from ``centre``, m = 1 for a one-bead sphere).

    Raises
    ------
    ShapeNotStored
        A flexible fiber without all its stored beads.
    """
    if beads is not None:
        pts = np.asarray(beads, dtype=np.float64).reshape(-1, 2)
        if n_beads and len(pts) != n_beads:
            raise ShapeNotStored(f"stored {len(pts)} bead positions for a fiber of {n_beads} beads")
        return pts
    if is_flexible(model):
        raise ShapeNotStored(shape_hint())
    if ends is not None:  # both ends, also for a sphere (a zero-length segment)
        tail, head = (np.asarray(e, dtype=np.float64) for e in ends)
        return np.vstack([tail, head])
    if centre is None or angle is None or half_length is None:
        raise ValueError("a rigid fiber needs its ends, or its centre, angle and half length")
    c, s = math.cos(angle), math.sin(angle)
    x, y = centre
    if n_beads == 1 or half_length == 0.0:
        return np.array([[x, y]])
    return np.array([[x - half_length * c, y - half_length * s],
                     [x + half_length * c, y + half_length * s]])  # fmt: skip
