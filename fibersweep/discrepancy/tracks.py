"""Observables of a fiber's track: where and how it crosses fixed stations in x.

One pure function, :func:`station_crossings`, turns a track (time, centre
x, y, angle) into the time, lateral position and angle at which the centre
first crosses given x stations; :func:`track_values` applies it at the
stations of the track observables. The same two functions serve the measured
tracks (``fibersweep discrepancy --trajectories``, in
:mod:`fibersweep.discrepancy.schema`) and the model's runs
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
from collections.abc import Mapping

import numpy as np
import pandas as pd

from fibersweep.discrepancy.observables import OBSERVABLES, track_observables
from fibersweep.errors import InputError
from fibersweep.fiber.effects.pillar_scale import scaled_track
from fibersweep.units import Geometry

__all__ = [
    "STATIONS",
    "measured_track_values",
    "nominal_track",
    "station_crossings",
    "station_positions",
    "track_values",
]

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


def values_of(mapping: Mapping[str, float], names: tuple[str, ...]) -> list[float]:
    """``mapping[name]`` for each name (NaN where absent)."""
    return [float(mapping.get(n, math.nan)) for n in names]


#: Positions of a ``pillar_scale`` run as a camera sees them; the effect applies it
#: itself (:meth:`~fibersweep.fiber.effects.pillar_scale.PillarScale.transform_result`),
#: kept here under its old name.
nominal_track = scaled_track


def measured_track_values(
    traj: pd.DataFrame, fibers: pd.DataFrame, geometry: Geometry, source: str
) -> pd.DataFrame:
    """Track observables of measured fibers from their validated trajectories.

    Parameters
    ----------
    traj : pandas.DataFrame
        Validated trajectories (``measured_tracks.validate_trajectories``):
        ``fiber_id`` (str), ``t`` [s], ``x``, ``y`` [µm, channel frame], ``theta`` [deg].
    fibers : pandas.DataFrame
        Validated fibers table: ``fiber_id``, ``length`` [/l_obs], ``class``.
    geometry : Geometry
        Channel and pillar of the model (the frame of the tracks).
    source : str
        Name used in messages.

    Returns
    -------
    pandas.DataFrame
        One row per fiber (the order of ``fibers``), one column per track observable
        of the registry; NaN for Trapping.

    Raises
    ------
    InputError
        A fiber without a track (tracks must be given for every fiber or none), or a
        fiber that is not Trapping whose track does not cross a station (wrong
        frame, a track that starts too late or stops too early), or a value out of
        its plausible range; each names the field and the fibers.
    """
    names = track_observables()
    ids = fibers["fiber_id"].astype(str).to_numpy()
    groups = {k: g for k, g in traj.groupby("fiber_id", sort=False)}
    lacking = [i for i in ids if i not in groups]
    if lacking:
        raise InputError(
            f"{source}: trajectories.fiber_id: no track for {len(lacking)} of {len(ids)} fibers "
            f"({_few(lacking)}); give a track for every fiber of the table, or leave "
            "--trajectories out"
        )
    trapped = (fibers["class"] == "Trapping").to_numpy()
    lengths = fibers["length"].to_numpy(dtype=np.float64)
    rows = []
    for i, fid in enumerate(ids):
        if trapped[i]:
            rows.append([math.nan] * len(names))
            continue
        g = groups[fid]
        v = track_values(
            g["t"].to_numpy(), g["x"].to_numpy(), g["y"].to_numpy(), g["theta"].to_numpy(),
            geometry, float(lengths[i]),
        )  # fmt: skip
        rows.append(values_of(v, names))
    out = pd.DataFrame(rows, columns=list(names), index=fibers.index)
    gone = out.isna().any(axis=1).to_numpy() & ~trapped
    if gone.any():
        xs = station_positions(geometry, geometry.pillar_base_length)
        raise InputError(
            f"{source}: trajectories: the track of {gone.sum()} fiber(s) that are not Trapping "
            f"({_few(ids[gone])}) does not cross every station: the centre must go from "
            f"upstream of the pillar (x < {xs[0]:.1f} µm) to one fiber length past it "
            f"(x > {xs[1]:.1f} µm + the length). Tracks are in µm in the model's channel frame "
            f"(pillar from x = {xs[0]:.1f} to {xs[1]:.1f} µm, base line y = "
            f"{geometry.base_center[1]:.1f} µm, flow along +x)"
        )
    for name in names:
        lo, hi = OBSERVABLES[name].bounds or (-math.inf, math.inf)
        v = out[name].to_numpy()
        bad = np.isfinite(v) & ((v < lo) | (v > hi))
        if bad.any():
            raise InputError(
                f"{source}: trajectories: {name} out of range [{lo:g}, {hi:g}] for "
                f"{_few(ids[bad])} (e.g. {v[bad][0]:.4g}); {OBSERVABLES[name].unit_hint}"
            )
    return out


def _few(ids, most: int = 5) -> str:
    ids = [str(i) for i in ids]
    more = f" and {len(ids) - most} more" if len(ids) > most else ""
    return f"fiber_id {', '.join(ids[:most])}{more}"
