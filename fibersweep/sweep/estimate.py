"""Time estimates of a sweep (``run --dry-run``).

With the field cached, one run of the sweep is timed (:func:`estimate_run_s`).
Without it (nothing is stored), the flow solve is estimated from a short timing of the LBM on
the coarsest grid of the nested solve (:data:`PROBE_STEPS` steps) and the typical
step counts of the solve (:data:`TYPICAL_STEPS`); one fiber run is timed on the
field those probe steps give, which is unconverged but has the right geometry and
scale (the cost of a run does not depend on the grid spacing: the interpolation
kernel covers the same number of nodes per bead at any Δx).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import Any

from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.settings import FiberSettings
from fibersweep.flow.settings import FlowSettings
from fibersweep.sweep.worker import SweepTask

__all__ = [
    "PROBE_STEPS",
    "TYPICAL_STEPS",
    "UncachedEstimate",
    "estimate_run_s",
    "estimate_uncached",
    "time_run",
]

#: LBM steps timed on the coarsest grid.
PROBE_STEPS = 200
#: Steps to converge to the default tolerance (1e-6) on the first grid of a solve,
#: and on each finer grid started from the coarser solution: measured on the
#: default geometry at dx = 4 and 2 µm (1800, then 2100), see docs/performance.md.
TYPICAL_STEPS = (1800, 2100)


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
    flow: FlowSettings, fiber: FiberSettings, start: FiberStart
) -> UncachedEstimate:
    """Time a short LBM probe and one fiber run; estimate the whole solve.

    Parameters
    ----------
    flow : FlowSettings
        Settings of the field to estimate.
    fiber : FiberSettings
        Settings of the run to time.
    start : FiberStart
        Start of the run to time (a point of the sweep).
    """
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
    run_s, warmup_s = _time_run_and_warmup(field, fiber, start)
    # Workers map the cached field read-only, a distinct array type to Numba: make those
    # kernels ready too, so the sweep's workers find them cached.
    warmup_s += _time_run_and_warmup(_read_only(field), fiber, start)[1]
    return UncachedEstimate(
        flow_s=updates / (mlups * 1e6),
        run_s=run_s,
        mlups=mlups,
        grids=grids,
        probe_s=time.perf_counter() - t_start,
        compile_s=compile_s,
        warmup_s=warmup_s,
    )


def _read_only(field: Any) -> Any:
    """``field`` with read-only velocity arrays, as a worker maps them from the cache."""
    import dataclasses

    def frozen(a: Any) -> Any:
        if a is None:
            return None
        b = a.copy()
        b.flags.writeable = False
        return b

    return dataclasses.replace(
        field, ux=frozen(field.ux), uy=frozen(field.uy), u3d=frozen(field.u3d)
    )


def _time_run_and_warmup(
    field: Any, fiber: FiberSettings, start: FiberStart
) -> tuple[float, float]:
    """Seconds of one fiber run, and the extra seconds of the first (kernels made ready)."""
    from fibersweep.fiber.run import simulate

    t0 = time.perf_counter()
    simulate(field, fiber, start)  # compiles (or loads) the kernels
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    simulate(field, fiber, start)
    run_s = time.perf_counter() - t0
    return run_s, max(0.0, first - run_s)


def time_run(field: Any, fiber: FiberSettings, start: FiberStart) -> float:
    """Seconds of one fiber run on ``field``, timed after a warm-up run (kernels compiled)."""
    return _time_run_and_warmup(field, fiber, start)[0]


def estimate_run_s(cfg: Any, todo: list[SweepTask]) -> float:
    """Seconds per run of a sweep, timed on its middle to-do point (see :func:`time_run`).

    The run is made with its own setting combination (its field must be cached).
    """
    from fibersweep.sweep.fields import flow_field_for
    from fibersweep.sweep.plan import sweep_settings

    t = todo[len(todo) // 2]
    sub = next((s.config for s in sweep_settings(cfg) if s.id == t.settings), cfg)
    fieldobj, _ = flow_field_for(sub)
    return time_run(fieldobj, sub.fiber, FiberStart(theta0=t.theta0, y0=t.y0, length=t.length))
