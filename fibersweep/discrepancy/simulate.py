"""Batches of fiber runs for the discrepancy workflow, on a persistent process pool.

The workflow makes many small batches (baseline copies, probes, each step of
a parameter fit), so the pool is started once and kept (spawned processes get
the field and the settings once, in their initializer). Every run has its own
seed (Brownian noise, start-noise effects), so a batch is reproducible whatever
the number of workers. A run that raises is recorded as ``status='failed'``
with the reason, never dropped. The number of runs is counted against a budget.
"""

from __future__ import annotations

import logging
import math
import multiprocessing as mp
from collections.abc import Mapping
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any

import numpy as np
import pandas as pd
from tqdm.auto import tqdm

from fibersweep.discrepancy.observables import OBSERVABLES
from fibersweep.errors import RUN_ERRORS, FibersweepError, InputError, SolverError
from fibersweep.fiber.result import CLASSES, FiberStart
from fibersweep.fiber.settings import FiberSettings
from fibersweep.flow.field import FlowField

__all__ = ["OUTCOME_COLUMNS", "Simulator", "BudgetExhausted", "outcome_row"]

log = logging.getLogger(__name__)

#: Outcome columns of a batch, one per observable of the registry, in its order.
OUTCOME_COLUMNS = tuple(OBSERVABLES)

_WORKER: dict[str, Any] = {}


class BudgetExhausted(FibersweepError):
    """The simulation budget does not allow the requested batch."""


def outcome_row(result: Any) -> dict[str, Any]:
    """Observable values of a RunResult (registry order), missing for a failed run.

    Values follow :mod:`fibersweep.discrepancy.observables` (class name, contact
    0.0/1.0, floats in the observables' units); plus ``status`` and ``reason``.
    """
    ok = result.status == "ok" and result.cls in CLASSES
    row = {name: o.outcome(result if ok else None) for name, o in OBSERVABLES.items()}
    row["status"] = "ok" if ok else "failed"
    row["reason"] = "" if ok else (result.reason or f"class {result.cls!r}")
    return row


def _failed(reason: str) -> dict[str, Any]:
    row = {name: o.outcome(None) for name, o in OBSERVABLES.items()}
    row.update(status="failed", reason=reason)
    return row


def _init(field: FlowField, settings: FiberSettings) -> None:
    _WORKER["field"] = field
    _WORKER["settings"] = settings


def _run_chunk(
    task: tuple[np.ndarray, np.ndarray, dict[str, float], np.ndarray],
) -> list[tuple[int, dict[str, Any]]]:
    from fibersweep.fiber.run import simulate

    idx, starts, effects, seeds = task
    field: FlowField = _WORKER["field"]
    base: FiberSettings = _WORKER["settings"]
    # the batch's effects come on top of those the baseline config already has
    effects = {**base.effects, **effects}
    settings = base.model_copy(update={"effects": effects})
    out = []
    for i, s, seed in zip(idx, starts, seeds, strict=True):
        start = FiberStart(theta0=float(s[0]), y0=float(s[1]), length=float(s[2]))
        try:
            res = simulate(field, settings, start, rng_seed=int(seed))
            row = outcome_row(res)
        except RUN_ERRORS as exc:  # recorded, not dropped: the run failed (or bad start)
            row = _failed(f"{type(exc).__name__}: {exc}")
        out.append((int(i), row))
    return out


class Simulator:
    """Runs batches of fibers at given starts and effects; counts runs against a budget.

    Parameters
    ----------
    field : FlowField
        Baseline flow field (effects that change the field apply inside the run).
    settings : FiberSettings
        Baseline fiber settings; each batch replaces ``effects``.
    workers : int
        Worker processes; 1 runs in this process.
    budget : int or None
        Most runs allowed in total (None: unlimited).
    progress : bool
        Show tqdm progress bars.

    Use as a context manager so the pool is shut down.
    """

    def __init__(
        self,
        field: FlowField,
        settings: FiberSettings,
        workers: int = 2,
        budget: int | None = None,
        progress: bool = True,
    ) -> None:
        if workers < 1:
            raise InputError(f"workers must be >= 1, got {workers}")
        self.field = field
        self.settings = settings
        self.workers = workers
        self.budget = budget
        self.progress = progress
        self.used = 0
        self.failed = 0
        self._pool: ProcessPoolExecutor | None = None

    def __enter__(self) -> Simulator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    @property
    def remaining(self) -> float:
        """Runs left in the budget (inf when unlimited)."""
        return math.inf if self.budget is None else self.budget - self.used

    def _get_pool(self) -> ProcessPoolExecutor:
        if self._pool is None:
            self._pool = ProcessPoolExecutor(
                max_workers=self.workers,
                mp_context=mp.get_context("spawn"),
                initializer=_init,
                initargs=(self.field, self.settings),
            )
        return self._pool

    def run(
        self,
        starts: np.ndarray,
        effects: Mapping[str, float] | None,
        seeds: np.ndarray,
        desc: str = "runs",
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
            Progress-bar label.

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
        build_effects({**self.settings.effects, **effects})  # unknown names fail here
        n = len(starts)
        if n > self.remaining:
            raise BudgetExhausted(
                f"batch '{desc}' needs {n} runs but only {self.remaining} of the budget "
                f"{self.budget} are left"
            )
        rows: list[dict[str, Any] | None] = [None] * n
        n_chunks = max(1, min(n, 4 * self.workers))
        chunks = [c for c in np.array_split(np.arange(n), n_chunks) if len(c)]
        tasks = [(c, starts[c], effects, seeds[c]) for c in chunks]
        bar = tqdm(total=n, desc=desc, disable=not self.progress, leave=False)
        try:
            if self.workers == 1:
                _init(self.field, self.settings)
                results = (_run_chunk(t) for t in tasks)
                for chunk in results:
                    for i, row in chunk:
                        rows[i] = row
                    bar.update(len(chunk))
            else:
                pool = self._get_pool()
                try:
                    for chunk in pool.map(_run_chunk, tasks):
                        for i, row in chunk:
                            rows[i] = row
                        bar.update(len(chunk))
                except BrokenProcessPool as exc:
                    self._pool = None
                    raise SolverError(f"a simulation worker died during '{desc}': {exc}") from None
        finally:
            bar.close()
        self.used += n
        df = pd.DataFrame(rows)
        nf = int((df["status"] != "ok").sum())
        if nf:
            self.failed += nf
            log.warning(
                "%s: %d of %d runs failed (%s)",
                desc,
                nf,
                n,
                df["reason"][df["status"] != "ok"].iloc[0],
            )
        return df
