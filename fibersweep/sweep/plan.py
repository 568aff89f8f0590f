"""What a sweep has to do: every run's id, what is already done, what changed.

Pure bookkeeping (no simulation), shared by ``fibersweep run`` (local pool or
Dask) and ``--dry-run``.
"""

from __future__ import annotations

import copy
import logging
import shutil
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fibersweep.config import Combination, Config
from fibersweep.errors import InputError
from fibersweep.sweep.ids import diff_settings, fiber_result_settings, run_ids, settings_id
from fibersweep.sweep.manifest import read_manifest
from fibersweep.sweep.starts import PHYSICS
from fibersweep.sweep.store import (
    RUNS_DIR,
    TRAJ_DIR,
    expected_data,
    kept_data,
    quarantine,
    read_runs,
    trajectory_ids,
    unreadable_parts,
)
from fibersweep.sweep.worker import SweepTask

__all__ = [
    "Setting",
    "SweepPlan",
    "base_settings",
    "make_tasks",
    "move_aside",
    "keeps_trajectories",
    "plan_sweep",
    "result_settings",
    "sweep_settings",
]

log = logging.getLogger(__name__)


def _other_revision(manifest: dict[str, Any] | None, resuming: bool) -> str | None:
    """A note when the stored runs come from another fibersweep revision than this one.

    Settings are compared on resume, the model's code is not: a physics change
    between the two revisions (a bug fix, a new force) would leave old runs beside
    new ones under the same ids. The note says so; it is not an error, since most
    revisions change no result.
    """
    from fibersweep.sweep.manifest import revision

    if not resuming or manifest is None:
        return None
    old = (manifest.get("provenance") or {}).get("git")
    now, _ = revision()
    if old is None or now is None or old == now:
        return None
    return (
        f"the stored runs were made by fibersweep revision {old[:12]}, this is {now[:12]}: "
        "a change of the model between the two is not detected; if one changed results, "
        "run again with --no-resume"
    )


def keeps_trajectories(cfg: Config) -> tuple[bool, bool]:
    """Whether each run of ``cfg`` stores its trajectory, and its beads' positions.

    A pillar array's run always keeps its trajectory (its mode is re-labelled from
    it); see :func:`fibersweep.sweep.store.kept_data`.
    """
    return kept_data(cfg.model_dump(mode="json", include={"flow": {"array"}, "fiber": True}))


def result_settings(cfg: Config, flow_key: str) -> dict[str, Any]:
    """Everything that changes results, as stored in the manifest and compared on resume.

    For a sweep over settings: its base config's (the swept keys are masked when
    compared, :func:`base_settings`).
    """
    return {"flow_key": flow_key, "fiber": fiber_result_settings(cfg.fiber)}


def base_settings(
    config_json: dict[str, Any], flow_key: str | None, swept: Sequence[str]
) -> dict[str, Any]:
    """The result settings of a config with the swept keys left out, for the resume check.

    Parameters
    ----------
    config_json : dict
        A config as JSON (``Config.model_dump(mode="json")`` or a manifest's).
    flow_key : str or None
        Its flow field's key, compared when no flow setting is swept.
    swept : sequence of str
        Dotted keys swept by the stored sweeps or this one: they may differ.

    Returns
    -------
    dict
        ``{"flow_key": ..., "fiber": ...}``, or ``{"flow": ..., "fiber": ...}`` with
        the flow settings themselves when a flow setting is swept (its key differs
        per run then).
    """
    from fibersweep.flow.cache import key_settings

    fiber = copy.deepcopy(config_json.get("fiber", {}))
    fiber.pop("classify", None)
    out: dict[str, Any] = {"fiber": fiber}
    flow_swept = any(k.startswith("flow.") for k in swept)
    if flow_swept:  # as in the cache key: a manifest from before a key was added matches
        out["flow"] = key_settings(config_json.get("flow", {}))
    else:
        out["flow_key"] = flow_key
    for key in swept:
        parts = key.split(".")
        node = out.get(parts[0])
        for part in parts[1:-1]:
            node = node.get(part) if isinstance(node, dict) else None
        if isinstance(node, dict):
            node.pop(parts[-1], None)
    return out


@dataclass(frozen=True)
class Setting:
    """One setting combination of a sweep.

    Attributes
    ----------
    id : str
        Settings id (:func:`fibersweep.sweep.ids.settings_id`).
    combination : Combination
        The swept values and the config they make.
    flow_key : str
        Its flow field's key.
    """

    id: str
    combination: Combination
    flow_key: str

    @property
    def config(self) -> Config:
        return self.combination.config


def sweep_settings(cfg: Config, flow_key: str | Sequence[str] | None = None) -> list[Setting]:
    """The setting combinations of a sweep, grouped by flow field (first seen first).

    Parameters
    ----------
    cfg : Config
    flow_key : str, sequence of str or None
        Flow keys of :meth:`Config.combinations` (one string: the same for all);
        None: each combination's own (:func:`fibersweep.flow.cache.cache_key`,
        nothing computed).
    """
    combos = cfg.combinations(PHYSICS)
    if flow_key is None:
        from fibersweep.flow.cache import cache_key

        keys = [cache_key(c.config.flow) for c in combos]
    elif isinstance(flow_key, str):
        keys = [flow_key] * len(combos)
    else:
        keys = list(flow_key)
    out = [Setting(settings_id(c.config.fiber, k), c, k) for c, k in zip(combos, keys, strict=True)]
    order = {k: i for i, k in reversed(list(enumerate(keys)))}
    return sorted(out, key=lambda s: order[s.flow_key])  # stable: axis order within a field


def make_tasks(
    cfg: Config,
    flow_key: str | Sequence[str] | None = None,
    columns: Sequence[str] | None = None,
    settings: Sequence[Setting] | None = None,
) -> list[SweepTask]:
    """One task per distinct run (a repeated value or point is run once).

    Parameters
    ----------
    cfg : Config
    flow_key : str, sequence of str or None
        See :func:`sweep_settings`.
    columns : sequence of str, optional
        Swept keys whose values each task carries (default: this sweep's); a
        folder that also holds other sweeps' keys names them all.
    settings : sequence of Setting, optional
        :func:`sweep_settings`'s result, if already made.

    Returns
    -------
    list of SweepTask
        Setting by setting (grouped by flow field), each in start order.
    """
    settings = sweep_settings(cfg, flow_key) if settings is None else settings
    columns = cfg.sweep.setting_keys if columns is None else list(columns)
    from fibersweep.sweep.draws import start_points

    tasks: dict[str, SweepTask] = {}
    t, y, L = start_points(cfg)
    for st in settings:
        if cfg.sweep.random is not None and st.combination.values:
            t, y, L = start_points(st.config)  # redraws depend on the combination
        values: tuple[tuple[str, Any], ...] = ()
        if columns:
            dumped = st.config.model_dump(mode="json")
            values = tuple((k, st.combination.values.get(k, _get(dumped, k))) for k in columns)
        ids = run_ids(t, y, L, st.config.fiber, st.flow_key)
        for rid, ti, yi, Li in zip(ids, t.tolist(), y.tolist(), L.tolist(), strict=True):
            if rid not in tasks:
                tasks[rid] = SweepTask(rid, ti, yi, Li, st.id, st.flow_key, values)
    return list(tasks.values())


def _get(data: Any, key: str) -> Any:
    """A config's value of a dotted key (an effect left out is at its baseline, 0)."""
    for part in key.split("."):
        data = data.get(part) if isinstance(data, dict) else None
    if data is None and key.startswith("fiber.effects."):
        return 0.0
    return data


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
    settings : list of Setting
        The sweep's setting combinations (one without setting axes).
    columns : list of str
        Swept keys of the folder: this sweep's and the stored sweeps' (one
        runs-table column each).
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
    settings: list[Setting] = field(default_factory=list)
    columns: list[str] = field(default_factory=list)

    def estimate_s(self, workers: int) -> float | None:
        """Wall-clock estimate for ``todo`` on ``workers`` workers [s] (None if unknown)."""
        if self.mean_run_s is None:
            return None
        return self.mean_run_s * len(self.todo) / max(1, min(workers, max(1, len(self.todo))))


def plan_sweep(
    cfg: Config,
    flow_key: str | Sequence[str] | None = None,
    *,
    resume: bool = True,
    retry_failed: bool = False,
    repair: bool = False,
    extra: Sequence[SweepTask] = (),
) -> SweepPlan:
    """Compare a config with its output directory and decide what to run.

    Parameters
    ----------
    cfg : Config
    flow_key : str, sequence of str or None
        Hash of the flow field, or one per setting combination; None: computed
        from the settings (:func:`sweep_settings`).
    resume : bool
        Keep finished runs (default). False starts over; old results are moved
        aside by :func:`move_aside`, never deleted.
    retry_failed : bool
        Run only the points recorded as failed.
    repair : bool
        Move unreadable parts into a ``quarantine-*`` folder (their runs are then
        to do). When False (a dry run) they are only left out and reported.
    extra : sequence of SweepTask
        Points beyond the grid (refinement rounds, :mod:`fibersweep.sweep.refine`),
        planned like the grid's (a point already in the grid is kept once).

    Raises
    ------
    InputError
        The output holds results made with different settings and ``resume`` is on.
    """
    out = Path(cfg.run.output)
    manifest = read_manifest(out)
    settings = sweep_settings(cfg, flow_key)
    swept = list(cfg.sweep.setting_keys)
    stored_swept = [k for k in (manifest or {}).get("swept", []) if k not in swept]
    columns = swept + stored_swept
    tasks = make_tasks(cfg, columns=columns, settings=settings)
    if extra:
        have = {t.key for t in tasks}
        tasks += [t for t in extra if t.key not in have]
    notes: list[str] = []
    bad = [p for p, _ in unreadable_parts(out)]
    if bad and repair:
        where = quarantine(out, bad)
        notes.append(
            f"{len(bad)} unreadable part(s) moved to {where}; the runs that lost their row "
            "or trajectory with them are run again"
        )
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
        if columns:  # settings swept here or before: compare the rest
            old_key = manifest["result_settings"].get("flow_key")
            changes = diff_settings(
                base_settings(manifest.get("config", {}), old_key, columns),
                base_settings(cfg.model_dump(mode="json"), settings[0].flow_key, columns),
            )
        else:
            changes = diff_settings(
                manifest["result_settings"], result_settings(cfg, settings[0].flow_key)
            )
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
    note = _other_revision(manifest, have_results and resume)
    if note:
        notes.append(note)

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
    lost = _lost_data(cfg, out, runs, tasks, bad)
    for i in lost:
        del status[i]  # not done: run again; its new row replaces the old (same id)
    if lost:
        how = (
            "; --retry-failed runs only failed runs: a plain `fibersweep run` runs them"
            if retry_failed
            else " and are run again"
        )
        notes.append(f"{len(lost)} ok run(s) lost their stored trajectory or beads{how}")
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
        settings=settings,
        columns=columns,
    )


def _lost_data(
    cfg: Config, out: Path, runs: Any, tasks: list[SweepTask], bad: list[Path]
) -> list[str]:
    """Ok runs of this sweep whose trajectory (or bead positions) the store should hold
    and does not: a trajectory part lost, moved aside or unreadable.

    Their rows are there, so they would count as done; they are run again instead
    (same ids: the new row and trajectory replace the old ones). A healthy folder
    has none, and nothing changes for it.
    """
    if runs.empty:
        return []
    need_traj, need_beads = expected_data(runs, cfg.model_dump(mode="json"))
    keys = {t.key for t in tasks}
    ids = runs["id"].to_numpy()
    ok = (runs["status"] == "ok").to_numpy() & np.array([i in keys for i in ids], bool)
    if not (ok & need_traj).any():
        return []
    have = np.isin(ids, list(trajectory_ids(out, skip=bad)))
    lost = ok & need_traj & ~have
    if (ok & need_beads).any():
        with_beads = np.isin(ids, list(trajectory_ids(out, skip=bad, with_column="beads")))
        lost |= ok & need_beads & ~with_beads
    return [str(i) for i in ids[lost]]


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
