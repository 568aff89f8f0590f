"""Classification of a fiber run as a pure function of its recorded trajectory.

Rules (SPEC section 4; thresholds in :class:`ClassifySettings`):

1. **Trapping**: the fiber is in contact and its centre of mass moves slower
   than ``trap_speed``·|U_center| for at least ``trap_time`` (consecutive
   samples, duration = last − first sample time of the run of such samples).
2. **Pole-vaulting**: while in contact the head (the bead that leads at the
   start) is blocked, speed below ``head_blocked_speed``·|U_center|, at some
   sample, and head and tail swap: the directed tail→head angle turns by more
   than 90° between the first and last sample.
3. Otherwise **Above** / **Below**: the side of the pillar centroid on which
   the centre of mass is when it crosses the centroid's x (first crossing in
   the flow direction).

A trajectory that neither crossed nor got trapped gives '' (undetermined).
The integrators call the same function on their full-resolution record; a
stored (thinned) trajectory keeps the samples these rules need, so
re-classifying with other thresholds needs no new simulation.
"""

from __future__ import annotations

import numpy as np

from fibersweep.fiber.result import Trajectory
from fibersweep.fiber.settings import ClassifySettings
from fibersweep.units import Geometry

__all__ = ["classify", "longest_run", "pass_crossing", "stopped_mask"]


def stopped_mask(traj: Trajectory, u_center: float, thresholds: ClassifySettings) -> np.ndarray:
    """Samples in contact and slower than the trap speed, shape (m,) bool."""
    contact = np.asarray(traj.contact, dtype=bool)
    return contact & (np.asarray(traj.com_speed) < thresholds.trap_speed * abs(u_center))


def longest_run(t: np.ndarray, mask: np.ndarray) -> float:
    """Longest duration [s] (last − first time) of consecutive True samples; 0 if none."""
    if not np.any(mask):
        return 0.0
    m = np.concatenate([[False], np.asarray(mask, dtype=bool), [False]])
    starts = np.flatnonzero(~m[:-1] & m[1:])
    ends = np.flatnonzero(m[:-1] & ~m[1:]) - 1
    return float(np.max(np.asarray(t)[ends] - np.asarray(t)[starts]))


def pass_crossing(traj: Trajectory, geometry: Geometry, u_center: float) -> float:
    """y [µm] of the centre of mass where it first crosses the pillar centroid's x; NaN if never."""
    xp = geometry.centroid[0]
    sign = 1.0 if u_center >= 0 else -1.0
    x = sign * (np.asarray(traj.x) - xp)
    idx = np.flatnonzero((x[:-1] < 0.0) & (x[1:] >= 0.0))
    if idx.size == 0:
        return float("nan")
    k = int(idx[0])
    w = -x[k] / (x[k + 1] - x[k])
    return float(traj.y[k] + w * (traj.y[k + 1] - traj.y[k]))


def classify(
    trajectory: Trajectory, geometry: Geometry, u_center: float, thresholds: ClassifySettings
) -> str:
    """Class of a run: 'Below', 'Above', 'Pole-vaulting', 'Trapping', or '' if undetermined.

    Parameters
    ----------
    trajectory : Trajectory
        Time-ordered samples (full resolution or thinned).
    geometry : Geometry
        Channel and pillar.
    u_center : float
        Centreline speed of the field the run used [µm/s] (its sign is the flow direction).
    thresholds : ClassifySettings
    """
    tr = trajectory
    if len(tr.t) < 2:
        return ""
    if longest_run(tr.t, stopped_mask(tr, u_center, thresholds)) >= thresholds.trap_time:
        return "Trapping"
    contact = np.asarray(tr.contact, dtype=bool)
    blocked = contact & (np.asarray(tr.head_speed) < thresholds.head_blocked_speed * abs(u_center))
    swapped = abs(float(tr.theta[-1]) - float(tr.theta[0])) > 90.0
    y_cross = pass_crossing(tr, geometry, u_center)
    if np.isnan(y_cross):
        return ""
    if np.any(blocked) and swapped:
        return "Pole-vaulting"
    return "Above" if y_cross > geometry.centroid[1] else "Below"
