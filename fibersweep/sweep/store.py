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
import shlex
import threading
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from fibersweep.atomic import TMP_GLOB, atomic_path
from fibersweep.errors import ResultsError, UnreadableResults
from fibersweep.fiber.result import ARRAY_COLUMNS, Column, record_columns
from fibersweep.sweep.coldocs import RUN_EXTRA_DOCS, TRAJ_COLUMN_DOCS, docs_for, with_docs
from fibersweep.sweep.manifest import read_manifest

__all__ = [
    "COLUMN_DOCS",
    "RUN_COLUMNS",
    "RUNS_DIR",
    "SWEEP_COLUMNS",
    "TRAJ_DIR",
    "VOLATILE_COLUMNS",
    "PartWriter",
    "clean_temporaries",
    "compact",
    "describe_os_error",
    "expected_data",
    "kept_data",
    "list_parts",
    "part_name",
    "read_runs",
    "read_trajectories",
    "rewrite_runs",
    "runs_table",
    "quarantine",
    "repair_command",
    "trajectory_ids",
    "unreadable_parts",
    "write_table_atomic",
]

log = logging.getLogger(__name__)

RUNS_DIR = "runs"
TRAJ_DIR = "trajectories"
META_KEY = b"fibersweep"

#: Columns the sweep adds to each run's record (bookkeeping, not physics).
SWEEP_COLUMNS: tuple[Column, ...] = (
    Column("cpu_time", "float64", "s", "CPU time of the run in its worker"),
    Column(
        "settings", "string", "", "id of the run's settings (hash of fiber settings and flow field)"
    ),
    Column("worker", "string", "", "host:pid of the worker that ran it"),
    Column("attempts", "int64", "", "times the run was started (worker crashes re-run it)"),
    Column("finished_at", "float64", "s", "Unix time the run finished"),
    Column(
        "round",
        "int64",
        "",
        "refinement round that first ran the run (0: the grid; see sweep.refine)",
    ),
)

_ID = Column(
    "id", "string", "", "content id of the run (hash of start, fiber settings and flow field)"
)
_COLUMNS = (_ID, *record_columns(), *SWEEP_COLUMNS)

#: Column types of the runs table, generated from the run record
#: (:func:`fibersweep.fiber.result.record_columns`) and :data:`SWEEP_COLUMNS`; extra keys
#: of a row (the swept settings) are kept with their schema type or an inferred one.
RUN_COLUMNS: dict[str, pa.DataType] = {c.name: pa.type_for_alias(c.arrow) for c in _COLUMNS}

#: Unit and frame of the runs-table columns, stored as Parquet field metadata
#: (``unit`` and ``doc``), so a table read outside fibersweep says what it holds.
COLUMN_DOCS: dict[str, tuple[str, str]] = {c.name: (c.unit, c.doc) for c in _COLUMNS}

#: Columns written only when some row of the part has a non-zero value; read as 0
#: where a part lacks them.
ONLY_WHEN_SET = ("round",)

#: Columns that differ between two runs of the same sweep (timing and bookkeeping);
#: leave them out to compare results run by run.
VOLATILE_COLUMNS = ("wall_time", "cpu_time", "worker", "finished_at", "attempts")

_seq = 0


def part_name(tag: str = "") -> str:
    """A part file name that sorts in write order (ns clock, then a per-process counter)."""
    global _seq
    _seq += 1
    return f"part-{time.time_ns():020d}-{os.getpid()}-{_seq:06d}{tag}.parquet"


def write_table_atomic(table: pa.Table, path: Path) -> Path:
    """Write ``table`` to ``path`` through a temporary file and an atomic rename."""
    with atomic_path(path) as tmp:
        pq.write_table(table, tmp)
    return path


def clean_temporaries(out: Path) -> int:
    """Remove temporary files a killed writer left behind; returns how many."""
    n = 0
    for sub in (RUNS_DIR, TRAJ_DIR):
        d = Path(out) / sub
        if d.is_dir():
            for p in d.glob(TMP_GLOB):
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
    array_runs = "mode" in df and df["mode"].notna().any()
    for name, typ in RUN_COLUMNS.items():
        if name in ARRAY_COLUMNS and not array_runs:
            continue  # a channel's runs: the table as before pillar arrays existed
        if name in ONLY_WHEN_SET and not (name in df and (df[name].fillna(0) != 0).any()):
            continue  # e.g. no 'round' column in a sweep that was never refined
        col = df[name] if name in df else pd.Series([None] * len(df), dtype=object)
        unit, doc = COLUMN_DOCS[name]
        fields.append(pa.field(name, typ, metadata={"unit": unit, "doc": doc}))
        arrays.append(pa.array(col.tolist(), type=typ, from_pandas=True))
    for name in df.columns:
        if name in RUN_COLUMNS:
            continue
        if "." in name:  # a swept setting (dotted key): typed, with its unit
            f, arr = _setting_field(name, df[name].tolist())
        else:
            arr = pa.array(df[name].tolist(), from_pandas=True)
            f = pa.field(name, arr.type, metadata=docs_for(name, RUN_EXTRA_DOCS))
        fields.append(f)
        arrays.append(arr)
    return _with_meta(pa.Table.from_arrays(arrays, schema=pa.schema(fields)), meta)


_KINDS = {"float": pa.float64(), "int": pa.int64(), "bool": pa.bool_(), "string": pa.string()}


def _missing(v: Any) -> bool:
    return v is None or (isinstance(v, float) and np.isnan(v))


def _setting_field(name: str, values: list[Any]) -> tuple[pa.Field, pa.Array]:
    """Column of a swept setting: its schema type, unit and description as field metadata.

    A section or list value is stored as its JSON text (type ``json`` in the metadata).
    """
    from fibersweep.config import setting_column

    kind, unit, doc = setting_column(name)
    meta = {"unit": unit, "doc": doc, "kind": kind}
    if kind in _KINDS:
        try:
            arr = pa.array(values, type=_KINDS[kind], from_pandas=True)
            return pa.field(name, arr.type, metadata=meta), arr
        except (pa.ArrowInvalid, pa.ArrowTypeError):  # e.g. stored as text by an older sweep
            pass
    text = [None if _missing(v) else v if isinstance(v, str) else json.dumps(v) for v in values]
    arr = pa.array(text, type=pa.string())
    return pa.field(name, arr.type, metadata={**meta, "kind": "json"}), arr


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
    return with_docs(pa.table(data), TRAJ_COLUMN_DOCS)


def _cause(exc: BaseException, path: Path) -> str:
    """Why ``path`` could not be read, without the path (the message names it once)."""
    text = describe_os_error(exc) if isinstance(exc, OSError) and exc.strerror else str(exc)
    for quoted in (f" '{path}'", f' "{path}"', f"{path}: ", str(path)):
        text = text.replace(quoted, "")
    text = text.replace("Could not open Parquet input source: ", "")
    return " ".join(text.split()).rstrip(".") or type(exc).__name__


def _read_part(path: Path, **kw: Any) -> pa.Table:
    """One part, or :class:`UnreadableResults` naming it once (never a silent skip)."""
    try:
        return pq.read_table(path, **kw)
    except (OSError, pa.ArrowException) as exc:
        out = path.parent.parent
        raise UnreadableResults(
            f"{path}: unreadable result part ({_cause(exc, path)}). `fibersweep check` on its "
            "folder lists all that is damaged; the sweep's own command moves the part aside "
            f"and runs its runs again: {repair_command(out)}"
        ) from None


def _read_parts(
    directory: Path, columns: list[str] | None = None, skip: frozenset[Path] = frozenset()
) -> pa.Table | None:
    tables = [_read_part(p, columns=columns) for p in list_parts(directory) if p not in skip]
    if not tables:
        return None
    return pa.concat_tables(tables, promote_options="permissive")


def unreadable_parts(out: Path) -> list[tuple[Path, str]]:
    """Parts of ``out`` that cannot be read, with the reason (runs read whole, trajectories' ids).

    Returns
    -------
    list of (Path, str)
    """
    bad = []
    for sub, cols in ((RUNS_DIR, None), (TRAJ_DIR, ["id"])):
        for p in list_parts(Path(out) / sub):
            try:
                pq.read_table(p, columns=cols)
            except (OSError, pa.ArrowException) as exc:
                bad.append((p, _cause(exc, p)))
    return bad


def kept_data(config: Mapping[str, Any] | None) -> tuple[bool, bool]:
    """What every ok run of a sweep stores besides its row: (a trajectory, its beads).

    Parameters
    ----------
    config : Mapping or None
        The sweep's config as JSON (``Config.model_dump(mode="json")``, or a
        manifest's ``config``); None: nothing is known to be kept.

    Returns
    -------
    trajectories : bool
        ``fiber.record.trajectories``, or a pillar array's run (always kept: its
        mode is re-labelled from it).
    beads : bool
        Every bead's position in the trajectory (``fiber.record.all_beads`` of a
        bead-spring fiber, or of any fiber in a channel).
    """
    if not config:
        return False, False
    fiber = config.get("fiber") or {}
    record = fiber.get("record") or {}
    array = (config.get("flow") or {}).get("array") is not None
    traj = bool(record.get("trajectories")) or array
    beads = traj and bool(record.get("all_beads")) and (fiber.get("model") != "rigid" or not array)
    return traj, beads


def expected_data(
    runs: pd.DataFrame, config: Mapping[str, Any] | None
) -> tuple[np.ndarray, np.ndarray]:
    """Per row of ``runs``: should the store hold its trajectory, and its beads' positions?

    From the sweep's config (:func:`kept_data`), with each run's own settings where
    they differ: a swept ``fiber.record.trajectories`` or ``fiber.record.all_beads``
    column, and the run's ``model`` (a rigid fiber in a pillar array keeps no beads).

    Returns
    -------
    trajectory, beads : ndarray of bool, one per row
    """
    n = len(runs)
    if not config or n == 0:
        return np.zeros(n, bool), np.zeros(n, bool)
    fiber = config.get("fiber") or {}
    record = fiber.get("record") or {}
    array = (config.get("flow") or {}).get("array") is not None

    def setting(key: str, default: Any) -> np.ndarray:
        col = f"fiber.record.{key}"
        if col not in runs:
            return np.full(n, bool(default))
        return runs[col].astype(object).where(runs[col].notna(), default).astype(bool).to_numpy()

    traj = setting("trajectories", record.get("trajectories", False)) | array
    beads = traj & setting("all_beads", record.get("all_beads", False))
    if array:
        model = runs["model"] if "model" in runs else pd.Series([fiber.get("model")] * n)
        beads &= (model.astype(object).fillna(fiber.get("model")) != "rigid").to_numpy()
    return traj, beads


_VALUE_OPTIONS = ("-w", "--workers", "--executor", "--scheduler", "--max-points")
_DROPPED_OPTIONS = ("-o", "--output")  # the folder is named by -o OUT instead


def _run_argv(argv: Sequence[str]) -> tuple[str, list[str]] | None:
    """(config, kept options) of a recorded ``fibersweep run`` command line, or None."""
    if len(argv) < 3 or argv[1] != "run":
        return None
    name = Path(str(argv[0])).name
    if name not in ("fibersweep", "__main__.py", "fibersweep.exe"):
        return None
    config, options, args = None, [], list(argv[2:])
    while args:
        a = str(args.pop(0))
        opt, eq, _ = a.partition("=")
        if opt in _VALUE_OPTIONS or opt in _DROPPED_OPTIONS:
            value = [a] if eq else [a, str(args.pop(0))] if args else [a]
            if opt in _VALUE_OPTIONS:
                options += value
        elif a.startswith("-"):
            continue  # --no-resume, --retry-failed, --dry-run, -v: not for a repair
        elif config is None:
            config = a
    return None if config is None else (config, options)


def repair_command(out: Path, manifest: Mapping[str, Any] | None = None) -> str:
    """The ``fibersweep run`` line that repairs ``out``: the one that made it.

    The config file is taken from the command line the manifest recorded, the
    overrides from the manifest; ``-o OUT`` is added unless the config's
    ``run.output`` is ``out`` seen from here. When the manifest does not say (a
    sweep started from Python, or no manifest), a template with ``CONFIG`` for the
    config file that made the folder.
    """
    out = Path(out)
    if manifest is None:
        try:
            manifest = read_manifest(out)
        except UnreadableResults:  # the template
            manifest = None
    manifest = manifest or {}
    argv = (manifest.get("provenance") or {}).get("argv") or []
    found = _run_argv([str(a) for a in argv]) if isinstance(argv, list) else None
    config, options = found if found is not None else ("CONFIG", [])
    overrides = [str(o) for o in manifest.get("overrides") or []]
    words = ["fibersweep", "run", config, *overrides, *options]
    stored = ((manifest.get("config") or {}).get("run") or {}).get("output")
    for o in overrides:  # the last run.output= override wins over the file's
        if o.startswith("run.output="):
            stored = o.partition("=")[2]
    # a relative config that is not here: the command runs where the sweep was started
    elsewhere = found is not None and not Path(config).is_absolute() and not Path(config).exists()
    if stored is None or Path(str(stored)).resolve() != out.resolve():
        words += ["-o", str(out.resolve() if elsewhere else out)]
    line = " ".join(w if w == "CONFIG" else shlex.quote(w) for w in words)
    if elsewhere:
        return f"`{line}` (from the folder the sweep was started in: {config} is relative)"
    if found is None:
        return (
            f"`{line}` (CONFIG: the config file that made the folder; its manifest.json "
            "holds the settings)"
        )
    return f"`{line}`"


def quarantine(out: Path, parts: Sequence[Path]) -> Path | None:
    """Move ``parts`` into ``out/quarantine-<time>/<runs|trajectories>/`` (never delete).

    Returns the quarantine folder, or None when there was nothing to move.
    """
    if not parts:
        return None
    dest = Path(out) / time.strftime("quarantine-%Y%m%dT%H%M%S", time.gmtime())
    for p in parts:
        target = dest / p.parent.name
        target.mkdir(parents=True, exist_ok=True)
        os.replace(p, target / p.name)
        log.warning("moved unreadable part %s to %s", p, target)
    return dest


def trajectory_ids(
    out: Path, skip: Sequence[Path] = (), with_column: str | None = None
) -> set[str]:
    """Ids that have a stored trajectory (parts in ``skip`` left out).

    ``with_column``: only the trajectories of parts that hold this column (``beads``:
    the runs whose bead positions are stored).
    """
    d = Path(out) / TRAJ_DIR
    if with_column is not None:
        skip = [
            *skip,
            *(p for p in list_parts(d) if p not in skip and not _has_column(p, with_column)),
        ]
    t = _read_parts(d, columns=["id"], skip=frozenset(skip))
    return set() if t is None else set(pc.unique(t.column("id")).to_pylist())


def _has_column(part: Path, name: str) -> bool:
    try:
        return name in pq.read_schema(part).names
    except (OSError, pa.ArrowException) as exc:
        raise UnreadableResults(f"{part}: unreadable result part ({_cause(exc, part)})") from None


def read_runs(out: Path, skip: Sequence[Path] = ()) -> pd.DataFrame:
    """The runs table of an output directory, one row per id (the last written wins).

    Parameters
    ----------
    out : Path
    skip : sequence of Path
        Parts to leave out (known unreadable ones, for a dry run's plan).

    Raises
    ------
    ResultsError
        A part cannot be read (named in the message).

    Returns
    -------
    DataFrame
        Columns RUN_COLUMNS (plus any extra ones), index 0..n-1; empty with those
        columns when nothing was written yet.
    """
    t = _read_parts(Path(out) / RUNS_DIR, skip=frozenset(skip))
    if t is None:
        return runs_table([]).to_pandas()
    df = t.to_pandas()
    for name in ONLY_WHEN_SET:  # parts written before the first non-zero value lack it
        if name in df:
            df[name] = df[name].fillna(0).astype(np.int64)
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
        frames.append((p, _read_part(p, **kw).to_pandas()))
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

    Parts are written after ``flush_every`` runs or once the oldest queued run has
    waited ``flush_seconds`` (a background timer checks every second, so a kill
    costs at most that much finished work even when runs are slow). A write that
    fails (disk full, folder gone) keeps the runs queued and is retried at the next
    flush; :meth:`close` raises :class:`ResultsError` if some still cannot be saved.

    Parameters
    ----------
    out : Path
        Output directory.
    meta : Mapping
        Provenance stored in every part's schema metadata.
    flush_every : int
        Write a part after this many runs.
    flush_seconds : float
        ... or when a queued run has waited this long [s].
    """

    def __init__(
        self,
        out: Path,
        meta: Mapping[str, Any] | None = None,
        flush_every: int = 32,
        flush_seconds: float = 5.0,
    ) -> None:
        self.out = Path(out)
        self.meta = dict(meta or {})
        self.flush_every = flush_every
        self.flush_seconds = flush_seconds
        self._rows: list[dict[str, Any]] = []
        self._traj: list[pa.Table] = []
        self._oldest: float | None = None
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._timer: threading.Thread | None = None
        self.error: OSError | None = None
        self.parts_written = 0
        self.rows_written = 0

    @property
    def pending(self) -> int:
        """Finished runs not yet on disk."""
        return len(self._rows)

    def start_timer(self) -> None:
        """Flush in the background once a queued run is ``flush_seconds`` old."""
        if self._timer is None:
            self._timer = threading.Thread(target=self._tick, name="part-writer", daemon=True)
            self._timer.start()

    def _tick(self) -> None:
        while not self._stop.wait(min(1.0, self.flush_seconds)):
            if self._due():
                self.flush()

    def _due(self) -> bool:
        return self._oldest is not None and time.monotonic() - self._oldest >= self.flush_seconds

    def add(self, row: Mapping[str, Any], trajectory: Mapping[str, np.ndarray] | None) -> None:
        """Queue one run's row (must hold ``id``) and its trajectory columns, if any.

        Ctrl-C can land anywhere in the main thread: the trajectory table is built
        before anything is queued and queued before the row, so an interrupt never
        leaves a row without its trajectory (a trajectory without its row is harmless:
        the run is not done, and its re-run's trajectory replaces it).
        """
        table = _traj_table(str(row["id"]), trajectory) if trajectory else None
        with self._lock:
            if table is not None:
                self._traj.append(table)
            self._rows.append(dict(row))
            if self._oldest is None:
                self._oldest = time.monotonic()
        if len(self._rows) >= self.flush_every or self._due():
            self.flush()

    def flush(self) -> bool:
        """Write what is queued (trajectories first, so a run row implies its trajectory).

        Returns
        -------
        bool
            False when the write failed (the runs stay queued; ``error`` says why).
        """
        with self._lock:
            try:
                if self._traj:
                    t = pa.concat_tables(self._traj, promote_options="permissive")
                    write_table_atomic(_with_meta(t, self.meta), self.out / TRAJ_DIR / part_name())
                    self._traj = []
                if self._rows:
                    write_table_atomic(
                        runs_table(self._rows, self.meta), self.out / RUNS_DIR / part_name()
                    )
                    self.parts_written += 1
                    self.rows_written += len(self._rows)
                    log.info("wrote %d runs to a new part", len(self._rows))
                    self._rows = []
            except OSError as exc:
                if str(exc) != str(self.error):
                    log.error(
                        "cannot write results (%s); %d finished runs kept in memory, "
                        "retrying at the next flush",
                        describe_os_error(exc),
                        len(self._rows),
                    )
                self.error = exc
                return False
            self.error = None
            self._oldest = None
            return True

    def close(self) -> None:
        """Stop the timer and write the rest.

        Raises
        ------
        ResultsError
            Some finished runs could not be written (they are named in the log).
        """
        self._stop.set()
        if self._timer is not None:
            self._timer.join()
            self._timer = None
        if not self.flush():
            ids = [str(r["id"]) for r in self._rows]
            log.error("runs not saved: %s", ", ".join(ids))
            raise ResultsError(
                f"{len(ids)} finished runs could not be saved in {self.out}: "
                f"{describe_os_error(self.error)}; run the same command again once the "
                "cause is fixed (only they are re-run)"
            )

    def __enter__(self) -> PartWriter:
        self.start_timer()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def describe_os_error(exc: BaseException | None) -> str:
    """'PATH: cause' for an OSError (one line, no traceback)."""
    if isinstance(exc, OSError) and exc.strerror:
        where = exc.filename if exc.filename is not None else ""
        return f"{where}: {exc.strerror}" if where else exc.strerror
    return str(exc)


def rewrite_runs(out: Path, runs: pd.DataFrame, meta: Mapping[str, Any] | None = None) -> Path:
    """Replace the runs table by ``runs`` (one merged part written atomically, then the
    old parts removed; until they are, readers deduplicate and the new part wins).
    """
    out = Path(out)
    old = list_parts(out / RUNS_DIR)
    path = write_table_atomic(
        runs_table(runs.to_dict("records"), meta), out / RUNS_DIR / part_name("-merged")
    )
    for p in old:
        p.unlink(missing_ok=True)
    return path


def compact(out: Path, meta: Mapping[str, Any] | None = None) -> None:
    """Merge each dataset's parts into one deduplicated part, then remove the old parts.

    Safe against interruption: the merged part is written atomically before any
    old part is removed; until they are, readers deduplicate.
    """
    out = Path(out)
    if len(list_parts(out / RUNS_DIR)) > 1:
        rewrite_runs(out, read_runs(out), meta)
    traj_parts = list_parts(out / TRAJ_DIR)
    if len(traj_parts) > 1:
        df = read_trajectories(out)
        t = with_docs(pa.Table.from_pandas(df, preserve_index=False), TRAJ_COLUMN_DOCS)
        write_table_atomic(_with_meta(t, meta), out / TRAJ_DIR / part_name("-merged"))
        for p in traj_parts:
            p.unlink(missing_ok=True)
