"""What every re-labelling of a results folder shares (``fibersweep classify``).

The channel's classes (:mod:`.reclassify`) and a pillar array's transport modes
(:mod:`.reclassify_modes`) are both re-derived from the stored trajectories
without simulating; both rebuild a trajectory from its stored samples, count
labels per swept combination, and replace the runs table, the counts file and the
manifest's thresholds atomically, with the metadata of the re-labelled part.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow.parquet as pq

from fibersweep.atomic import atomic_path
from fibersweep.config.fiber import ClassifySettings
from fibersweep.sweep.manifest import revision, write_manifest
from fibersweep.sweep.store import (
    META_KEY,
    RUNS_DIR,
    list_parts,
    part_name,
    runs_table,
    write_table_atomic,
)
from fibersweep.version import __version__

__all__ = [
    "COUNTS_FILE",
    "Reclassified",
    "classified_meta",
    "replace_labels",
]

#: The label counts of a results folder, per swept combination.
COUNTS_FILE = "counts.csv"


@dataclass(frozen=True)
class Reclassified:
    """Outcome of a re-labelling (:func:`fibersweep.sweep.reclassify.reclassify`)."""

    n_runs: int
    n_changed: int
    counts: pd.DataFrame
    counts_path: Path
    warnings: tuple[str, ...] = ()


def replace_labels(
    out: Path, runs: pd.DataFrame, meta: dict[str, Any], man: dict[str, Any],
    thresholds: ClassifySettings, counts_of,
) -> tuple[pd.DataFrame, Path]:  # fmt: skip
    """Write re-labelled ``runs`` as one part replacing the old ones, the counts file and
    the manifest's thresholds and totals.

    ``counts_of(runs, by=None)`` gives a table whose first column is the label
    (class or mode) and whose ``runs`` column the count
    (:func:`fibersweep.sweep.reclassify.class_counts`,
    :func:`fibersweep.sorting.modes.mode_counts`). Returns the counts per
    swept combination and the path they were written to.
    """
    old_parts = list_parts(out / RUNS_DIR)
    write_table_atomic(
        runs_table(runs.to_dict("records"), meta), out / RUNS_DIR / part_name("-classified")
    )
    for p in old_parts:
        p.unlink(missing_ok=True)
    counts = counts_of(runs, list(man.get("swept") or []))
    counts_path = out / COUNTS_FILE
    with atomic_path(counts_path) as tmp:
        counts.to_csv(tmp, index=False)
    man["config"]["fiber"]["classify"] = thresholds.model_dump(mode="json")
    total = counts_of(runs)
    man["counts"] = {c: int(n) for c, n in zip(total.iloc[:, 0], total["runs"], strict=True)}
    write_manifest(out, man)
    return counts, counts_path




def classified_meta(parts: list[Path], man: dict, thresholds: ClassifySettings) -> dict[str, Any]:
    """Schema metadata of a re-classified part: the sweep's provenance kept, the rule added.

    The version, revision and config of the sweep come from its newest part (the
    manifest's provenance if no part has them); ``classify`` holds the thresholds
    and ``rule`` the rule that labelled the rows, with the version and revision of
    the fibersweep that re-labelled them.
    """
    old: dict[str, Any] = {}
    for p in reversed(parts):
        raw = (pq.read_schema(p).metadata or {}).get(META_KEY)
        if raw:
            old = json.loads(raw)
            break
    prov = man.get("provenance", {})
    base = {
        "fibersweep": prov.get("fibersweep"),
        "git": prov.get("git"),
        "flow_key": prov.get("flow_key"),
        "config": man.get("config"),
    }
    rev, source = revision()
    return {
        **base,
        **old,
        "classify": thresholds.model_dump(),
        "rule": thresholds.rule,
        "classified_by": {"fibersweep": __version__, "git": rev, "git_from": source},
    }
