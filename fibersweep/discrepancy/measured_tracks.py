"""Measured trajectories: the optional second table, its checks, and the track observables.

Trajectories (optional second table): columns ``fiber_id, t [s], x [µm],
y [µm], theta [deg]``, rows time-ordered per fiber; every fiber_id must be in
the fibers table, and every fiber of the table needs a track. ``x, y`` are the
fiber's centre in the model's channel frame: x along the flow (+x
downstream), y across it, the pillar where the config's flow geometry puts it
(by default its centroid at x = L_ch/2 = 1200 µm, its base line at
y = W_ch/2 - h_obs/3 = 375 µm, spanning x = 1156.7 .. 1243.3 µm); ``theta``
is the fiber's angle from +x (directed or not). From them the track
observables (``y_out``, ``theta_out``, ``t_transit``;
:mod:`fibersweep.discrepancy.tracks`) are derived and compared; each track
must run from upstream of the pillar to one fiber length past it (a Trapping
fiber's track may stop anywhere: its track observables are NaN).

Without an ``angle_unit`` column in the fibers table, the tracks' theta is
taken for radians when their first samples match theta0 converted to radians
far better than theta0 itself. Every problem raises :class:`InputError` naming
the column, the rule and the rows (first few, 0-based).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from fibersweep.discrepancy.observables import OBSERVABLES
from fibersweep.discrepancy.schema import MeasuredData, rows_text
from fibersweep.discrepancy.tracks import measured_track_values
from fibersweep.errors import InputError
from fibersweep.units import Geometry

__all__ = ["TRAJECTORY_COLUMNS", "validate_trajectories", "with_tracks"]

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
        (:func:`~fibersweep.discrepancy.tracks.measured_track_values`).
    """
    values = measured_track_values(traj, data.table, geometry, source)
    table = pd.concat([data.table, values], axis=1)
    observed = (*data.observed, *(n for n in values.columns if OBSERVABLES[n].scored))
    return MeasuredData(table, observed, traj, data.source)
