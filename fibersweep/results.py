"""A sweep's results in one call: ``fibersweep.load(RESULTS)``.

Reads an output folder (``fibersweep run``'s) into a :class:`Results`: the runs
table, the trajectories, the resolved settings, the provenance and, for every
column, its unit and meaning (the Parquet field metadata each column carries).
A folder whose class column mixes pole-vaulting rules logs a warning and lists
it in ``warnings``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow.parquet as pq

from fibersweep.errors import InputError

__all__ = ["Results", "load_results"]

log = logging.getLogger(__name__)


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
    )
