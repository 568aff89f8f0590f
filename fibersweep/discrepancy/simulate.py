"""Batches of fiber runs for the discrepancy workflow, on the sweep's executors and workers.

The workflow makes many small batches (baseline copies, probes, each step of
a parameter fit). They go through the same executors as a sweep (the local
process pool or Dask, :mod:`fibersweep.sweep.executors`), kept open across
batches (``keep=True``), and run on the sweep's worker
(:func:`fibersweep.sweep.worker.run_batch`): (start, seed, effects, keep-track)
batches, the field memory-mapped from its cache entry once per worker process,
one error policy for every run. Every run has its own
seed (Brownian noise, start-noise effects), so a batch is reproducible whatever
the number of workers. A run that raises is recorded as ``status='failed'``
with the reason, never dropped. The number of runs is counted against a budget.

With ``Simulator(tracks=True)`` (measured tracks are compared), every run
records its trajectory (:data:`TRACK_SAMPLES` samples at least, whatever the
config's ``record`` says: it changes no other outcome) so that the track
observables (:mod:`fibersweep.analysis.observables`) are in every outcome table;
without, they are NaN and the runs skip that cost (~9 %).

Declared candidates (:mod:`.declared`): a batch's ``effects`` may name them
besides library effects. Their values are applied to the config's settings as
overrides (:func:`.declared.apply_values`); each distinct setting is made once
(a flow setting's field found in its cache or solved there) and travels with
the batch (:attr:`fibersweep.sweep.worker.RunBatch.setting`), so the pool
never restarts. A batch holds one setting; a batch of a flexible model is cut
into finer chunks (:data:`FLEXIBLE_CHUNKS`) so that its slow runs spread over
the workers instead of one worker finishing a long chunk alone.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Mapping, Sequence
from functools import partial
from typing import Any

import numpy as np
import pandas as pd

from fibersweep.analysis.observables import track_values
from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.array_observables import is_array_result
from fibersweep.discrepancy.array_starts import clear_starts
from fibersweep.discrepancy.candidates import Candidate
from fibersweep.discrepancy.declared import apply_values
from fibersweep.discrepancy.observables import OBSERVABLES, of_geometry
from fibersweep.errors import FibersweepError, InputError, SolverError
from fibersweep.fiber.result import CLASSES
from fibersweep.flow.field import FlowField
from fibersweep.progressbar import WarmingBar, finish, progress_bar
from fibersweep.sweep.executors import EXECUTORS, make_executor
from fibersweep.sweep.worker import (
    RunBatch,
    SettingSpec,
    WorkerSpec,
    init_worker,
    run_batch,
    setting_for_field,
)
from fibersweep.units import Geometry

__all__ = [
    "ARRAY_OUTCOME_COLUMNS",
    "OUTCOME_COLUMNS",
    "TRACK_SAMPLES",
    "Simulator",
    "BudgetExhausted",
    "is_array",
    "outcome_row",
]

log = logging.getLogger(__name__)

#: Outcome columns of a channel batch, one per channel observable, in registry order
#: (an array batch's: :data:`ARRAY_OUTCOME_COLUMNS`).
OUTCOME_COLUMNS = of_geometry("channel")
#: Outcome columns of a pillar-array batch (:mod:`.array_observables`).
ARRAY_OUTCOME_COLUMNS = of_geometry("array")

#: Fewest trajectory samples a run keeps for its track observables (a 2 s pass: one
#: sample per ~2 ms, ~1.2 µm of travel; linear interpolation at a station then errs
#: by far less than the 1 µm measurement noise).
TRACK_SAMPLES = 1000

#: Chunks per worker of a batch whose fiber model is not rigid (4 otherwise): a
#: flexible run costs more and varies more, so finer chunks keep the workers busy.
FLEXIBLE_CHUNKS = 16


def is_array(field: Any) -> bool:
    """Whether ``field`` is a pillar array's unit cell (a CellField: it has ``array``)."""
    return getattr(field, "array", None) is not None


class BudgetExhausted(FibersweepError):
    """The simulation budget does not allow the requested batch."""


def outcome_row(
    result: Any, geometry: Geometry | None = None, array: bool | None = None
) -> dict[str, Any]:
    """Observable values of a RunResult (registry order), missing for a failed run.

    Values follow :mod:`fibersweep.discrepancy.observables` (class name, contact
    0.0/1.0, floats in the observables' units); plus ``status`` and ``reason``.

    Parameters
    ----------
    result : RunResult
    geometry : Geometry, optional
        Channel and pillar of the run's (baseline) field; with it and
        ``result.trajectory`` the track observables are derived
        (:func:`fibersweep.analysis.observables.track_values`), else NaN. NaN as
        well for Trapping (their NaN rule).
    array : bool, optional
        The run went through a pillar array: the array observables
        (:data:`ARRAY_OUTCOME_COLUMNS`) [default: whether ``result`` has a mode;
        a run that failed before it started has none, so the batch says].
    """
    if array or (array is None and is_array_result(result)):  # its own observables, no tracks
        ok = result.status == "ok" and is_array_result(result)
        row = {n: OBSERVABLES[n].outcome(result if ok else None) for n in of_geometry("array")}
        row["status"] = "ok" if ok else "failed"
        row["reason"] = "" if ok else (result.reason or "failed")
        return row
    ok = result.status == "ok" and result.cls in CLASSES
    tracks = None
    traj = getattr(result, "trajectory", None)
    if ok and geometry is not None and traj is not None and result.cls != "Trapping":
        tracks = track_values(traj.t, traj.x, traj.y, traj.theta, geometry, result.start.length)
    row = {n: OBSERVABLES[n].outcome(result if ok else None, tracks) for n in of_geometry()}
    row["status"] = "ok" if ok else "failed"
    row["reason"] = "" if ok else (result.reason or f"class {result.cls!r}")
    return row


def frames(traj: Any, fps: float) -> dict[str, np.ndarray] | None:
    """A trajectory as a camera samples it (no noise): uniform frames from its start.

    Parameters
    ----------
    traj : Trajectory or None
    fps : float
        Frame rate [1/s].

    Returns
    -------
    dict 't', 'x', 'y', 'theta' -> ndarray, shape (f,), or None without a trajectory
        Times [s] ``k / fps`` up to the run's end, centre [µm] and angle [deg]
        interpolated linearly in time.
    """
    if traj is None or len(traj.t) < 2:
        return None
    t = traj.t[0] + np.arange(int(np.floor((traj.t[-1] - traj.t[0]) * fps)) + 1) / fps
    return {"t": t, **{c: np.interp(t, traj.t, getattr(traj, c)) for c in ("x", "y", "theta")}}


def _failed(reason: str, array: bool = False) -> dict[str, Any]:
    row = {n: OBSERVABLES[n].outcome(None) for n in of_geometry("array" if array else "channel")}
    row.update(status="failed", reason=reason)
    return row


def batch_outcome(result: Any, field: FlowField, tracks: bool, fps: float | None) -> dict[str, Any]:
    """What a worker returns per run of a batch: the outcome row, and its track with ``fps``.

    The ``reduce`` of the workflow's :class:`~fibersweep.sweep.worker.RunBatch`
    (top-level: it pickles by name). Positions are the effects' own report
    (``pillar_scale`` rescales the trajectory itself).
    """
    array = is_array(field)
    row = outcome_row(result, field.geometry if tracks and not array else None, array)
    if fps is not None:
        row["track"] = frames(result.trajectory, fps)
    return row


class Simulator:
    """Runs batches of fibers at given starts and effects; counts runs against a budget.

    Parameters
    ----------
    field : FlowField
        Baseline flow field (effects that change the field apply inside the run).
    settings : FiberSettings
        Baseline fiber settings; each batch replaces ``effects``.
    workers : int
        Worker processes; 1 with the local executor runs in this process.
    budget : int or None
        Most runs allowed in total (None: unlimited).
    progress : bool
        Show one tqdm progress bar over all batches (the stage in its label,
        the ETA against ``planned``).
    planned : int or None
        Runs the caller knows will run (the bar's length; default ``budget``);
        :meth:`expect` sets it stage by stage.
    tracks : bool
        Keep every run's trajectory and derive the track observables
        (:mod:`fibersweep.analysis.observables`), for measured tracks. False (the
        default) leaves them NaN and saves about 9 % of the run time.
    executor : str
        Executor name from :data:`fibersweep.sweep.executors.EXECUTORS`
        ('local' or 'dask').
    scheduler : str or None
        Dask scheduler address (dask executor only).
    candidates : sequence of Candidate
        Declared candidates a batch may name (:mod:`.declared`); library effects
        need none.
    flow : FlowSettings, optional
        The field's settings (for a declared flow candidate; default: the
        field's cache entry).
    cache_dir : str or Path, optional
        Flow cache where a declared flow candidate's field is found or solved.

    Use as a context manager so the workers are shut down.
    """

    def __init__(
        self,
        field: FlowField,
        settings: FiberSettings,
        workers: int = 2,
        budget: int | None = None,
        progress: bool = True,
        executor: str = "local",
        scheduler: str | None = None,
        planned: int | None = None,
        tracks: bool = False,
        candidates: Sequence[Candidate] = (),
        flow: Any = None,
        cache_dir: Any = None,
    ) -> None:
        if workers < 1:
            raise InputError(f"workers must be >= 1, got {workers}")
        self.field = field
        self.array = is_array(field)  # a pillar array's unit cell: array observables
        self.settings = settings
        self.workers = workers
        self.tracks = bool(tracks)
        self.budget = budget
        self.progress = progress
        self.used = 0
        self.failed = 0
        self.failed_by_stage: dict[str, int] = {}
        self.used_by_stage: dict[str, int] = {}  # runs per stage (first word of desc)
        self.seconds_by_stage: dict[str, float] = {}  # wall time per stage
        self.declared = {c.name: c for c in candidates if not c.is_effect}
        self._flow = flow
        self._cache_dir = cache_dir
        self._variants: dict[tuple, tuple[SettingSpec, FiberSettings]] = {}
        self._fields: dict[tuple, Any] = {}  # each variant's field (an array's start check)
        self._batches = 0
        self._planned = planned if planned is not None else budget
        self._later = 0  # runs later stages may add (said beside the bar)
        self._bar: Any = None
        # retries=0: a run that kills its worker is a failed run here, not re-run
        options: dict[str, Any] = {"keep": True}
        if executor in EXECUTORS and "inline" in EXECUTORS[executor].Options.model_fields:
            options["inline"] = workers == 1  # no pool to start for one worker
        self._executor = make_executor(executor, workers, scheduler, retries=0, **options)
        # the field travels as its cache entry (mapped by each worker) when it has one
        self._spec = WorkerSpec(settings=(setting_for_field(field, settings),), warm=False)
        self._initargs = (self._spec, self._executor.parent_handles_ctrl_c)

    def __enter__(self) -> Simulator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Stop the workers (and close the progress bar)."""
        if self._bar is not None:
            finish(self._bar)  # a workflow that stops early ends at its real total
            self._bar = None
        self._executor.close()

    def expect(self, runs: int, later: int = 0) -> None:
        """Set the bar's length to the runs done plus ``runs`` the next stages will run.

        Parameters
        ----------
        runs : int
            Most runs of the stages that will run now, whatever their outcome.
        later : int
            Most runs of stages that run only on some outcomes (said beside the bar,
            not counted in its length, so the estimate is of what will run).
        """
        self._planned = self.used + int(runs)
        self._later = int(later)
        if self._bar is not None:
            self._bar.total = max(self._planned, self._bar.n)
            self._bar.set_postfix_str(self._later_text(), refresh=True)

    def expect_more(self, runs: int) -> None:
        """Move ``runs`` of the later stages' runs into the bar's length (they now run)."""
        ahead = (self._planned or self.used) - self.used  # what :meth:`expect` last said
        self.expect(ahead + int(runs), later=max(0, self._later - int(runs)))

    def _later_text(self) -> str:
        return f"later stages: up to {self._later} more if needed" if self._later else ""

    def variant(self, values: Mapping[str, float]) -> tuple[SettingSpec | None, FiberSettings]:
        """The setting of declared candidate values (None and the config's for none on).

        Made once per distinct set of values; a changed flow setting's field is
        found in the flow cache or solved and stored there.
        """
        on = tuple(sorted((n, float(v)) for n, v in values.items() if float(v) != 0.0))
        if not on:
            return None, self.settings
        if on not in self._variants:
            from fibersweep.config.flow import FlowSettings

            flow = self._flow
            if flow is None:
                meta = (self.field.meta or {}).get("settings")
                flow = FlowSettings.model_validate(meta) if meta else FlowSettings()
            label = ", ".join(self.declared[n].show(v) for n, v in on)
            fiber, new_flow = apply_values(self.declared, dict(on), self.settings, flow, label)
            field = self.field
            if new_flow != flow:
                if self._cache_dir is None:
                    raise InputError(f"{label}: a flow candidate needs the flow cache folder")
                from fibersweep.flow.cache import get_flow_field

                log.info("flow field of %s (solved once, then cached)", label)
                field, _ = get_flow_field(new_flow, self._cache_dir)
            sid = f"candidate-{len(self._variants)}"
            self._variants[on] = (setting_for_field(field, fiber, sid), fiber)
            self._fields[on] = field
        return self._variants[on]

    def _clear(self, starts: np.ndarray, fiber: FiberSettings, rows: list) -> np.ndarray:
        """Indices of the array starts clear of every pillar; the others' rows failed.

        The run itself would refuse such a start (:class:`fibersweep.fiber.array_run.ArrayCase`);
        checking here spares a worker's traceback per start and keeps the same outcome.
        """
        on = tuple(sorted((n, float(v)) for n, v in self._last_on.items()))
        ok = clear_starts(self._fields.get(on, self.field), fiber, starts)
        for i in np.flatnonzero(~ok):
            rows[int(i)] = _failed(
                f"start touches a pillar: y0 = {starts[i, 1]:.4g} (fraction of period_y), "
                f"theta0 = {starts[i, 0]:.4g} deg, L = {starts[i, 2]:.4g} µm",
                array=True,
            )
        return np.flatnonzero(ok)

    @property
    def remaining(self) -> float:
        """Runs left in the budget (inf when unlimited)."""
        return math.inf if self.budget is None else self.budget - self.used

    def run(
        self,
        starts: np.ndarray,
        effects: Mapping[str, float] | None,
        seeds: np.ndarray,
        desc: str = "runs",
        fps: float | None = None,
    ) -> pd.DataFrame:
        """Simulate one run per start.

        Parameters
        ----------
        starts : ndarray, shape (n, 3)
            theta0 [deg], y0 [/h], length [/l_obs] (already jittered).
        effects : mapping name -> value
            Effects switched on for this batch (validated by the registry).
        seeds : ndarray, shape (n,), int
            Seed of each run.
        desc : str
            Progress-bar label; its first word is the stage failures are counted
            under (``failed_by_stage``).
        fps : float, optional
            Also return each run's track sampled at this frame rate [1/s]
            (:func:`frames`, column ``track``; None for a failed run).

        Returns
        -------
        pandas.DataFrame
            n rows in input order, columns OUTCOME_COLUMNS + status, reason.

        Raises
        ------
        BudgetExhausted
            If the batch would exceed the budget.
        """
        from fibersweep.fiber.effects import build_effects

        starts = np.asarray(starts, dtype=np.float64)
        seeds = np.asarray(seeds, dtype=np.int64)
        if starts.ndim != 2 or starts.shape[1] != 3 or len(seeds) != len(starts):
            raise ValueError(
                f"starts (n, 3) and seeds (n,) expected: {starts.shape}, {seeds.shape}"
            )
        effects = {k: float(v) for k, v in (effects or {}).items() if float(v) != 0.0}
        self._last_on = {k: v for k, v in effects.items() if k in self.declared}
        spec, fiber = self.variant(self._last_on)
        effects = {k: v for k, v in effects.items() if k not in self.declared}
        build_effects({**fiber.effects, **effects})  # unknown names fail here
        n = len(starts)
        if n > self.remaining:
            raise BudgetExhausted(
                f"batch '{desc}' needs {n} runs but only {self.remaining} of the budget "
                f"{self.budget} are left"
            )
        rows: list[dict[str, Any] | None] = [None] * n
        todo = np.arange(n)
        if self.array:  # a (jittered) start inside a pillar's reach fails here, not in a worker
            todo = self._clear(starts, fiber, rows)
        per_worker = 4 if fiber.model == "rigid" else FLEXIBLE_CHUNKS
        n_chunks = max(1, min(len(todo), per_worker * self.workers))
        chunks = [c for c in np.array_split(todo, n_chunks) if len(c)]
        self._batches += 1
        reduce = partial(batch_outcome, tracks=self.tracks, fps=fps)
        keep_track = self.tracks or fps is not None
        tasks = {
            f"b{self._batches}-{k}": RunBatch(
                f"b{self._batches}-{k}",
                c,
                starts[c],
                seeds[c],
                effects,
                keep_track,
                TRACK_SAMPLES,
                reduce,
                setting=spec,
            )  # fmt: skip
            for k, c in enumerate(chunks)
        }
        if self._bar is None and self.progress:
            # the rate and estimate start once each worker has a run done (compiled)
            note = "" if self._later else "workers starting (the first runs also compile)"
            self._bar = WarmingBar(self._planned, self.workers, note, make=progress_bar,
                                   unit="run")  # fmt: skip
            if self._later:
                self._bar.set_postfix_str(self._later_text(), refresh=False)
        bar = self._bar
        if bar is not None:
            if bar.total is not None and bar.n + n > bar.total:
                bar.total = bar.n + n  # more than planned: grow (the ETA stays honest)
            bar.set_description_str(desc[:40])
            if n > len(todo):
                bar.update(n - len(todo))  # starts refused before any run
        t0 = time.perf_counter()
        outcomes = (
            (o.key, o.value, o.error)
            for o in (
                self._executor.run(run_batch, list(tasks.values()), init_worker, self._initargs)
                if tasks
                else ()
            )
        )
        for key, chunk, error in outcomes:
            if error:  # the worker died (or the task could not run): failed runs
                chunk = [(int(i), _failed(f"worker: {error}", self.array))
                         for i in tasks[key].idx]  # fmt: skip
            for i, row in chunk:
                rows[i] = row
            if bar is not None:
                bar.update(len(chunk))
        self.used += n
        stage = desc.split(" ")[0]
        self.used_by_stage[stage] = self.used_by_stage.get(stage, 0) + n
        dt = time.perf_counter() - t0
        self.seconds_by_stage[stage] = self.seconds_by_stage.get(stage, 0.0) + dt
        df = pd.DataFrame(rows)
        nf = int((df["status"] != "ok").sum())
        bare = spec is None and not any(float(v) != 0.0 for v in (effects or {}).values())
        if nf == n and n and bare:  # the model as it is ran none: no verdict can rest on it
            raise SolverError(
                f"{desc}: every one of the {n} runs of the model as it is failed, e.g. "
                f"{df['reason'].iloc[0]}; check the measured starts against the config"
            )
        if nf:
            self.failed += nf
            self.failed_by_stage[stage] = self.failed_by_stage.get(stage, 0) + nf
            # under a probed or fitted effect (e.g. strong Brownian motion hitting the
            # time limit) a failure is an outcome of that effect, not of the analysis
            log.log(
                logging.INFO if effects or spec is not None else logging.WARNING,
                "%s: %d of %d runs failed (%s)",
                desc,
                nf,
                n,
                df["reason"][df["status"] != "ok"].iloc[0],
            )
        return df
