"""Observables of a run from its trajectory: thinning, first contact, passing time, angles."""

from __future__ import annotations

import math

import numpy as np

from fibersweep.analysis.classify import ClassifySettings, stopped_mask
from fibersweep.analysis.trajectory import Trajectory

__all__ = [
    "fiber_angle",
    "first_contact_index",
    "pass_time",
    "take",
    "thin_indices",
]


def take(traj: Trajectory, idx: np.ndarray) -> Trajectory:
    """The samples ``idx`` of a trajectory."""
    return Trajectory(
        t=traj.t[idx],
        x=traj.x[idx],
        y=traj.y[idx],
        theta=traj.theta[idx],
        head=traj.head[idx],
        tail=traj.tail[idx],
        head_speed=traj.head_speed[idx],
        com_speed=traj.com_speed[idx],
        contact=traj.contact[idx],
        beads=None if traj.beads is None else traj.beads[idx],
    )


def _transitions(mask: np.ndarray) -> np.ndarray:
    """Indices on both sides of every change of a boolean series."""
    k = np.flatnonzero(mask[1:] != mask[:-1])
    return np.union1d(k, k + 1)


def thin_indices(
    traj: Trajectory, samples: int, u_center: float, thresholds: ClassifySettings
) -> np.ndarray:
    """About ``samples`` sample indices that keep what classification needs.

    Kept: first and last sample; both sides of every change of the contact flag
    and of the 'stopped in contact' flag (at most a quarter of the budget,
    evenly chosen); and one sample per uniform time bin: the slowest-head sample
    if the bin has contact (blocked-head evidence), else the bin's first.
    """
    m = len(traj.t)
    if m <= samples:
        return np.arange(m)
    keep = [np.array([0, m - 1])]
    events = np.union1d(
        _transitions(np.asarray(traj.contact, dtype=bool)),
        _transitions(stopped_mask(traj, u_center, thresholds)),
    )
    budget = max(samples // 4, 2)
    if events.size > budget:
        events = events[np.linspace(0, events.size - 1, budget).round().astype(int)]
    keep.append(events)
    nbins = max(samples - 2 - events.size, 1)
    edges = np.linspace(traj.t[0], traj.t[-1], nbins + 1)
    b = np.clip(np.searchsorted(edges, traj.t, side="right") - 1, 0, nbins - 1)
    starts = np.flatnonzero(np.r_[True, b[1:] != b[:-1]])
    ends = np.r_[starts[1:], m]
    hs = np.where(traj.contact, traj.head_speed, np.inf)
    picks = np.empty(starts.size, dtype=np.int64)
    for k, (s0, s1) in enumerate(zip(starts, ends, strict=True)):
        seg = hs[s0:s1]
        picks[k] = s0 + int(np.argmin(seg)) if np.isfinite(seg).any() else s0
    keep.append(picks)
    return np.unique(np.concatenate(keep))


def first_contact_index(traj: Trajectory) -> int | None:
    """Index of the first sample with contact, or None."""
    k = np.flatnonzero(traj.contact)
    return int(k[0]) if k.size else None


def pass_time(traj: Trajectory, x_pass: float, u_center: float) -> float:
    """First time [s] the rearmost bead is past ``x_pass`` in the flow direction; NaN if never."""
    sign = 1.0 if u_center >= 0 else -1.0
    rear = np.minimum(sign * traj.head[:, 0], sign * traj.tail[:, 0])
    k = np.flatnonzero(rear > sign * x_pass)
    return float(traj.t[k[0]]) if k.size else math.nan


def fiber_angle(theta_deg: float) -> float:
    """Undirected fiber angle in (−90, 90] degrees from a directed angle."""
    a = (theta_deg + 90.0) % 180.0 - 90.0
    return 90.0 if a == -90.0 else float(a)
