"""Run a sweep: flow field from the cache, tasks to an executor, rows to Parquet.

One code path for the bookkeeping whatever the executor: outcomes stream back
from :mod:`fibersweep.sweep.executors` and are written here, with the same
atomic part files, resume and retry logic.
"""

from __future__ import annotations

import logging
import time
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fibersweep.config import Config
from fibersweep.errors import ResultsError
from fibersweep.fiber.result import CLASSES
from fibersweep.sweep.executors import executor_for_run
from fibersweep.sweep.fields import (
    combinations_entry,
    prepare,
)
from fibersweep.sweep.lock import output_lock
from fibersweep.sweep.manifest import provenance, read_manifest, write_manifest
from fibersweep.sweep.plan import (
    SweepPlan,
    keeps_trajectories,
    move_aside,
    plan_sweep,
    result_settings,
)
from fibersweep.sweep.refine import next_round, stored_rounds
from fibersweep.sweep.store import (
    PartWriter,
    clean_temporaries,
    compact,
    describe_os_error,
    read_runs,
    rewrite_runs,
)
from fibersweep.sweep.worker import (
    SettingSpec,
    SweepTask,
    WorkerSpec,
    failed_row,
    init_worker,
    run_task,
)

__all__ = [
    "SweepSummary",
    "run_sweep",
]

log = logging.getLogger(__name__)


@dataclass
class SweepSummary:
    """What one ``run_sweep`` call did.

    Attributes
    ----------
    out : Path
    ran : int
        Runs finished in this call (ok or failed).
    counts : Counter
        Runs per class in this call ('failed' for failures).
    table_counts : dict
        Runs per class in the whole table afterwards.
    failed : int
        Failed runs in the whole table afterwards.
    wall_s : float
        Seconds spent running tasks.
    interrupted : bool
    """

    out: Path
    ran: int = 0
    counts: Counter = field(default_factory=Counter)
    table_counts: dict[str, int] = field(default_factory=dict)
    failed: int = 0
    wall_s: float = 0.0
    interrupted: bool = False
    failures: list[str] = field(default_factory=list)
    refinement: dict[str, Any] | None = None


def run_sweep(
    cfg: Config,
    *,
    resume: bool = True,
    retry_failed: bool = False,
    progress: Callable[[Mapping[str, Any]], None] | None = None,
    on_plan: Callable[[SweepPlan], None] | None = None,
    overrides: Sequence[str] = (),
    on_round: Callable[[int, SweepPlan], None] | None = None,
) -> SweepSummary:
    """Run every to-do point of a sweep and record it; then refine, round by round.

    With ``sweep.refine``, each round reads the classes of the stored runs and
    bisects the brackets wider than the tolerance (:func:`fibersweep.sweep.refine.propose`);
    its points are ordinary runs of the same table (column ``round``). The rounds
    are derived again from the stored runs on every call, so a second call
    continues an interrupted refinement without running anything twice.

    Parameters
    ----------
    cfg : Config
        Resolved config (``cfg.run`` says workers, executor, output).
    resume, retry_failed : bool
        See :func:`fibersweep.sweep.plan.plan_sweep`.
    progress : callable, optional
        Called with each finished row (for a progress bar).
    on_plan : callable, optional
        Called with the plan before anything runs.
    overrides : sequence of str
        The command line's ``KEY=VALUE`` overrides, recorded in the manifest as
        given (``cfg`` already has them applied).
    on_round : callable, optional
        Called with the round number and its plan before a refinement round runs.

    Returns
    -------
    SweepSummary
        ``interrupted`` is set (and the exception re-raised) on Ctrl-C; every run
        finished before it is on disk.
    """
    out = Path(cfg.run.output)
    with output_lock(out, "run"):
        return _run_locked(cfg, out, resume, retry_failed, progress, on_plan, overrides, on_round)


def _run_locked(
    cfg: Config,
    out: Path,
    resume: bool,
    retry_failed: bool,
    progress: Callable[[Mapping[str, Any]], None] | None,
    on_plan: Callable[[SweepPlan], None] | None,
    overrides: Sequence[str] = (),
    on_round: Callable[[int, SweepPlan], None] | None = None,
) -> SweepSummary:
    fields, plan = prepare(cfg, resume=resume, retry_failed=retry_failed)
    refine = cfg.sweep.refine
    extra: list[SweepTask] = []
    rnd = 0
    if refine is not None and not plan.fresh:  # continue from the stored rounds
        extra, rnd, _ = stored_rounds(refine, plan.settings, plan.tasks, read_runs(out))
        if extra:
            plan = plan_sweep(cfg, None, retry_failed=retry_failed, repair=True, extra=extra)
    if on_plan is not None:
        on_plan(plan)
    if plan.fresh:
        move_aside(out)
    clean_temporaries(out)
    old = read_manifest(out) or {}
    first = plan.settings[0]
    fieldobj, info = fields[first.flow_key]
    combos = combinations_entry(plan, fields, old)
    prov = provenance(info.key)
    base_key = first.flow_key if not _flow_swept(plan.columns) else _base_key(cfg)
    manifest = {
        "config": cfg.model_dump(mode="json"),
        "overrides": list(overrides),
        "result_settings": result_settings(cfg, base_key),
        "provenance": prov,
        "flow_cache": str(getattr(info, "path", "")),
        "separatrix": combos[first.id]["separatrix"],
        "u_center_effective": combos[first.id]["u_center_effective"],
        "sweep_size": len(plan.tasks),
        "swept": plan.columns,
        "flow_keys": list(fields),
        "combinations": combos,
        "state": "running",
    }
    write_manifest(out, manifest)
    meta = {
        "fibersweep": prov["fibersweep"],
        "git": prov["git"],
        "git_from": prov["git_from"],
        "flow_key": info.key,
        "flow_keys": list(fields),
        "swept": plan.columns,
        "config": manifest["config"],
        "overrides": manifest["overrides"],
    }
    summary = SweepSummary(out=out)
    # a refinement round may run any setting: every one is set up
    needed = {t.settings for t in (plan.tasks if refine is not None else plan.todo)}
    spec = WorkerSpec(
        log_level=logging.getLogger("fibersweep").getEffectiveLevel(),
        settings=tuple(
            SettingSpec(
                settings=st.id,
                flow_key=st.flow_key,
                flow_json=st.config.flow.model_dump_json(),
                field_path=str(Path(fields[st.flow_key][1].path).resolve()),
                fiber_json=st.config.fiber.model_dump_json(),
            )
            for st in plan.settings
            if st.id in needed
        ),
    )
    # rounds reuse the workers (every executor can keep them)
    keep = refine is not None
    ex = executor_for_run(cfg.run, keep=keep)
    # workers leave Ctrl-C to us when the executor says we handle it (the local pool)
    initargs = (spec, ex.parent_handles_ctrl_c)
    # an array run always keeps its trajectory: its mode is re-labelled from it
    keep_traj, _ = keeps_trajectories(cfg)
    t0 = time.perf_counter()
    state = "stopped"
    writer = PartWriter(out, meta, cfg.run.flush_every, cfg.run.flush_seconds)
    writer.start_timer()
    try:
        while True:  # the grid, then each refinement round
            _run_batch(ex, plan.todo, initargs, writer, keep_traj, summary, progress)
            if refine is None:
                break
            new, summary.refinement = _refine_step(cfg, out, plan, writer, rnd, retry_failed)
            manifest["refinement"] = summary.refinement
            if not new:
                break
            rnd += 1
            extra += new
            plan = plan_sweep(cfg, None, retry_failed=retry_failed, repair=True, extra=extra)
            if on_round is not None:
                on_round(rnd, plan)
    except KeyboardInterrupt:  # Ctrl-C, or SIGTERM (errors.Terminated)
        summary.interrupted = True
        state = "interrupted"
        if summary.refinement is not None:
            summary.refinement["stopped"] = "interrupted"
        raise
    else:
        state = "complete"
    finally:
        summary.wall_s = time.perf_counter() - t0
        manifest["sweep_size"] = len(plan.tasks)
        if keep:
            ex.close()  # type: ignore[attr-defined]
        _finish(cfg, out, meta, manifest, writer, state, summary, plan)
    log.info("sweep done: %d runs in %.1f s", summary.ran, summary.wall_s)
    return summary


def _run_batch(
    ex: Any,
    todo: list[SweepTask],
    initargs: tuple,
    writer: PartWriter,
    keep_traj: bool,
    summary: SweepSummary,
    progress: Callable[[Mapping[str, Any]], None] | None,
) -> None:
    """Run ``todo`` on the executor; queue each row (and trajectory) for writing."""
    if not todo:
        return
    by_key = {t.key: t for t in todo}
    for oc in ex.run(run_task, todo, init_worker, initargs):
        if oc.value is not None:
            row, traj = dict(oc.value["row"]), oc.value["trajectory"]
            row["attempts"] = oc.attempts
        else:
            row, traj = failed_row(by_key[oc.key], oc.error, oc.attempts), None
        writer.add(row, traj if keep_traj else None)
        summary.ran += 1
        label = row["class"] if row["status"] == "ok" else "failed"
        summary.counts[label] += 1
        if row["status"] != "ok":
            summary.failures.append(f"{row['id']}: {row['reason']}")
        if progress is not None:
            progress(row)


def _refine_step(
    cfg: Config, out: Path, plan: SweepPlan, writer: PartWriter, rnd: int, retry_failed: bool
) -> tuple[list[SweepTask], dict[str, Any]]:
    """Write what ran, read the classes back, and make the next round's tasks."""
    if not writer.flush():
        return [], {"stopped": "unsaved", "rounds": rnd}
    stored = read_runs(out)
    assert cfg.sweep.refine is not None
    new, info = next_round(cfg.sweep.refine, plan.settings, plan.tasks, stored, rnd)
    have = set(stored["id"])
    not_run = sum(t.key not in have for t in [*plan.tasks, *new])
    if retry_failed and not_run:
        # --retry-failed runs no new point: a plain run continues the refinement
        info.update(stopped="retry-failed", not_run=not_run)
        return [], info
    return new, info


def _flow_swept(columns: list[str]) -> bool:
    return any(k.startswith("flow.") for k in columns)


def _base_key(cfg: Config) -> str:
    from fibersweep.flow.cache import cache_key

    return cache_key(cfg.flow)


def _fill_setting_columns(out: Path, meta: dict[str, Any], table: Any, plan: SweepPlan) -> Any:
    """Give stored runs of this sweep the swept keys' columns they lack.

    Runs made before a setting was swept (or before another folder's key was)
    have no value in its column; a run of this sweep is known by its id, so its
    values are those of its task. Rewritten as one merged part when anything changed.
    """
    by_id = {t.key: t for t in plan.tasks}
    changed = False
    table = table.copy()
    for name in ["settings", *plan.columns]:
        if name not in table:
            table[name] = None
        col = table[name].astype(object)
        missing = col.isna().to_numpy() | (col == "").to_numpy()
        for i in missing.nonzero()[0]:
            task = by_id.get(table.at[i, "id"])
            if task is not None:
                value = task.columns().get(name)
                if value is not None:
                    col.iat[i] = value
                    changed = True
        table[name] = col
    if changed:
        try:
            rewrite_runs(out, table, meta)
        except OSError as exc:
            log.warning("swept-setting columns not filled in (%s)", describe_os_error(exc))
    return table


def _finish(
    cfg: Config,
    out: Path,
    meta: dict[str, Any],
    manifest: dict[str, Any],
    writer: PartWriter,
    state: str,
    summary: SweepSummary,
    plan: SweepPlan | None = None,
) -> None:
    """Write what is left, compact, and record the outcome in the manifest.

    Whatever fails here (a full disk) leaves the table readable: parts are atomic,
    and runs that could not be written are reported by :class:`ResultsError`.
    """
    unsaved: ResultsError | None = None
    try:
        writer.close()
    except ResultsError as exc:
        unsaved, state = exc, "unsaved"
    if state == "complete" and cfg.run.compact:
        try:
            compact(out, meta)
        except OSError as exc:  # the parts stay; readers merge them
            log.warning("parts not merged (%s)", describe_os_error(exc))
    table = read_runs(out)
    if plan is not None and plan.columns and unsaved is None:
        table = _fill_setting_columns(out, meta, table, plan)
    ok = table[table["status"] == "ok"]
    if "mode" in ok and ok["mode"].notna().any():  # pillar-array runs: their modes
        from fibersweep.analysis.modes import MODES

        summary.table_counts = {m: int((ok["mode"] == m).sum()) for m in MODES}
    else:
        summary.table_counts = {c: int((ok["class"] == c).sum()) for c in CLASSES}
        other = int((~ok["class"].isin(CLASSES)).sum())
        if other:
            summary.table_counts["unclassified"] = other
    summary.failed = int((table["status"] != "ok").sum())
    manifest.update(
        state=state,
        finished=time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        counts=summary.table_counts,
        failed=summary.failed,
        rows=len(table),
        unsaved=writer.pending,
    )
    try:
        write_manifest(out, manifest)
    except OSError as exc:
        log.error("manifest not updated (%s)", describe_os_error(exc))
    if unsaved is not None:
        raise unsaved
