"""The state of an output folder, read without changing anything (``fibersweep check``)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

from fibersweep.atomic import TMP_GLOB
from fibersweep.errors import InputError, UnreadableResults
from fibersweep.sweep.lock import LockHolder, lock_holder
from fibersweep.sweep.manifest import read_manifest
from fibersweep.sweep.rules import mixed_rules_message
from fibersweep.sweep.store import (
    RUNS_DIR,
    TRAJ_DIR,
    expected_data,
    list_parts,
    read_runs,
    repair_command,
    trajectory_ids,
    unreadable_parts,
)

__all__ = ["FolderReport", "check_folder"]


@dataclass(frozen=True)
class FolderReport:
    """What :func:`check_folder` found.

    Attributes
    ----------
    out : Path
    state : str or None
        The manifest's state ('complete', 'running', 'interrupted', 'unsaved', ...);
        None without a manifest.
    lock : LockHolder or None
        Who holds the folder's lock, and whether that process is alive.
    runs_parts, traj_parts : int
        Part files found.
    unreadable : list of (Path, str)
        Parts that cannot be read, with the reason.
    rows, ok, failed : int
        Distinct runs in the readable parts, and how many are ok / failed.
    missing_trajectories : int
        Ok runs without a stored trajectory while the sweep records them (a
        pillar array's runs always do).
    missing_beads : int
        Ok runs whose trajectory lacks the bead positions the sweep records
        (``fiber.record.all_beads``), their trajectory itself being there.
    beadless_parts : list of Path
        The trajectory parts without a ``beads`` column, when some run misses them.
    missing_rows : int
        Runs the manifest counted when the sweep last finished that no readable
        runs part holds (a runs part lost or unreadable).
    manifest_error : str or None
        Why manifest.json cannot be read (None: read, or absent).
    repair : str
        The command that repairs the folder (``fibersweep run`` as it was made,
        or a template), shown when it is not healthy.
    temporaries : int
        Temporary files a killed writer left (removed by the next ``run``).
    quarantined : list of Path
        ``quarantine-*`` folders holding parts moved aside earlier.
    mixed_rules : str or None
        A warning when the class column mixes pole-vaulting rules (still healthy).
    """

    out: Path
    state: str | None
    lock: LockHolder | None
    runs_parts: int
    traj_parts: int
    unreadable: list[tuple[Path, str]] = field(default_factory=list)
    rows: int = 0
    ok: int = 0
    failed: int = 0
    missing_trajectories: int = 0
    missing_beads: int = 0
    beadless_parts: list[Path] = field(default_factory=list)
    missing_rows: int = 0
    manifest_error: str | None = None
    repair: str = ""
    temporaries: int = 0
    quarantined: list[Path] = field(default_factory=list)
    mixed_rules: str | None = None

    @property
    def healthy(self) -> bool:
        """Every part and the manifest readable, and no run missing data it should have."""
        return not (
            self.unreadable
            or self.missing_trajectories
            or self.missing_beads
            or self.missing_rows
            or self.manifest_error
        )

    def lines(self) -> list[str]:
        """The report as text lines (the last: ``ok`` or ``NOT ok``)."""
        out = [
            f"{self.out}: manifest state {self.state or 'missing'}; "
            f"{self.rows} runs ({self.ok} ok, {self.failed} failed) in "
            f"{self.runs_parts} runs part(s), {self.traj_parts} trajectory part(s)"
        ]
        if self.lock is not None:
            alive = self.lock.alive()
            how = {True: "running", False: "stale: its process is gone"}.get(
                alive, "on another host"
            )
            out.append(f"  locked by {self.lock.describe()} ({how})")
        if self.manifest_error:
            out.append(f"  UNREADABLE {self.manifest_error}")
        for p, why in self.unreadable:
            out.append(f"  UNREADABLE {p}: {why}")
        if self.missing_rows:
            n = self.rows + self.missing_rows
            out.append(
                f"  MISSING {self.missing_rows} run(s): the manifest counted {n} when the sweep "
                f"last finished, the readable {RUNS_DIR} parts hold {self.rows}"
            )
        if self.missing_trajectories:
            out.append(
                f"  MISSING the trajectory of {self.missing_trajectories} ok run(s) "
                f"(the sweep keeps one per run: a {TRAJ_DIR} part is lost or unreadable)"
            )
        if self.missing_beads:
            out.append(
                f"  MISSING the bead positions of {self.missing_beads} ok run(s) "
                "(the sweep keeps them: fiber.record.all_beads)"
                + "".join(f"; no beads column in {p}" for p in self.beadless_parts)
            )
        if self.temporaries:
            out.append(f"  {self.temporaries} temporary file(s) of an interrupted write")
        for q in self.quarantined:
            out.append(f"  parts moved aside earlier: {q}")
        if self.mixed_rules:  # readable and complete, but not comparable run by run
            out.append(f"  warning: {self.mixed_rules}")
        if not self.healthy and not self.manifest_error:
            what = "moves the unreadable parts to a quarantine-* folder, then " * bool(
                self.unreadable
            )
            out.append(f"  repair: {self.repair}")
            out.append(f"    (it {what}runs again each run that lost data; the others are kept)")
        out.append("  ok" if self.healthy else "  NOT ok")
        return out


def check_folder(out: Path) -> FolderReport:
    """Read every part of ``out`` and report; changes nothing.

    Raises
    ------
    InputError
        ``out`` is not a folder.
    """
    out = Path(out)
    if not out.is_dir():
        raise InputError(f"{out}: no such folder")
    manifest_error = None
    try:
        man = read_manifest(out)
    except UnreadableResults as exc:
        man, manifest_error = None, str(exc)
    bad = unreadable_parts(out)
    skip = [p for p, _ in bad]
    runs = read_runs(out, skip=skip)
    ok = runs["status"] == "ok"
    need_traj, need_beads = expected_data(runs, (man or {}).get("config"))
    missing = missing_beads = 0
    beadless: list[Path] = []
    ok_np = ok.to_numpy()
    if (ok_np & need_traj).any():
        ids = runs["id"].to_numpy()
        have = np.isin(ids, list(trajectory_ids(out, skip=skip)))
        missing = int((ok_np & need_traj & ~have).sum())
        if (ok_np & need_beads).any():
            with_beads = np.isin(ids, list(trajectory_ids(out, skip=skip, with_column="beads")))
            missing_beads = int((ok_np & need_beads & have & ~with_beads).sum())
            if missing_beads:
                beadless = [
                    p
                    for p in list_parts(out / TRAJ_DIR)
                    if p not in skip and "beads" not in pq.read_schema(p).names
                ]
    counted = (man or {}).get("rows")
    missing_rows = max(0, int(counted) - len(runs)) if isinstance(counted, int) else 0
    temporaries = sum(
        1
        for sub in (RUNS_DIR, TRAJ_DIR)
        if (out / sub).is_dir()
        for _ in (out / sub).glob(TMP_GLOB)
    )
    return FolderReport(
        out=out,
        state=None if man is None else man.get("state"),
        lock=lock_holder(out),
        runs_parts=len(list_parts(out / RUNS_DIR)),
        traj_parts=len(list_parts(out / TRAJ_DIR)),
        unreadable=bad,
        rows=len(runs),
        ok=int(ok.sum()),
        failed=int((~ok).sum()),
        missing_trajectories=missing,
        missing_beads=missing_beads,
        beadless_parts=beadless,
        missing_rows=missing_rows,
        manifest_error=manifest_error,
        repair=repair_command(out, man),
        temporaries=temporaries,
        quarantined=sorted(out.glob("quarantine-*")),
        mixed_rules=mixed_rules_message(runs, out),
    )
