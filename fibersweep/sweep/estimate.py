"""Time estimates of a sweep (``run --dry-run``).

With the field cached, one run of the sweep is timed (:func:`estimate_run_s`).
Without it (nothing is stored), the flow solve is estimated from a short timing of the LBM on
the coarsest grid of the nested solve (:data:`PROBE_STEPS` steps) and the typical
step counts of the solve (:data:`TYPICAL_STEPS`); one fiber run is timed on the
field those probe steps give, which is unconverged but has the right geometry and
scale (the cost of a run does not depend on the grid spacing: the interpolation
kernel covers the same number of nodes per bead at any Δx).

A pillar array's unit cell (``flow.array``) is probed the same way: the cell
solver runs :data:`PROBE_STEPS` steps per solve, its speed gives the solve's
time at :data:`CELL_STEPS_PER_NODE` steps per node of the cell's largest side,
and the runs are timed on that probe cell. An array run's cost depends on the
fiber's length (a sphere crosses the rows fast, a long fiber slides along every
pillar) and its mode, so one run per length (and setting) of the sweep is timed, spread
evenly over them up to :data:`MAX_TIMED` runs (:func:`sample_tasks`).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from fibersweep.config.fiber import FiberSettings
from fibersweep.config.flow import FlowSettings
from fibersweep.fiber.result import FiberStart
from fibersweep.sweep.worker import SweepTask

__all__ = [
    "CELL_STEPS_PER_NODE",
    "MAX_TIMED",
    "PROBE_STEPS",
    "TYPICAL_STEPS",
    "UncachedEstimate",
    "busy_cores",
    "estimate_run_s",
    "estimate_uncached",
    "free_workers",
    "sample_tasks",
    "time_run",
]

#: LBM steps timed on the coarsest grid.
PROBE_STEPS = 200
#: Steps to converge to the default tolerance (1e-6) on the first grid of a solve,
#: and on each finer grid started from the coarser solution: measured on the
#: default geometry at dx = 4 and 2 µm (1800, then 2100), see docs/performance.md.
TYPICAL_STEPS = (1800, 2100)
#: Steps per solve of a unit cell, per node of its largest side: measured on
#: ``configs/array.yaml`` (80 µm periods, 40 µm deep) at dx = 2 µm (40 nodes:
#: 4200 steps for the two solves) and dx = 4 µm (20 nodes: 1600).
CELL_STEPS_PER_NODE = 45
#: Most runs timed for an estimate (spread over the lengths of an array sweep).
MAX_TIMED = 6


log = logging.getLogger(__name__)


class _NotConverged(logging.Filter):
    """Drops the solver's "not converged" warning of the probe."""

    def filter(self, record: logging.LogRecord) -> bool:
        return "not converged" not in record.getMessage()


@dataclass(frozen=True)
class UncachedEstimate:
    """Estimated cost of a field that is not cached, and of one run on it.

    Attributes
    ----------
    flow_s : float
        Seconds to compute the field (every grid of the nested solve).
    run_s : float
        Seconds of one fiber run (timed after a warm-up run).
    mlups : float
        Million lattice-cell updates per second measured by the probe.
    grids : tuple of (float, int)
        (dx [µm], cells) of each grid solved, coarsest first.
    probe_s : float
        Seconds this estimate took.
    compile_s : float
        Seconds to get the flow kernels ready in this process: compiling them on
        first use (then they are cached on disk), else loading them.
    warmup_s : float
        Seconds the first fiber runs took beyond a timed one, on the field as made
        and as a worker maps it (read-only): compiling the fiber kernels on first
        use (then they are cached), else loading them.
    """

    flow_s: float
    run_s: float
    mlups: float
    grids: tuple[tuple[float, int], ...]
    probe_s: float
    compile_s: float = 0.0
    warmup_s: float = 0.0


def estimate_uncached(
    flow: FlowSettings, fiber: FiberSettings, start: FiberStart | Sequence[FiberStart]
) -> UncachedEstimate:
    """Time a short LBM probe and the fiber runs; estimate the whole solve.

    Parameters
    ----------
    flow : FlowSettings
        Settings of the field to estimate (a channel, or a unit cell with ``array``).
    fiber : FiberSettings
        Settings of the runs to time.
    start : FiberStart or sequence of FiberStart
        Start(s) of the run(s) to time (points of the sweep); ``run_s`` is their mean.
    """
    starts = [start] if isinstance(start, FiberStart) else list(start)
    if flow.array is not None:
        return _estimate_cell(flow, fiber, starts)
    from fibersweep.flow.lbm import coarser_settings, lattice_of, solve_lattice
    from fibersweep.flow.solver import field_from_solution

    t_start = time.perf_counter()
    levels = [flow]
    while (coarser := coarser_settings(levels[-1])) is not None:
        levels.append(coarser)
    levels.reverse()  # coarsest first, as the nested solve does them
    grids = tuple((s.dx, lattice_of(s).cells) for s in levels)
    probe = levels[0].model_copy(update={"max_steps": PROBE_STEPS, "check_every": PROBE_STEPS // 2})
    lbm_log = logging.getLogger("fibersweep.flow.lbm")
    quiet = _NotConverged()
    lbm_log.addFilter(quiet)  # the probe stops before convergence on purpose
    try:
        # compile (or load) the kernels on a tiny channel first: not part of the timing
        tiny = probe.geometry.model_copy(
            update={"width": 160.0, "length": 160.0, "pillar_height": 40.0,
                    "pillar_x": None, "pillar_y_base": None}
        )  # fmt: skip
        t_compile = time.perf_counter()
        solve_lattice(probe.model_copy(update={"geometry": tiny, "max_steps": 4}))
        compile_s = time.perf_counter() - t_compile
        sol = solve_lattice(probe)
    finally:
        lbm_log.removeFilter(quiet)
    mlups = sol.report.mlups
    updates = sum(
        cells * (TYPICAL_STEPS[0] if i == 0 else TYPICAL_STEPS[1])
        for i, (_, cells) in enumerate(grids)
    )
    field = field_from_solution(probe, sol)
    run_s, warmup_s = _time_runs(field, fiber, starts)
    return UncachedEstimate(
        flow_s=updates / (mlups * 1e6),
        run_s=run_s,
        mlups=mlups,
        grids=grids,
        probe_s=time.perf_counter() - t_start,
        compile_s=compile_s,
        warmup_s=warmup_s,
    )


def _estimate_cell(
    flow: FlowSettings, fiber: FiberSettings, starts: list[FiberStart]
) -> UncachedEstimate:
    """:func:`estimate_uncached` of a pillar array's unit cell (module docstring)."""
    from fibersweep.flow.cell import field_of, solve_cell

    t_start = time.perf_counter()
    probe = flow.model_copy(update={"max_steps": PROBE_STEPS, "check_every": PROBE_STEPS // 2})
    quiet = _NotConverged()
    logs = [logging.getLogger(n) for n in ("fibersweep.flow.lbm", "fibersweep.flow.cell")]
    for lg in logs:
        lg.addFilter(quiet)  # the probe stops before convergence on purpose
    try:
        t0 = time.perf_counter()
        solve_cell(flow.model_copy(update={"max_steps": 4, "check_every": 2}))  # compile (or load)
        compile_s = time.perf_counter() - t0
        sol = solve_cell(probe)
    finally:
        for lg in logs:
            lg.removeFilter(quiet)
    g = sol.grid
    cells = g.nx * g.ny * g.nz
    solves = max(1, round(sol.steps / PROBE_STEPS))  # 2 with the mean flow made along x
    mlups = cells * sol.steps / max(sol.seconds, 1e-9) / 1e6
    steps = solves * CELL_STEPS_PER_NODE * max(g.nx, g.ny, g.nz_full)
    field = field_of(probe, sol)
    run_s, warmup_s = _time_runs(field, fiber, starts)
    return UncachedEstimate(
        flow_s=steps * cells / (mlups * 1e6),
        run_s=run_s,
        mlups=mlups,
        grids=((flow.dx, cells),),
        probe_s=time.perf_counter() - t_start,
        compile_s=compile_s,
        warmup_s=warmup_s,
    )


def _time_runs(field: Any, fiber: FiberSettings, starts: list[FiberStart]) -> tuple[float, float]:
    """Mean seconds of one run over ``starts``, and the seconds spent making kernels ready.

    Workers map the cached field read-only, a distinct array type to Numba: those
    kernels are made ready too, so the sweep's workers find them cached.
    """
    run_s, warmup_s = _time_run_and_warmup(field, fiber, starts[0])
    warmup_s += _time_run_and_warmup(_read_only(field), fiber, starts[0])[1]
    times = [run_s]
    for st in starts[1:]:
        t0 = time.perf_counter()
        _simulate_quiet(field, fiber, st)
        times.append(time.perf_counter() - t0)
    return sum(times) / len(times), warmup_s


def _simulate_quiet(field: Any, fiber: FiberSettings, start: FiberStart) -> None:
    """One run for its time; a start the run refuses costs what it cost."""
    from fibersweep.errors import InputError
    from fibersweep.fiber.run import simulate

    try:
        simulate(field, fiber, start)
    except InputError as exc:  # e.g. a random start the probe field sees touching
        log.info("timed run refused: %s", exc)


def sample_tasks(todo: Sequence[SweepTask], k: int = MAX_TIMED) -> list[SweepTask]:
    """Up to ``k`` runs of ``todo`` that stand for it: the middle run of each length and
    setting combination (spread evenly over them, by length, when there are more than
    ``k``), else the middle run."""
    by_length: dict[tuple[float, str], list[SweepTask]] = {}
    for t in todo:
        by_length.setdefault((float(t.length), str(t.settings)), []).append(t)
    groups = [by_length[key] for key in sorted(by_length)]
    if len(groups) > k:
        groups = [groups[round(i * (len(groups) - 1) / (k - 1))] for i in range(k)]
    return [g[len(g) // 2] for g in groups] or list(todo[:1])


def _read_only(field: Any) -> Any:
    """``field`` with read-only velocity arrays, as a worker maps them from the cache."""
    import dataclasses

    def frozen(a: Any) -> Any:
        if a is None:
            return None
        b = a.copy()
        b.flags.writeable = False
        return b

    arrays = {n: frozen(getattr(field, n)) for n in ("ux", "uy", "u3d") if hasattr(field, n)}
    return dataclasses.replace(field, **arrays)


def busy_cores() -> tuple[float, int]:
    """The machine's 1-minute load average and its CPU count (load 0 where unknown)."""
    import os

    try:
        load = float(os.getloadavg()[0])
    except (AttributeError, OSError):  # no load average on this platform
        load = 0.0
    return load, os.cpu_count() or 1


def free_workers(workers: int, load: float, cpus: int) -> int:
    """Workers that will run at once on ``cpus`` cores already ``load`` busy (>= 1).

    A sweep's workers share the cores with what the machine runs already, so on a
    busy machine its wall time is that of fewer workers: those the free cores
    hold (rounded), at least one.
    """
    return max(1, min(int(workers), round(cpus - load)))


def _time_run_and_warmup(
    field: Any, fiber: FiberSettings, start: FiberStart
) -> tuple[float, float]:
    """Seconds of one fiber run, and the extra seconds of the first (kernels made ready)."""
    t0 = time.perf_counter()
    _simulate_quiet(field, fiber, start)  # compiles (or loads) the kernels
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    _simulate_quiet(field, fiber, start)
    run_s = time.perf_counter() - t0
    return run_s, max(0.0, first - run_s)


def time_run(field: Any, fiber: FiberSettings, start: FiberStart) -> float:
    """Seconds of one fiber run on ``field``, timed after a warm-up run (kernels compiled)."""
    return _time_run_and_warmup(field, fiber, start)[0]


def estimate_run_s(cfg: Any, todo: list[SweepTask]) -> float:
    """Seconds per run of a sweep, timed on its middle to-do point (see :func:`time_run`);
    in a pillar array, the mean over runs spread across the lengths (:func:`sample_tasks`).

    Each run is made with its own setting combination (its field must be cached).
    """
    from fibersweep.sweep.fields import flow_field_for
    from fibersweep.sweep.plan import sweep_settings

    configs = {s.id: s.config for s in sweep_settings(cfg)}
    picks = sample_tasks(todo) if cfg.flow.array is not None else [todo[len(todo) // 2]]
    times = []
    for k, t in enumerate(picks):
        sub = configs.get(t.settings, cfg)
        fieldobj, _ = flow_field_for(sub)
        start = FiberStart(theta0=t.theta0, y0=t.y0, length=t.length)
        if k == 0:
            times.append(time_run(fieldobj, sub.fiber, start))
            continue
        t0 = time.perf_counter()
        _simulate_quiet(fieldobj, sub.fiber, start)
        times.append(time.perf_counter() - t0)
    return sum(times) / len(times)
