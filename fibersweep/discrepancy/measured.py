"""Measured data from disk: the fibers table and its optional trajectories.

:func:`load_measured` reads and validates the fibers table (its schema is in
:mod:`fibersweep.discrepancy.schema`) and, when given, the trajectories, from
which the track observables are derived.

Trajectories (optional second table): columns ``fiber_id, t [s], x [µm],
y [µm], theta [deg]``, rows time-ordered per fiber; every fiber_id must be in
the fibers table, and every fiber of the table needs a track. ``x, y`` are the
fiber's centre in the model's channel frame: x along the flow (+x
downstream), y across it, the pillar where the config's flow geometry puts it
(by default its centroid at x = L_ch/2 = 1200 µm, its base line at
y = W_ch/2 - h_obs/3 = 375 µm, spanning x = 1156.7 .. 1243.3 µm); ``theta``
is the fiber's angle from +x (directed or not). From them the track
observables (``y_out``, ``theta_out``, ``t_transit``;
:func:`fibersweep.analysis.observables.track_values`) are derived and compared; each
track must run from upstream of the pillar to one fiber length past it (a Trapping
fiber's track may stop anywhere: its track observables are NaN).

Without an ``angle_unit`` column in the fibers table, the tracks' theta is
taken for radians when their first samples match theta0 converted to radians
far better than theta0 itself. Every problem raises :class:`InputError` naming
the column, the rule and the rows (first few, 0-based).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from fibersweep.analysis.observables import station_positions, track_values
from fibersweep.discrepancy.observables import OBSERVABLES, track_observables
from fibersweep.discrepancy.schema import MeasuredData, read_table, rows_text, validate_measured
from fibersweep.errors import InputError
from fibersweep.units import Geometry

__all__ = [
    "TRAJECTORY_COLUMNS",
    "load_measured",
    "measured_track_values",
    "validate_trajectories",
    "with_tracks",
]

TRAJECTORY_COLUMNS = ("fiber_id", "t", "x", "y", "theta")


def _trajectory_radians(traj: pd.DataFrame, fibers: pd.DataFrame) -> str | None:
    """Why the trajectories' theta looks like radians, judged against theta0 [deg]."""
    first = traj.groupby("fiber_id", sort=False)["theta"].first()
    theta0 = fibers.set_index("fiber_id")["theta0"].reindex(first.index).to_numpy()
    th = first.to_numpy()
    ok = np.isfinite(theta0) & np.isfinite(th)
    if ok.sum() < 3 or np.max(np.abs(theta0[ok])) < 1.0:
        return None  # starts too close to 0 to tell degrees from radians
    miss_deg = float(np.median(np.abs(th[ok] - theta0[ok])))
    miss_rad = float(np.median(np.abs(th[ok] - np.radians(theta0[ok]))))
    if miss_rad < 0.2 * miss_deg:
        return (
            f"the first sample of each track matches theta0 in radians (median miss "
            f"{miss_rad:.3g}) far better than theta0 in degrees ({miss_deg:.3g})"
        )
    return None


def validate_trajectories(
    traj: pd.DataFrame, fibers: pd.DataFrame | pd.Series, source: str
) -> pd.DataFrame:
    """Check the optional trajectory table (see module docstring).

    Parameters
    ----------
    traj : pandas.DataFrame
        Raw trajectory table.
    fibers : pandas.DataFrame or pandas.Series
        The validated fibers table (``fiber_id`` and ``theta0`` [deg], used for
        the radians check), or only its ``fiber_id`` column.
    source : str
        Name used in messages.

    Raises
    ------
    InputError
        Missing columns, non-finite values, unknown fiber ids, times that go
        backwards, or angles that look like radians, each naming the rows.
    """
    fiber_ids = fibers["fiber_id"] if isinstance(fibers, pd.DataFrame) else fibers
    missing = [c for c in TRAJECTORY_COLUMNS if c not in traj.columns]
    if missing:
        raise InputError(f"{source}: trajectories: missing column(s) {', '.join(missing)}")
    traj = traj.reset_index(drop=True).copy()
    traj["fiber_id"] = traj["fiber_id"].astype(str)
    problems = []
    for col in ("t", "x", "y", "theta"):
        v = pd.to_numeric(traj[col], errors="coerce").to_numpy(dtype=np.float64)
        bad = ~np.isfinite(v)
        if bad.any():
            problems.append(f"trajectories.{col}: non-finite or non-numeric in {rows_text(bad)}")
        traj[col] = v
    unknown = ~traj["fiber_id"].isin(set(fiber_ids.astype(str)))
    if unknown.any():
        problems.append(f"trajectories.fiber_id: not in the fibers table in {rows_text(unknown)}")
    if not problems:
        back = (traj.groupby("fiber_id", sort=False)["t"].diff() <= 0).to_numpy()
        if back.any():
            problems.append(f"trajectories.t: not increasing within a fiber in {rows_text(back)}")
    if not problems and isinstance(fibers, pd.DataFrame) and "theta0" in fibers.columns:
        why = _trajectory_radians(traj, fibers)
        if why:
            problems.append(
                f"trajectories.theta: {why}; these look like radians, but degrees are "
                "expected. Convert to degrees"
            )
    if problems:
        raise InputError(f"{source}: " + "; ".join(problems))
    return traj


def with_tracks(
    data: MeasuredData, traj: pd.DataFrame, geometry: Geometry, source: str = "trajectories"
) -> MeasuredData:
    """``data`` with its validated trajectories and the track observables derived from them.

    Parameters
    ----------
    data : MeasuredData
        Validated fibers.
    traj : pandas.DataFrame
        Validated trajectories (:func:`validate_trajectories`), channel frame [µm].
    geometry : Geometry
        Channel and pillar of the model.
    source : str
        Name used in messages.

    Raises
    ------
    InputError
        Fibers without a track, tracks that do not cross the stations (e.g. in
        another frame), each naming the field
        (:func:`measured_track_values`).
    """
    values = measured_track_values(traj, data.table, geometry, source)
    table = pd.concat([data.table, values], axis=1)
    observed = (*data.observed, *(n for n in values.columns if OBSERVABLES[n].scored))
    return MeasuredData(table, observed, traj, data.source)


def _values_of(mapping: dict[str, float], names: tuple[str, ...]) -> list[float]:
    """``mapping[name]`` for each name (NaN where absent)."""
    return [float(mapping.get(n, math.nan)) for n in names]


def measured_track_values(
    traj: pd.DataFrame, fibers: pd.DataFrame, geometry: Geometry, source: str
) -> pd.DataFrame:
    """Track observables of measured fibers from their validated trajectories.

    Parameters
    ----------
    traj : pandas.DataFrame
        Validated trajectories (:func:`validate_trajectories`):
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
        rows.append(_values_of(v, names))
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


def load_measured(
    path: str | Path,
    trajectories: str | Path | None = None,
    ignore_extra: bool = False,
    geometry: Geometry | None = None,
) -> MeasuredData:
    """Read and validate a measured-fiber table (and optionally its trajectories).

    Parameters
    ----------
    path : path
        ``.parquet`` or ``.csv`` file following :mod:`fibersweep.discrepancy.schema`.
    trajectories : path, optional
        ``.parquet`` or ``.csv`` trajectory table; the track observables are
        derived from it (:func:`with_tracks`).
    ignore_extra : bool
        Ignore columns the schema does not know instead of raising.
    geometry : Geometry, optional
        Channel and pillar of the model, the frame of the tracks (required with
        ``trajectories``).

    Raises
    ------
    InputError
        Unreadable file or any schema violation (naming columns and rows).
    """
    p = Path(path)
    if not p.exists():
        raise InputError(f"{p}: no such file")
    data = validate_measured(read_table(p), source=str(p), ignore_extra=ignore_extra)
    if trajectories is not None:
        tp = Path(trajectories)
        if not tp.exists():
            raise InputError(f"{tp}: no such file")
        if geometry is None:
            raise ValueError("load_measured: trajectories need the model's geometry")
        traj = validate_trajectories(read_table(tp), data.table, str(tp))
        data = with_tracks(data, traj, geometry, str(tp))
    return data
