"""One fiber run: validate the start, integrate (the settings' model and integrator), classify,
report.

:func:`simulate` is the public entry point the sweep calls thousands of times:
a module-level function (picklable), Numba kernels compiled once per process
(``cache=True``), per-length body mobilities cached (``body_mobility``).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time

import numpy as np

from fibersweep.analysis.classify import classify
from fibersweep.analysis.observables import (
    fiber_angle,
    first_contact_index,
    pass_time,
    take,
    thin_indices,
)
from fibersweep.config.fiber import FiberSettings
from fibersweep.errors import InputError
from fibersweep.fiber.kernel import record as R
from fibersweep.fiber.kernel.bundles import Kernel, build_kernel
from fibersweep.fiber.models.deformation import deformation
from fibersweep.fiber.models.registry import integrator_of
from fibersweep.fiber.models.rigid import seed_numba
from fibersweep.fiber.models.spacing import offsets
from fibersweep.fiber.result import FiberStart, RunResult, Trajectory
from fibersweep.fiber.setup import Setup, prepare
from fibersweep.flow.field import FlowField

__all__ = ["simulate", "simulate_for", "simulate_reversible"]

log = logging.getLogger(__name__)


def _integrate(
    setup: Setup,
    k: Kernel,
    x0: float,
    y0: float,
    th0: float,
    beads0: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray | None, int]:
    """Run the selected integrator; returns (record rows, bead positions or None, stop code)."""
    return integrator_of(setup.settings).integrate(k, x0, y0, th0, beads0)


def _seed(rng: np.random.Generator, setup: Setup) -> None:
    if setup.effects.random:
        seed_numba(int(rng.integers(0, 2**31 - 1)))


def _result(
    setup: Setup, k: Kernel, rec: np.ndarray, beads: np.ndarray | None, code: int, wall: float
) -> RunResult:
    st = setup.settings
    geo = setup.field.geometry
    traj = R.trajectory_from_record(rec, beads)
    common = dict(
        start=setup.start,
        n_steps=integrator_of(st).steps(k, rec),
        wall_time=wall,
        model=st.model,
        integrator=st.resolved_integrator,
        n_beads=setup.n,
        min_clearance=float(np.min(rec[:, R.MIN_DIST]) - st.bead_radius),
        x_f=float(traj.x[-1]),
        y_f=float(traj.y[-1]),
        theta_f=float(traj.theta[-1]),
        t_end=float(traj.t[-1]),
    )
    if beads is not None and len(beads):
        common.update(
            deformation(
                beads,
                rec[:, R.CONTACT],
                setup.pillar.vertices,
                setup.pillar.circle,
                setup.pillar.r_cut,
                st.bead_radius,
                st.young_modulus,
                st.bead_spacing,
            )
        )
    k = first_contact_index(traj)
    if k is not None:
        common.update(
            contact=True,
            theta_c=fiber_angle(float(traj.theta[k])),
            y_c=float(geo.y_over_h(rec[k, R.CY])),
            t_contact=float(traj.t[k]),
        )
    common["t_pass"] = pass_time(traj, setup.pillar.x_max, setup.u_center)
    if st.record.trajectories:
        idx = thin_indices(traj, st.record.samples, setup.u_center, st.classify)
        kept = take(traj, idx)
        if st.record.all_beads and kept.beads is None:
            s = offsets(setup.n, st.bead_radius, st.bead_spacing)
            th = rec[idx, R.TH]
            bx = rec[idx, R.XC][:, None] + np.cos(th)[:, None] * s[None, :]
            by = rec[idx, R.YC][:, None] + np.sin(th)[:, None] * s[None, :]
            kept = dataclasses.replace(kept, beads=np.stack([bx, by], -1))
        elif not st.record.all_beads and kept.beads is not None:
            kept = dataclasses.replace(kept, beads=None)
        common["trajectory"] = kept
    if code < 0:
        return RunResult(status="failed", reason=R.STOP_REASONS[code], **common)
    cls = classify(traj, geo, setup.u_center, st.classify)
    if code == R.TRAPPED and cls != "Trapping":  # pragma: no cover - same rule both sides
        log.warning("kernel trap rule and classify() disagree (%s)", cls)
    if not cls:
        return RunResult(status="failed", reason="unclassified", **common)
    delta = math.nan
    if cls != "Trapping":
        delta = (float(traj.y[-1]) - setup.y0_abs) / geo.pillar_height
    return RunResult(status="ok", cls=cls, delta=delta, **common)


def simulate(
    field: FlowField, settings: FiberSettings, start: FiberStart, *, rng_seed: int | None = None
) -> RunResult:
    """Run one fiber from its start to far downstream (or trapping), classify and report.

    Parameters
    ----------
    field : FlowField or CellField
        Steady midplane flow [µm/s]: the channel's, or a pillar array's unit cell
        (then :func:`fibersweep.fiber.array_run.simulate_array` runs it, with its
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
    from fibersweep.flow.cell import CellField

    if isinstance(field, CellField):  # a pillar array's unit cell (flow.array)
        from fibersweep.fiber.array_run import simulate_array

        return simulate_array(field, settings, start, rng_seed=rng_seed)
    t_wall = time.perf_counter()
    integrator_of(settings)  # an unknown model or integrator: InputError before any work
    rng = np.random.default_rng(rng_seed)
    setup = prepare(field, settings, start, rng)
    _seed(rng, setup)
    k = build_kernel(setup)
    try:
        rec, beads, code = _integrate(setup, k, setup.x0, setup.y0_abs, setup.th0)
    except (FloatingPointError, np.linalg.LinAlgError, ZeroDivisionError) as exc:
        log.warning("run %s failed: %s", start, exc)
        return RunResult(
            start=start,
            status="failed",
            reason=f"numerical error: {exc}",
            model=settings.model,
            integrator=settings.resolved_integrator,
        )
    result = _result(setup, k, rec, beads, code, time.perf_counter() - t_wall)
    return setup.effects.result(result, start, field.geometry)


def simulate_reversible(
    field: FlowField, settings: FiberSettings, start: FiberStart, *, rng_seed: int | None = None
) -> tuple[RunResult, float]:
    """Run past the pillar, reverse the flow, run back for the same time.

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
    setup = prepare(field.reversed(), settings, start, rng)
    _seed(rng, setup)
    t_total = fwd.t_end
    k = build_kernel(setup, mode=1, t_stop=t_total)
    th_f = math.radians(fwd.theta_f)
    beads_f = fwd_beads[-1] if fwd_beads is not None else None
    rec, beads, code = _integrate(setup, k, fwd.x_f, fwd.y_f, th_f, beads_f)
    if code < 0:
        return fwd, math.nan
    s = offsets(setup.n, settings.bead_radius, settings.bead_spacing)
    end = rec[-1]
    p0 = np.column_stack(
        [setup.x0 + s * math.cos(setup.th0), setup.y0_abs + s * math.sin(setup.th0)]
    )
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

    Returns
    -------
    (Trajectory, reason)
        The full-resolution trajectory (all beads for the bead-spring model) and
        '' or the failure reason if the run stopped early.
    """
    if not (math.isfinite(duration) and duration > 0):
        raise InputError(f"duration: must be a positive number of seconds, got {duration!r}")
    rng = np.random.default_rng(rng_seed)
    setup = prepare(field, settings, start, rng)
    _seed(rng, setup)
    k = build_kernel(setup, mode=1, t_stop=duration)
    rec, beads, code = _integrate(setup, k, setup.x0, setup.y0_abs, setup.th0)
    return R.trajectory_from_record(rec, beads), R.STOP_REASONS.get(code, "")
