"""Observables of a fiber's track: where and how it crosses fixed stations in x.

One pure function, :func:`station_crossings`, turns a track (time, centre
x, y, angle) into the time, lateral position and angle at which the centre
first crosses given x stations; :func:`track_values` applies it at the
stations of the track observables. The same two functions serve the measured
tracks (``fibersweep discrepancy --trajectories``, in
:mod:`fibersweep.discrepancy.measured`) and the model's runs
(:func:`fibersweep.discrepancy.simulate.outcome_row`, from
``RunResult.trajectory``), so both sides are derived identically.

Frame
-----
Tracks are in the model's channel frame [µm]: x along the flow (+x
downstream), y across it, the pillar where the flow settings put it (by
default its centroid at x = L_ch / 2 and its base line at
y = W_ch / 2 - h_obs / 3; :class:`fibersweep.units.Geometry`). This is
the frame of :class:`~fibersweep.analysis.trajectory.Trajectory`.

Stations (centre x; the pillar's extent from its outline)
---------------------------------------------------------
- ``in``: the pillar's upstream-most x;
- ``out``: the pillar's downstream-most x;
- ``far``: one fiber length downstream of ``out``.

The first crossing of station s is between the first consecutive samples with
``x[i] < s <= x[i+1]``; values there are interpolated linearly in x. A track
that starts at or past a station, or never reaches it (Trapping), has no value
there (NaN).
"""

from __future__ import annotations

import math

import numpy as np

from fibersweep.units import Geometry

__all__ = ["STATIONS", "station_crossings", "station_positions", "track_values"]

#: Station names, in the order of :func:`station_positions`.
STATIONS = ("in", "out", "far")


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
        [deg] at each station, linearly interpolated between the two samples
        that bracket the first crossing ``x[i] < s <= x[i+1]``; NaN where the
        track starts at or past the station or never reaches it.
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
    a = (out[2] + 90.0) % 180.0 - 90.0  # undirected, as the contact angle theta_c
    out[2] = np.where(a == -90.0, 90.0, a)
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
