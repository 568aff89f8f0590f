"""What a sweep has to do: every run's id, what is already done, what changed.

Pure bookkeeping (no simulation), shared by ``fibersweep run`` (local pool or
Dask) and ``--dry-run``.
"""

from __future__ import annotations

import logging
import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fibersweep.config import Config
from fibersweep.errors import InputError
from fibersweep.sweep.ids import diff_settings, fiber_result_settings, run_ids
from fibersweep.sweep.manifest import read_manifest
from fibersweep.sweep.store import (
    RUNS_DIR,
    TRAJ_DIR,
    quarantine,
    read_runs,
    trajectory_ids,
    unreadable_parts,
)
from fibersweep.sweep.worker import SweepTask

__all__ = ["SweepPlan", "make_tasks", "move_aside", "plan_sweep", "result_settings"]

log = logging.getLogger(__name__)


def result_settings(cfg: Config, flow_key: str) -> dict[str, Any]:
    """Everything that changes results, as stored in the manifest and compared on resume."""
    return {"flow_key": flow_key, "fiber": fiber_result_settings(cfg.fiber)}


def make_tasks(cfg: Config, flow_key: str) -> list[SweepTask]:
    """One task per distinct sweep point (a repeated axis value is run once)."""
    t, y, L = cfg.sweep.grid()
    ids = run_ids(t, y, L, cfg.fiber, flow_key)
    tasks: dict[str, SweepTask] = {}
    for rid, ti, yi, Li in zip(ids, t.tolist(), y.tolist(), L.tolist(), strict=True):
        if rid not in tasks:
            tasks[rid] = SweepTask(rid, ti, yi, Li)
    return list(tasks.values())


@dataclass(frozen=True)
class SweepPlan:
    """The state of an output directory against a config.

    Attributes
    ----------
    out : Path
    tasks : list of SweepTask
        Every point of the sweep.
    todo : list of SweepTask
        What this invocation will run.
    done_ok, done_failed : int
        Points of this sweep already finished, successfully or not.
    kept_other : int
        Rows in the store from earlier sweeps with the same settings but points
        no longer in the sweep (kept, not re-run).
    changes : list of str
        Result-changing differences from the stored manifest ("path: old -> new").
    notes : list of str
        Things the user should know (e.g. changed classification thresholds).
    mean_run_s : float or None
        Mean wall time of the finished runs [s], for the estimate.
    fresh : bool
        True when existing results will be moved aside.
    """

    out: Path
    tasks: list[SweepTask]
    todo: list[SweepTask]
    done_ok: int
    done_failed: int
    kept_other: int = 0
    changes: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    mean_run_s: float | None = None
    fresh: bool = False

    def estimate_s(self, workers: int) -> float | None:
        """Wall-clock estimate for ``todo`` on ``workers`` workers [s] (None if unknown)."""
        if self.mean_run_s is None:
            return None
        return self.mean_run_s * len(self.todo) / max(1, min(workers, max(1, len(self.todo))))


def plan_sweep(
    cfg: Config,
    flow_key: str,
    *,
    resume: bool = True,
    retry_failed: bool = False,
    repair: bool = False,
) -> SweepPlan:
    """Compare a config with its output directory and decide what to run.

    Parameters
    ----------
    cfg : Config
    flow_key : str
        Hash of the flow field.
    resume : bool
        Keep finished runs (default). False starts over; old results are moved
        aside by :func:`move_aside`, never deleted.
    retry_failed : bool
        Run only the points recorded as failed.
    repair : bool
        Move unreadable parts into a ``quarantine-*`` folder (their runs are then
        to do). When False (a dry run) they are only left out and reported.

    Raises
    ------
    InputError
        The output holds results made with different settings and ``resume`` is on.
    """
    out = Path(cfg.run.output)
    tasks = make_tasks(cfg, flow_key)
    manifest = read_manifest(out)
    notes: list[str] = []
    bad = [p for p, _ in unreadable_parts(out)]
    if bad and repair:
        where = quarantine(out, bad)
        notes.append(f"{len(bad)} unreadable part(s) moved to {where}; their runs are run again")
        bad = []
    elif bad:
        notes.append(
            f"{len(bad)} unreadable part(s) ({', '.join(p.name for p in bad)}): `fibersweep run` "
            "moves them to a quarantine-* folder and runs their runs again"
        )
    runs = read_runs(out, skip=bad)
    have_results = len(runs) > 0
    changes: list[str] = []
    if manifest is not None and "result_settings" in manifest:
        changes = diff_settings(manifest["result_settings"], result_settings(cfg, flow_key))
        old_cls = manifest.get("config", {}).get("fiber", {}).get("classify")
        new_cls = cfg.fiber.classify.model_dump(mode="json")
        if old_cls is not None and old_cls != new_cls and have_results:
            notes.append(
                "classification thresholds differ from the stored ones ("
                + "; ".join(diff_settings(old_cls, new_cls, "fiber.classify"))
                + "): stored classes keep the old thresholds; run `fibersweep classify` "
                "to re-label them (needs recorded trajectories)"
            )
    elif have_results:
        changes = ["manifest.json missing: cannot tell which settings made the stored runs"]

    if changes and have_results and resume:
        ids_now = {t.key for t in tasks}
        old_same_point = _points_redone(runs, tasks)
        raise InputError(
            f"{out}: the stored results were made with other settings:\n    "
            + "\n    ".join(changes)
            + f"\n  {old_same_point} of the {len(runs)} stored runs would be redone "
            f"({len(ids_now)} runs in this sweep, none reusable). Use --no-resume to "
            "start over (the old results are moved to a 'previous-*' folder inside the "
            "output directory), or set run.output to a new directory."
        )

    fresh = not resume and have_results
    if fresh:
        runs = runs.iloc[0:0]
    status = dict(zip(runs["id"], runs["status"], strict=True))
    if cfg.fiber.record.trajectories and (bad or any(out.glob(f"quarantine-*/{TRAJ_DIR}"))):
        # A trajectory part was lost: its ids are unknown, so every ok run without a
        # trajectory is run again (the new row and trajectory replace the old row).
        have = trajectory_ids(out, skip=bad)
        lost = [i for i, st in status.items() if st == "ok" and i not in have]
        for i in lost:
            del status[i]
        if lost:
            notes.append(f"{len(lost)} run(s) lost their trajectory and are run again")
    ids = {t.key for t in tasks}
    done_ok = sum(1 for t in tasks if status.get(t.key) == "ok")
    done_failed = sum(1 for t in tasks if status.get(t.key) == "failed")
    if retry_failed:
        todo = [t for t in tasks if status.get(t.key) == "failed"]
    else:
        todo = [t for t in tasks if t.key not in status]
    ok_times = runs.loc[runs["status"] == "ok", "wall_time"].to_numpy(dtype=float)
    mean = float(np.mean(ok_times)) if ok_times.size else None
    return SweepPlan(
        out=out,
        tasks=tasks,
        todo=todo,
        done_ok=done_ok,
        done_failed=done_failed,
        kept_other=int(sum(1 for i in status if i not in ids)),
        changes=changes,
        notes=notes,
        mean_run_s=mean,
        fresh=fresh,
    )


def _points_redone(runs: Any, tasks: list[SweepTask]) -> int:
    """How many stored runs share a start with a point of the new sweep."""
    pts = {(round(t.theta0, 9), round(t.y0, 9), round(t.length, 9)) for t in tasks}
    return int(
        sum(
            (round(a, 9), round(b, 9), round(c, 9)) in pts
            for a, b, c in zip(runs["theta0"], runs["y0"], runs["length"], strict=True)
        )
    )


def move_aside(out: Path) -> Path | None:
    """Move the runs, trajectories and manifest of ``out`` into ``out/previous-<time>/``."""
    out = Path(out)
    items = [
        out / n for n in (RUNS_DIR, TRAJ_DIR, "manifest.json", "counts.csv") if (out / n).exists()
    ]
    if not items:
        return None
    dest = out / time.strftime("previous-%Y%m%dT%H%M%S", time.gmtime())
    k = 1
    while dest.exists():
        dest = dest.with_name(dest.name.split(".")[0] + f".{k}")
        k += 1
    dest.mkdir(parents=True)
    for p in items:
        shutil.move(str(p), str(dest / p.name))
    log.info("moved old results to %s", dest)
    return dest
