"""One fiber run: the one path of both cases (the channel's pillar, a pillar array).

:func:`simulate` is the public entry point the sweep calls thousands of times:
a module-level function (picklable), Numba kernels compiled once per process
(``cache=True``), per-length body mobilities cached (``body_mobility``).

The path is the same for every field: resolve the integrator, ask the run's
*case* (:mod:`fibersweep.fiber.case`) to check the start and place the fiber in
its frame with its stop rule, seed the effects' randomness, integrate, ask the
case to measure. The cases are :data:`CASES`, asked in turn: a pillar array's unit
cell (:data:`fibersweep.fiber.array_run.ARRAY`), else the single pillar in its
channel (:data:`fibersweep.fiber.channel.CHANNEL`). :func:`simulate_for` (a fixed
duration) takes the same path with the time stop rule; :func:`simulate_reversible`
is the channel's.
"""

from __future__ import annotations

import logging
import math
import time

import numpy as np

from fibersweep.config.fiber import FiberSettings
from fibersweep.errors import InputError
from fibersweep.fiber.array_run import ARRAY
from fibersweep.fiber.case import Case, Outcome, Placed
from fibersweep.fiber.channel import CHANNEL
from fibersweep.fiber.kernel import record as R
from fibersweep.fiber.models.registry import integrator_of
from fibersweep.fiber.models.rigid import seed_numba
from fibersweep.fiber.models.spacing import offsets
from fibersweep.fiber.result import FiberStart, RunResult, Trajectory
from fibersweep.flow.field import FlowField

__all__ = ["CASES", "case_of", "simulate", "simulate_for", "simulate_reversible"]

log = logging.getLogger(__name__)

#: The run's cases, asked in this order whether they take a field (the channel takes any).
CASES: tuple[Case, ...] = (ARRAY, CHANNEL)


def case_of(field) -> Case:
    """The case of the first of :data:`CASES` that accepts ``field``."""
    return next(c for c in CASES if c.accepts(field))


def _place(
    field,
    settings: FiberSettings,
    start: FiberStart,
    rng: np.random.Generator,
    *,
    mode: int = 0,
    t_stop: float = math.nan,
) -> tuple[Case, Placed]:
    """The field's case and its placed run; Numba's generator seeded from ``rng`` when an
    effect draws from it (after the case's start draws, so each seed gives one run)."""
    case = case_of(field)
    placed = case.place(field, settings, start, rng, mode=mode, t_stop=t_stop)
    if placed.random:
        seed_numba(int(rng.integers(0, 2**31 - 1)))
    return case, placed


def simulate(
    field: FlowField, settings: FiberSettings, start: FiberStart, *, rng_seed: int | None = None
) -> RunResult:
    """Run one fiber from its start to far downstream (or trapping), classify and report.

    Parameters
    ----------
    field : FlowField or CellField
        Steady midplane flow [µm/s]: the channel's, or a pillar array's unit cell
        (then the run is the array case, :mod:`fibersweep.fiber.array_run`, with its
        start in the array's units).
    settings : FiberSettings
        Model and integrator, contact, stepping, classification, recording, effects.
    start : FiberStart
        theta0 [deg], y0 / h_obs, L / l_obs (array: y0 / period_y, L [µm]).
    rng_seed : int, optional
        Seed of the effects' randomness (start noise, Brownian motion).

    Returns
    -------
    RunResult
        status 'failed' with a reason for a run that blew up (NaN, penetration,
        time limit, left the channel); never raises for those.

    Raises
    ------
    InputError
        Bad input, naming the parameter: non-finite values, a length the grid
        cannot resolve, a start overlapping the pillar or outside the channel,
        an unknown effect, a model and integrator that are no pair.
    """
    t_wall = time.perf_counter()
    integrator = integrator_of(settings)  # an unknown model or integrator: InputError first
    case, placed = _place(field, settings, start, np.random.default_rng(rng_seed))
    try:
        rec, beads, code = integrator.integrate(
            placed.kernel, placed.x0, placed.y0, placed.th0, None
        )
    except (FloatingPointError, np.linalg.LinAlgError, ZeroDivisionError) as exc:
        log.warning("run %s failed: %s", start, exc)
        return RunResult(
            start=start,
            status="failed",
            reason=f"numerical error: {exc}",
            model=settings.model,
            integrator=integrator.name,
        )
    out = Outcome(integrator, rec, beads, int(code), time.perf_counter() - t_wall)
    return case.measure(placed, field, settings, start, out)


def simulate_reversible(
    field: FlowField, settings: FiberSettings, start: FiberStart, *, rng_seed: int | None = None
) -> tuple[RunResult, float]:
    """Run past the pillar, reverse the flow, run back for the same time (channel case).

    Returns
    -------
    (RunResult, return_error_um)
        The forward run's result and the largest distance [µm] between a bead's
        start position and its position at the end of the return run (NaN when
        the forward run did not pass the pillar).
    """
    rec_all = settings.record.model_copy(update={"trajectories": True, "all_beads": True})
    fwd = simulate(field, settings.model_copy(update={"record": rec_all}), start, rng_seed=rng_seed)
    fwd_beads = fwd.trajectory.beads if fwd.trajectory is not None else None
    if fwd.status != "ok" or fwd.cls == "Trapping":
        return fwd, math.nan
    rng = np.random.default_rng(rng_seed)
    _, back = _place(field.reversed(), settings, start, rng, mode=1, t_stop=fwd.t_end)
    th_f = math.radians(fwd.theta_f)
    beads_f = fwd_beads[-1] if fwd_beads is not None else None
    rec, beads, code = integrator_of(settings).integrate(
        back.kernel, fwd.x_f, fwd.y_f, th_f, beads_f
    )
    if code < 0:
        return fwd, math.nan
    s = offsets(back.n, settings.bead_radius, settings.bead_spacing)
    end = rec[-1]
    p0 = np.column_stack([back.x0 + s * math.cos(back.th0), back.y0 + s * math.sin(back.th0)])
    if beads is not None:
        p1 = beads[-1]
    else:
        p1 = np.column_stack(
            [end[R.XC] + s * math.cos(end[R.TH]), end[R.YC] + s * math.sin(end[R.TH])]
        )
    return fwd, float(np.max(np.hypot(*(p1 - p0).T)))


def simulate_for(
    field: FlowField,
    settings: FiberSettings,
    start: FiberStart,
    duration: float,
    *,
    rng_seed: int | None = None,
) -> tuple[Trajectory, str]:
    """Integrate for a fixed ``duration`` [s] (no pass test), for idealised flows and tests.

    The path of :func:`simulate` with the time stop rule (either case; the start in
    the case's units).

    Returns
    -------
    (Trajectory, reason)
        The full-resolution trajectory (all beads for the bead-spring model) and
        '' or the failure reason if the run stopped early.
    """
    if not (math.isfinite(duration) and duration > 0):
        raise InputError(f"duration: must be a positive number of seconds, got {duration!r}")
    integrator = integrator_of(settings)
    _, placed = _place(
        field, settings, start, np.random.default_rng(rng_seed), mode=1, t_stop=duration
    )
    rec, beads, code = integrator.integrate(placed.kernel, placed.x0, placed.y0, placed.th0, None)
    return R.trajectory_from_record(rec, beads), R.STOP_REASONS.get(code, "")
