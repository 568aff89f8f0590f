"""Observables of a run from its trajectory: thinning, contact, passing time, angles, stations.

Pure functions of a :class:`~fibersweep.analysis.trajectory.Trajectory` (or of its
time, centre and angle columns): the fiber run reads its contact angle and passing
time here, and the discrepancy workflow its track observables, for the model's runs
and the measured tracks alike (:func:`track_values`).

Track observables: where and how the centre crosses fixed stations in x
------------------------------------------------------------------------
:func:`station_crossings` turns a track (time, centre x, y, angle) into the time,
lateral position and angle at which the centre first crosses given x stations;
:func:`track_values` applies it at the stations of the track observables.

Tracks are in the model's channel frame [µm]: x along the flow (+x downstream), y
across it, the pillar where the flow settings put it (by default its centroid at
x = L_ch / 2 and its base line at y = W_ch / 2 - h_obs / 3;
:class:`fibersweep.units.Geometry`), the frame of :class:`Trajectory`. Stations
(centre x; the pillar's extent from its outline):

- ``in``: the pillar's upstream-most x;
- ``out``: the pillar's downstream-most x;
- ``far``: one fiber length downstream of ``out``.

The first crossing of station s is between the first consecutive samples with
``x[i] < s <= x[i+1]``; values there are interpolated linearly in x. A track that
starts at or past a station, or never reaches it (Trapping), has no value there
(NaN).
"""

from __future__ import annotations

import math
from typing import overload

import numpy as np

from fibersweep.analysis.classify import ClassifySettings, stopped_mask
from fibersweep.analysis.trajectory import Trajectory
from fibersweep.units import Geometry

__all__ = [
    "STATIONS",
    "fiber_angle",
    "first_contact_index",
    "pass_time",
    "station_crossings",
    "station_positions",
    "take",
    "thin_indices",
    "track_values",
]

#: Station names, in the order of :func:`station_positions`.
STATIONS = ("in", "out", "far")


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


@overload
def fiber_angle(theta_deg: float) -> float: ...


@overload
def fiber_angle(theta_deg: np.ndarray) -> np.ndarray: ...


def fiber_angle(theta_deg: float | np.ndarray) -> float | np.ndarray:
    """Undirected fiber angle in (−90, 90] degrees from a directed angle.

    Parameters
    ----------
    theta_deg : float or ndarray
        Directed angle [deg], wrapped or not; NaN stays NaN.

    Returns
    -------
    float or ndarray
        A float for a scalar, else an array of the same shape.
    """
    a = np.mod(np.asarray(theta_deg, dtype=np.float64) + 90.0, 180.0) - 90.0
    a = np.where(a == -90.0, 90.0, a)
    return float(a) if a.ndim == 0 else a


def station_crossings(
    t: np.ndarray, x: np.ndarray, y: np.ndarray, theta: np.ndarray, stations: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Time, lateral position and fiber angle where the centre first crosses each station.

    Parameters
    ----------
    t : ndarray, shape (m,)
        Sample times [s], increasing.
    x, y : ndarray, shape (m,)
        Centre of the fiber [µm].
    theta : ndarray, shape (m,)
        Fiber angle from +x [deg]; directed or not, wrapped or not (it is
        unwrapped with period 180° before interpolating).
    stations : ndarray, shape (k,)
        x of the stations [µm].

    Returns
    -------
    t_s, y_s, theta_s : ndarray, shape (k,)
        Crossing time [s], centre y [µm] and undirected angle in (-90, 90]
        [deg] (:func:`fiber_angle`) at each station, linearly interpolated
        between the two samples that bracket the first crossing
        ``x[i] < s <= x[i+1]``; NaN where the track starts at or past the
        station or never reaches it.
    """
    t, x, y = (np.asarray(a, dtype=np.float64) for a in (t, x, y))
    th = np.unwrap(np.asarray(theta, dtype=np.float64), period=180.0)
    s = np.atleast_1d(np.asarray(stations, dtype=np.float64))
    out = np.full((3, s.size), np.nan)
    if x.size < 2:
        return out[0], out[1], out[2]
    for j, sx in enumerate(s):
        up = (x[:-1] < sx) & (x[1:] >= sx)
        hits = np.flatnonzero(up)
        if not hits.size or x[0] >= sx:
            continue
        i = int(hits[0])
        f = (sx - x[i]) / (x[i + 1] - x[i])
        out[:, j] = [v[i] + f * (v[i + 1] - v[i]) for v in (t, y, th)]
    out[2] = fiber_angle(out[2])  # undirected, as the contact angle theta_c
    return out[0], out[1], out[2]


def station_positions(geometry: Geometry, length_um: float) -> np.ndarray:
    """x of the stations ``in``, ``out``, ``far`` [µm], shape (3,).

    Parameters
    ----------
    geometry : Geometry
        Channel and pillar of the model (its outline's bounds give the extent).
    length_um : float
        Fiber length [µm] (``far`` is one length past ``out``).
    """
    x0, _, x1, _ = geometry.shape.bounds
    return np.array([x0, x1, x1 + float(length_um)])


def track_values(
    t: np.ndarray,
    x: np.ndarray,
    y: np.ndarray,
    theta: np.ndarray,
    geometry: Geometry,
    length: float,
) -> dict[str, float]:
    """Values of the track observables of one fiber.

    Parameters
    ----------
    t, x, y, theta : ndarray, shape (m,)
        Track: time [s], centre [µm] in the channel frame, angle [deg].
    geometry : Geometry
        Channel and pillar (stations, base line, h_obs, l_obs).
    length : float
        Fiber length / l_obs.

    Returns
    -------
    dict name -> float
        ``y_in``, ``y_out``, ``y_far`` (centre y from the base line / h_obs),
        ``theta_in``, ``theta_out``, ``theta_far`` [deg] and ``t_transit`` (time
        from ``in`` to ``far`` [s]); NaN where a station is not reached.
    """
    if not math.isfinite(length):
        length = math.nan
    xs = station_positions(geometry, length * geometry.pillar_base_length)
    ts, ys, ths = station_crossings(t, x, y, theta, xs)
    yh = np.asarray(geometry.y_over_h(ys), dtype=np.float64)
    out: dict[str, float] = {}
    for k, name in enumerate(STATIONS):
        out[f"y_{name}"] = float(yh[k])
        out[f"theta_{name}"] = float(ths[k])
    out["t_transit"] = float(ts[2] - ts[0])
    return out
