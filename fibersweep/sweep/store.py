"""Results on disk: Parquet part files written atomically, read back deduplicated.

Layout of an output directory::

    OUT/manifest.json                  provenance and the resolved config
    OUT/runs/part-*.parquet            one row per run (see RUN_COLUMNS)
    OUT/trajectories/part-*.parquet    one row per trajectory sample, keyed by id

Every part is written to a temporary name in the same directory and renamed
(``os.replace`` is atomic on POSIX), so a crash or Ctrl-C never leaves a
half-written table: the reader only sees ``*.parquet`` files. Part names sort in
write order; when an id appears more than once (a retried failure, a part
merged by compaction while the old parts were not yet removed) the last row
wins.
"""

from __future__ import annotations

import json
import logging
import os
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

__all__ = [
    "RUN_COLUMNS",
    "RUNS_DIR",
    "TRAJ_DIR",
    "PartWriter",
    "clean_temporaries",
    "compact",
    "list_parts",
    "part_name",
    "read_runs",
    "read_trajectories",
    "runs_table",
    "write_table_atomic",
]

log = logging.getLogger(__name__)

RUNS_DIR = "runs"
TRAJ_DIR = "trajectories"
META_KEY = b"fibersweep"

#: Column types of the runs table; extra keys of ``RunResult.row()`` are kept with
#: inferred types.
RUN_COLUMNS: dict[str, pa.DataType] = {
    "id": pa.string(),
    "theta0": pa.float64(),
    "y0": pa.float64(),
    "length": pa.float64(),
    "class": pa.string(),
    "status": pa.string(),
    "reason": pa.string(),
    "delta": pa.float64(),
    "contact": pa.bool_(),
    "theta_c": pa.float64(),
    "y_c": pa.float64(),
    "t_contact": pa.float64(),
    "t_pass": pa.float64(),
    "x_f": pa.float64(),
    "y_f": pa.float64(),
    "theta_f": pa.float64(),
    "n_steps": pa.int64(),
    "wall_time": pa.float64(),
    "cpu_time": pa.float64(),
    "model": pa.string(),
    "worker": pa.string(),
    "attempts": pa.int64(),
    "finished_at": pa.float64(),
}

_seq = 0


def part_name(tag: str = "") -> str:
    """A part file name that sorts in write order (ns clock, then a per-process counter)."""
    global _seq
    _seq += 1
    return f"part-{time.time_ns():020d}-{os.getpid()}-{_seq:06d}{tag}.parquet"


def write_table_atomic(table: pa.Table, path: Path) -> Path:
    """Write ``table`` to ``path`` through a temporary file and an atomic rename."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        pq.write_table(table, tmp)
        with open(tmp, "rb") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def clean_temporaries(out: Path) -> int:
    """Remove temporary files a killed writer left behind; returns how many."""
    n = 0
    for sub in (RUNS_DIR, TRAJ_DIR):
        d = Path(out) / sub
        if d.is_dir():
            for p in d.glob(".*.tmp-*"):
                p.unlink(missing_ok=True)
                n += 1
    return n


def list_parts(directory: Path) -> list[Path]:
    """Part files of a dataset in write order."""
    d = Path(directory)
    return sorted(d.glob("part-*.parquet")) if d.is_dir() else []


def _with_meta(table: pa.Table, meta: Mapping[str, Any] | None) -> pa.Table:
    if not meta:
        return table
    old = table.schema.metadata or {}
    return table.replace_schema_metadata({**old, META_KEY: json.dumps(meta, default=str).encode()})


def runs_table(
    rows: Sequence[Mapping[str, Any]], meta: Mapping[str, Any] | None = None
) -> pa.Table:
    """Arrow table of run rows with the fixed column types of RUN_COLUMNS first."""
    df = pd.DataFrame(list(rows))
    fields, arrays = [], []
    for name, typ in RUN_COLUMNS.items():
        col = df[name] if name in df else pd.Series([None] * len(df), dtype=object)
        fields.append(pa.field(name, typ))
        arrays.append(pa.array(col.tolist(), type=typ, from_pandas=True))
    for name in df.columns:
        if name not in RUN_COLUMNS:
            fields.append(pa.field(name, pa.array(df[name].tolist(), from_pandas=True).type))
            arrays.append(pa.array(df[name].tolist(), from_pandas=True))
    return _with_meta(pa.Table.from_arrays(arrays, schema=pa.schema(fields)), meta)


def _traj_table(run_id: str, cols: Mapping[str, np.ndarray]) -> pa.Table:
    n = len(next(iter(cols.values()))) if cols else 0
    data: dict[str, Any] = {
        "id": pa.array([run_id] * n, type=pa.string()),
        "sample": pa.array(np.arange(n, dtype=np.int64)),
    }
    for k, v in cols.items():
        arr = np.asarray(v)
        if arr.ndim == 1:
            data[k] = pa.array(arr)
        else:  # e.g. beads, shape (m, n_beads, 2): one list per sample
            data[k] = pa.array([a.ravel().tolist() for a in arr], type=pa.list_(pa.float64()))
    return pa.table(data)


def _read_parts(directory: Path, columns: list[str] | None = None) -> pa.Table | None:
    tables = []
    for p in list_parts(directory):
        try:
            tables.append(pq.read_table(p, columns=columns))
        except (OSError, pa.ArrowInvalid) as exc:  # never expected: parts are atomic
            log.warning("skipping unreadable part %s: %s", p, exc)
    if not tables:
        return None
    return pa.concat_tables(tables, promote_options="permissive")


def read_runs(out: Path) -> pd.DataFrame:
    """The runs table of an output directory, one row per id (the last written wins).

    Returns
    -------
    DataFrame
        Columns RUN_COLUMNS (plus any extra ones), index 0..n-1; empty with those
        columns when nothing was written yet.
    """
    t = _read_parts(Path(out) / RUNS_DIR)
    if t is None:
        return runs_table([]).to_pandas()
    df = t.to_pandas()
    df = df.drop_duplicates(subset="id", keep="last")
    return df.sort_values(["length", "y0", "theta0", "id"], kind="stable").reset_index(drop=True)


def read_trajectories(out: Path, ids: Sequence[str] | None = None) -> pd.DataFrame:
    """Trajectory samples, keyed by ``id`` and ``sample``, for ``ids`` (all if None).

    A trajectory written twice (a re-run) keeps only its last version.
    """
    d = Path(out) / TRAJ_DIR
    frames = []
    for p in list_parts(d):
        kw = {"filters": [("id", "in", list(ids))]} if ids is not None else {}
        frames.append((p, pq.read_table(p, **kw).to_pandas()))
    if not frames:
        return pd.DataFrame(columns=["id", "sample"])
    # Last part holding an id wins, whole trajectory at a time.
    owner: dict[str, int] = {}
    for k, (_, f) in enumerate(frames):
        for rid in pd.unique(f["id"]):
            owner[rid] = k
    keep = [f[f["id"].map(owner) == k] for k, (_, f) in enumerate(frames)]
    df = pd.concat(keep, ignore_index=True)
    return df.sort_values(["id", "sample"], kind="stable").reset_index(drop=True)


class PartWriter:
    """Buffers finished runs and writes them as atomic Parquet parts.

    Parameters
    ----------
    out : Path
        Output directory.
    meta : Mapping
        Provenance stored in every part's schema metadata.
    flush_every : int
        Write a part after this many runs.
    flush_seconds : float
        ... or when this long has passed since the last write.
    """

    def __init__(
        self,
        out: Path,
        meta: Mapping[str, Any] | None = None,
        flush_every: int = 32,
        flush_seconds: float = 30.0,
    ) -> None:
        self.out = Path(out)
        self.meta = dict(meta or {})
        self.flush_every = flush_every
        self.flush_seconds = flush_seconds
        self._rows: list[dict[str, Any]] = []
        self._traj: list[pa.Table] = []
        self._last = time.monotonic()
        self.parts_written = 0
        self.rows_written = 0

    def add(self, row: Mapping[str, Any], trajectory: Mapping[str, np.ndarray] | None) -> None:
        """Queue one run's row (must hold ``id``) and its trajectory columns, if any."""
        self._rows.append(dict(row))
        if trajectory:
            self._traj.append(_traj_table(str(row["id"]), trajectory))
        if (
            len(self._rows) >= self.flush_every
            or time.monotonic() - self._last >= self.flush_seconds
        ):
            self.flush()

    def flush(self) -> None:
        """Write what is queued (trajectories first, so a run row implies its trajectory)."""
        if self._traj:
            t = pa.concat_tables(self._traj, promote_options="permissive")
            write_table_atomic(_with_meta(t, self.meta), self.out / TRAJ_DIR / part_name())
            self._traj = []
        if self._rows:
            write_table_atomic(runs_table(self._rows, self.meta), self.out / RUNS_DIR / part_name())
            self.parts_written += 1
            self.rows_written += len(self._rows)
            log.info("wrote %d runs to a new part", len(self._rows))
            self._rows = []
        self._last = time.monotonic()

    def __enter__(self) -> PartWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.flush()


def compact(out: Path, meta: Mapping[str, Any] | None = None) -> None:
    """Merge each dataset's parts into one deduplicated part, then remove the old parts.

    Safe against interruption: the merged part is written atomically before any
    old part is removed; until they are, readers deduplicate.
    """
    out = Path(out)
    runs_parts = list_parts(out / RUNS_DIR)
    if len(runs_parts) > 1:
        df = read_runs(out)
        write_table_atomic(
            runs_table(df.to_dict("records"), meta), out / RUNS_DIR / part_name("-merged")
        )
        for p in runs_parts:
            p.unlink(missing_ok=True)
    traj_parts = list_parts(out / TRAJ_DIR)
    if len(traj_parts) > 1:
        df = read_trajectories(out)
        t = pa.Table.from_pandas(df, preserve_index=False)
        write_table_atomic(_with_meta(t, meta), out / TRAJ_DIR / part_name("-merged"))
        for p in traj_parts:
            p.unlink(missing_ok=True)
