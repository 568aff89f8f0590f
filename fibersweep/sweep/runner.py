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
from fibersweep.sweep.executors import make_executor
from fibersweep.sweep.lock import output_lock
from fibersweep.sweep.manifest import provenance, read_manifest, write_manifest
from fibersweep.sweep.plan import SweepPlan, move_aside, plan_sweep, result_settings
from fibersweep.sweep.store import (
    PartWriter,
    clean_temporaries,
    compact,
    describe_os_error,
    read_runs,
)
from fibersweep.sweep.worker import SweepTask, WorkerSpec, failed_row, init_worker, run_task

__all__ = [
    "SweepSummary",
    "estimate_run_s",
    "flow_field_for",
    "flow_key_for",
    "prepare",
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


def flow_field_for(cfg: Config, *, mmap: bool = True) -> tuple[Any, Any]:
    """The flow field of a config from the cache (computed once if missing)."""
    from fibersweep.flow.cache import get_flow_field

    return get_flow_field(cfg.flow, cfg.run.cache_dir, mmap=mmap)


def flow_key_for(cfg: Config) -> tuple[str, bool]:
    """The flow-field key of a config and whether the field is cached (computes nothing)."""
    from fibersweep.flow.cache import MANIFEST, cache_key

    key = cache_key(cfg.flow)
    # A complete cache entry is flow-<key>/ with its manifest written last.
    return key, (Path(cfg.run.cache_dir) / f"flow-{key}" / MANIFEST).exists()


def estimate_run_s(cfg: Config, todo: list[SweepTask]) -> float | None:
    """Seconds per run, timed here on the middle to-do point after one warm-up run."""
    from fibersweep.fiber.result import FiberStart
    from fibersweep.fiber.run import simulate

    fieldobj, _ = flow_field_for(cfg)
    t = todo[len(todo) // 2]
    start = FiberStart(theta0=t.theta0, y0=t.y0, length=t.length)
    simulate(fieldobj, cfg.fiber, start)  # compiles
    t0 = time.perf_counter()
    simulate(fieldobj, cfg.fiber, start)
    return time.perf_counter() - t0


def prepare(
    cfg: Config, *, resume: bool = True, retry_failed: bool = False
) -> tuple[Any, Any, SweepPlan]:
    """Field, cache info and plan of a sweep (computes the field if it is not cached)."""
    fieldobj, info = flow_field_for(cfg)
    plan = plan_sweep(cfg, info.key, resume=resume, retry_failed=retry_failed, repair=True)
    return fieldobj, info, plan


def effective_u_center(fieldobj: Any, fiber: Any) -> float:
    """U_center [µm/s] the runs move in: the field's after the effects that change it.

    The classification thresholds are fractions of this speed; ``classify``
    re-applies them later from the manifest, so it must be the run's own.
    """
    from fibersweep.fiber.effects import build_effects

    return float(build_effects(fiber.effects).field(fieldobj).fluid.u_center)


def _separatrix(fieldobj: Any, info: Any, out: Path) -> float | None:
    old = read_manifest(out) or {}
    if old.get("provenance", {}).get("flow_key") == info.key and "separatrix" in old:
        return old["separatrix"]
    try:
        from fibersweep.flow.streamlines import separatrix_y

        return float(separatrix_y(fieldobj))
    except Exception as exc:  # a figure aid: never stop a sweep over it
        log.warning("separatrix not computed: %s", exc)
        return None


def run_sweep(
    cfg: Config,
    *,
    resume: bool = True,
    retry_failed: bool = False,
    progress: Callable[[Mapping[str, Any]], None] | None = None,
    on_plan: Callable[[SweepPlan], None] | None = None,
    overrides: Sequence[str] = (),
) -> SweepSummary:
    """Run every to-do point of a sweep and record it.

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

    Returns
    -------
    SweepSummary
        ``interrupted`` is set (and the exception re-raised) on Ctrl-C; every run
        finished before it is on disk.
    """
    out = Path(cfg.run.output)
    with output_lock(out, "run"):
        return _run_locked(cfg, out, resume, retry_failed, progress, on_plan, overrides)


def _run_locked(
    cfg: Config,
    out: Path,
    resume: bool,
    retry_failed: bool,
    progress: Callable[[Mapping[str, Any]], None] | None,
    on_plan: Callable[[SweepPlan], None] | None,
    overrides: Sequence[str] = (),
) -> SweepSummary:
    fieldobj, info, plan = prepare(cfg, resume=resume, retry_failed=retry_failed)
    if on_plan is not None:
        on_plan(plan)
    if plan.fresh:
        move_aside(out)
    clean_temporaries(out)
    prov = provenance(info.key)
    manifest = {
        "config": cfg.model_dump(mode="json"),
        "overrides": list(overrides),
        "result_settings": result_settings(cfg, info.key),
        "provenance": prov,
        "flow_cache": str(getattr(info, "path", "")),
        "separatrix": _separatrix(fieldobj, info, out),
        "u_center_effective": effective_u_center(fieldobj, cfg.fiber),
        "sweep_size": len(plan.tasks),
        "state": "running",
    }
    write_manifest(out, manifest)
    meta = {
        "fibersweep": prov["fibersweep"],
        "git": prov["git"],
        "flow_key": info.key,
        "config": manifest["config"],
        "overrides": manifest["overrides"],
    }
    summary = SweepSummary(out=out)
    spec = WorkerSpec(
        flow_json=cfg.flow.model_dump_json(),
        field_path=str(Path(info.path).resolve()),
        flow_key=info.key,
        fiber_json=cfg.fiber.model_dump_json(),
        log_level=logging.getLogger("fibersweep").getEffectiveLevel(),
    )
    ex = make_executor(cfg.run.executor, cfg.run.workers, cfg.run.scheduler, cfg.run.retries)
    # Dask workers keep their own signal handling; pool workers leave Ctrl-C to us.
    initargs = (spec, cfg.run.executor == "local")
    by_key: dict[str, SweepTask] = {t.key: t for t in plan.todo}
    keep_traj = cfg.fiber.record.trajectories
    t0 = time.perf_counter()
    state = "stopped"
    writer = PartWriter(out, meta, cfg.run.flush_every, cfg.run.flush_seconds)
    writer.start_timer()
    try:
        if plan.todo:
            for oc in ex.run(run_task, plan.todo, init_worker, initargs):
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
    except KeyboardInterrupt:  # Ctrl-C, or SIGTERM (errors.Terminated)
        summary.interrupted = True
        state = "interrupted"
        raise
    else:
        state = "complete"
    finally:
        summary.wall_s = time.perf_counter() - t0
        _finish(cfg, out, meta, manifest, writer, state, summary)
    log.info("sweep done: %d runs in %.1f s", summary.ran, summary.wall_s)
    return summary


def _finish(
    cfg: Config,
    out: Path,
    meta: dict[str, Any],
    manifest: dict[str, Any],
    writer: PartWriter,
    state: str,
    summary: SweepSummary,
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
    ok = table[table["status"] == "ok"]
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
