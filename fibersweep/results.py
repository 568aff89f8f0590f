"""A sweep's results in one call: ``fibersweep.load(RESULTS)``.

Reads an output folder (``fibersweep run``'s) into a :class:`Results`: the runs
table, the trajectories, the resolved settings, the provenance and, for every
column, its unit and meaning (the Parquet field metadata each column carries).
A folder whose class column mixes pole-vaulting rules logs a warning and lists
it in ``warnings``.

The units and meanings follow the geometry the results were made with: past one
pillar in a channel, ``y0`` is in units of h_obs and ``length`` of l_obs; in a
pillar array (``flow.array``), ``y0`` is a fraction of ``period_y`` and ``length``
is in µm, and the channel's outcome columns (``class``, ``delta``...) are empty
(:data:`ARRAY_COLUMNS`). For array results, :meth:`Results.fraction_summary` is
the f summary per setting and length that ``sort-report`` prints: f over the
runs that were not trapped, with the trapped share beside it.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow.parquet as pq

from fibersweep.errors import InputError

__all__ = ["ARRAY_COLUMNS", "Results", "load_array_results", "load_results"]

log = logging.getLogger(__name__)

#: Unit and meaning of the columns that differ in a pillar array's results.
ARRAY_COLUMNS: dict[str, tuple[str, str]] = {
    "y0": (
        "period_y",
        "start lateral position of the centre of mass, as a fraction of period_y (0..1), "
        "in the gap before row 0",
    ),
    "length": ("µm", "fiber length L"),
    "x_f": ("µm", "final centre-of-mass x, array frame (the unit cell's pillar at row 0)"),
    "y_f": ("µm", "final centre-of-mass y, array frame"),
    "class": ("", "not used in a pillar array (empty): the outcome is mode"),
    "delta": ("", "not defined in a pillar array (NaN): see fraction and shift_per_row"),
    "theta_c": ("deg", "not defined in a pillar array (NaN): see contacts"),
    "y_c": ("", "not defined in a pillar array (NaN)"),
    "t_contact": ("s", "not defined in a pillar array (NaN): see time_on_pillars"),
    "t_pass": ("s", "not defined in a pillar array (NaN): see t_end"),
    "fraction": (
        "",
        "shift_per_row / (shift period_y): 1 follows the tilt, 0 the flow; a trapped run's "
        "counts only the rows before it stopped, so f summaries leave trapped runs out "
        "(Results.fraction_summary, sort-report) and give their share",
    ),
}


@dataclass(frozen=True)
class Results:
    """What a sweep wrote, read back.

    Attributes
    ----------
    path : Path
        The output folder.
    runs : DataFrame
        One row per run (docs/output.md lists the columns); ``runs.attrs["units"]``
        holds the units too.
    trajectories : DataFrame
        One row per (``id``, ``sample``); empty when none were recorded or
        ``trajectories=False`` was asked.
    settings : dict
        The resolved config of the sweep (every default filled in), as in the manifest.
    units : dict
        Column -> unit of both tables (``""`` for a dimensionless or text column;
        ``h_obs`` and ``l_obs`` are the pillar height and base length).
    docs : dict
        Column -> one-line meaning.
    provenance : dict
        fibersweep version, revision, libraries, host, command line, flow-field key.
    manifest : dict
        The whole manifest.json.
    warnings : list of str
        What a reader should know (e.g. a class column that mixes rules).
    geometry : str
        ``'channel'`` (one pillar) or ``'array'`` (``flow.array``): what ``units`` and
        ``docs`` describe.
    """

    path: Path
    runs: pd.DataFrame
    trajectories: pd.DataFrame
    settings: dict[str, Any]
    units: dict[str, str]
    docs: dict[str, str]
    provenance: dict[str, Any]
    manifest: dict[str, Any] = field(repr=False)
    warnings: list[str] = field(default_factory=list)
    geometry: str = "channel"

    def fraction_summary(self) -> pd.DataFrame:
        """The f summary of a pillar array's runs, per setting combination and length.

        f (and the migration angle) are averaged over the runs that were **not
        trapped**; the share that was trapped is the ``trapped`` column, and
        ``moving`` counts the runs averaged. These are the numbers ``sort-report``
        prints (with the stored modes; ``sort-report`` can re-label them with other
        thresholds). Columns and their meaning:
        :data:`fibersweep.sorting.report.MIGRATION_DOCS`.

        Raises
        ------
        InputError
            The results are not a pillar array's.
        """
        from fibersweep.sorting.report import migration_table, with_settings

        if self.geometry != "array":
            raise InputError(
                f"{self.path}: fraction_summary is for pillar-array results (flow.array); "
                "these are a channel's, summarised by class"
            )
        runs, settings = with_settings(self.runs[self.runs["mode"].notna()].copy(), self.manifest)
        return migration_table(runs, settings)

    def trajectory(self, run_id: str) -> pd.DataFrame:
        """Samples of one run, in time order (empty if it has none)."""
        t = self.trajectories
        if t.empty:
            return t
        return t[t["id"] == run_id].reset_index(drop=True)

    def __repr__(self) -> str:
        n_traj = self.trajectories["id"].nunique() if not self.trajectories.empty else 0
        return (
            f"Results({str(self.path)!r}: {len(self.runs)} runs, {n_traj} trajectories, "
            f"fibersweep {self.provenance.get('fibersweep')}, git {self.provenance.get('git')})"
        )


def _field_docs(parts: list[Path]) -> tuple[dict[str, str], dict[str, str]]:
    """Unit and meaning of each column, from the Parquet field metadata of ``parts``."""
    units: dict[str, str] = {}
    docs: dict[str, str] = {}
    for p in parts:  # later parts win (a re-classified part holds the newest columns)
        for f in pq.read_schema(p):
            meta = {k.decode(): v.decode() for k, v in (f.metadata or {}).items()}
            if "unit" in meta:
                units[f.name] = meta["unit"]
            if "doc" in meta:
                docs[f.name] = meta["doc"]
    return units, docs


def load_results(results: str | Path, trajectories: bool = True) -> Results:
    """Read a sweep's output folder (see :class:`Results`).

    Parameters
    ----------
    results : str or Path
        The output folder (``run.output``).
    trajectories : bool
        Also read the trajectories (the larger table).

    Raises
    ------
    InputError
        Not an output folder of fibersweep.
    ResultsError
        A part cannot be read (named in the message).
    """
    from fibersweep.sweep.manifest import read_manifest
    from fibersweep.sweep.rules import mixed_rules_message
    from fibersweep.sweep.store import RUNS_DIR, TRAJ_DIR, list_parts, read_runs
    from fibersweep.sweep.store import read_trajectories as read_traj

    out = Path(results)
    man = read_manifest(out) if out.is_dir() else None
    if man is None:
        raise InputError(f"{out}: not a fibersweep output folder (no manifest.json)")
    runs = read_runs(out)
    traj = read_traj(out) if trajectories else pd.DataFrame(columns=["id", "sample"])
    units, docs = _field_docs(list_parts(out / RUNS_DIR) + list_parts(out / TRAJ_DIR)[-1:])
    array = bool((man.get("config") or {}).get("flow", {}).get("array"))
    if array:  # the store's column docs are the channel's: say what they are here
        for c, (u, d) in ARRAY_COLUMNS.items():
            if c in runs.columns:
                units[c], docs[c] = u, d
    runs.attrs["units"] = {c: units[c] for c in runs.columns if c in units}
    traj.attrs["units"] = {c: units[c] for c in traj.columns if c in units}
    warnings = [w for w in [mixed_rules_message(runs, out)] if w]
    for w in warnings:
        log.warning("%s", w)
    return Results(
        path=out,
        runs=runs,
        trajectories=traj,
        settings=man.get("config", {}),
        units=units,
        docs=docs,
        provenance=man.get("provenance", {}),
        manifest=man,
        warnings=warnings,
        geometry="array" if array else "channel",
    )


def load_array_results(results: str | Path) -> tuple[pd.DataFrame, list[dict], dict]:
    """The runs, settings and config of an array sweep's results folder.

    Returns
    -------
    runs : DataFrame
        The runs table with ``setting`` (index into ``settings``) and
        ``setting_label`` added, and the thinned trajectory of each run as list
        columns ``traj_t`` [s], ``traj_xc``, ``traj_yc`` [µm], ``traj_th`` [rad],
        ``traj_contact`` (0/1), ``traj_speed`` [µm/s].
    settings : list of dict
        Per setting combination: ``id``, ``label``, ``values`` (swept key -> value),
        ``array`` (the flow.array settings), ``flow`` (all flow settings),
        ``flow_key``, ``u_center`` [µm/s].
    config : dict
        The stored config (JSON).

    Raises
    ------
    InputError
        The folder holds no sweep, or its runs are not pillar-array runs.
    """
    from fibersweep.sorting.report import with_settings, with_tracks
    from fibersweep.sweep.manifest import read_manifest
    from fibersweep.sweep.store import read_runs, read_trajectories

    results = Path(results)
    man = read_manifest(results)
    if man is None:
        raise InputError(f"RESULTS: {results} holds no sweep (no manifest.json)")
    runs = read_runs(results)
    if "mode" not in runs or not runs["mode"].notna().any():
        raise InputError(
            f"RESULTS: {results} holds no pillar-array runs (sort-report reads a sweep of a "
            "config with flow.array; a channel's results: plot-phase, plot-delta, classify)"
        )
    runs, settings = with_settings(runs[runs["mode"].notna()].copy(), man)
    traj = read_trajectories(results, list(runs["id"]))
    if traj.empty:
        raise InputError(f"RESULTS: {results} holds no trajectories of its array runs")
    return with_tracks(runs, traj), settings, man["config"]
