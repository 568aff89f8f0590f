"""The state of an output folder, read without changing anything (``fibersweep check``)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from fibersweep.atomic import TMP_GLOB
from fibersweep.errors import InputError
from fibersweep.sweep.lock import LockHolder, lock_holder
from fibersweep.sweep.manifest import read_manifest
from fibersweep.sweep.rules import mixed_rules_message
from fibersweep.sweep.store import (
    RUNS_DIR,
    TRAJ_DIR,
    list_parts,
    read_runs,
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
        Ok runs without a stored trajectory while the sweep records them.
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
    temporaries: int = 0
    quarantined: list[Path] = field(default_factory=list)
    mixed_rules: str | None = None

    @property
    def healthy(self) -> bool:
        """No unreadable part and no run missing data it should have."""
        return not self.unreadable and self.missing_trajectories == 0

    def lines(self) -> list[str]:
        """The report as text lines."""
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
        for p, why in self.unreadable:
            out.append(f"  UNREADABLE {p}: {why}")
        if self.unreadable:
            out.append("  `fibersweep run` on this folder moves them aside and re-runs their runs")
        if self.missing_trajectories:
            out.append(f"  {self.missing_trajectories} ok runs have no stored trajectory")
        if self.temporaries:
            out.append(f"  {self.temporaries} temporary file(s) of an interrupted write")
        for q in self.quarantined:
            out.append(f"  parts moved aside earlier: {q}")
        if self.mixed_rules:  # readable and complete, but not comparable run by run
            out.append(f"  warning: {self.mixed_rules}")
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
    man = read_manifest(out)
    bad = unreadable_parts(out)
    skip = [p for p, _ in bad]
    runs = read_runs(out, skip=skip)
    ok = runs["status"] == "ok"
    missing = 0
    records = bool(
        man and man.get("config", {}).get("fiber", {}).get("record", {}).get("trajectories")
    )
    if records:
        missing = int((ok & ~runs["id"].isin(trajectory_ids(out, skip=skip))).sum())
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
        temporaries=temporaries,
        quarantined=sorted(out.glob("quarantine-*")),
        mixed_rules=mixed_rules_message(runs, out),
    )
