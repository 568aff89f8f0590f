"""One fiber run through a tilted pillar array: the array case of ``simulate``.

``simulate(field, settings, start)`` comes here when ``field`` is a unit-cell
:class:`~fibersweep.flow.cell.CellField` (``flow.array`` set). The start is
read in the array's units:

- ``theta0`` [deg] as in the channel;
- ``y0``: lateral position of the centre as a fraction of ``period_y`` (0..1),
  in the gap between row −1 and row 0 (x in the middle of that gap);
- ``length``: the fiber length L [µm]; the fiber has round(L / 2a) beads (1: a sphere),
  or round((L − 2a)/b) + 1 at a bead spacing b (``fiber.bead_spacing``).

The run crosses ``fiber.array_rows`` rows (it passes when its rear end is that
many periods downstream of the start), or ends trapped or at ``fiber.step.t_max``.
Its thinned trajectory is always kept (``record.samples`` samples spread over
the run, plus every change of contact): the array columns of the
:class:`~fibersweep.fiber.result.RunResult` are a pure function of it
(:func:`fibersweep.analysis.modes.summarise_trajectory`), so ``fibersweep
classify`` re-labels the modes from the store.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time

import numpy as np

from fibersweep.errors import InputError
from fibersweep.fiber.kernel import record as R
from fibersweep.fiber.models.registry import integrator_of
from fibersweep.fiber.models.spacing import DEFAULT_SPACING, n_beads, offsets
from fibersweep.fiber.result import FiberStart, RunResult, Trajectory
from fibersweep.fiber.setup import MIN_BEADS

__all__ = ["array_run_kernel", "n_beads_of", "simulate_array", "start_clear", "start_x"]

log = logging.getLogger(__name__)


def n_beads_of(length: float, bead_radius: float, spacing: float = DEFAULT_SPACING) -> int:
    """Beads of a fiber of length L [µm] with bead radius a [µm] and ``fiber.bead_spacing``
    ``spacing``: round(L / 2a) for touching beads, at least 1 (:func:`.spacing.n_beads`)."""
    return n_beads(length, bead_radius, spacing)


def start_x(array) -> float:
    """x of the starts: the middle of the gap between row −1 and row 0 [µm]."""
    x0, _, x1, _ = array.shape.bounds
    return 0.5 * (x0 + x1 - array.period_x)


def start_clear(
    array,
    pillar,
    n_beads: int,
    bead_radius: float,
    y0: float,
    theta0: float,
    spacing: float = DEFAULT_SPACING,
) -> bool:
    """Whether a fiber started at lateral fraction ``y0``, angle ``theta0`` [deg] clears every
    pillar by more than the contact cutoff ``pillar.r_cut`` [µm] (beads ``spacing`` · 2a
    apart)."""
    s = offsets(n_beads, bead_radius, spacing)
    th = math.radians(theta0)
    bx = start_x(array) + s * math.cos(th)
    by = y0 * array.period_y + s * math.sin(th)
    return all(
        float(np.min(sh.signed_distance(bx, by))) > pillar.r_cut
        for _, _, sh in array.images(bx.min(), by.min(), bx.max(), by.max(), pillar.r_cut)
    )


def array_run_kernel(field, settings, length: float, x_end: float | None = None):
    """The kernel of one fiber of length L [µm] in the array of ``field``
    (:func:`fibersweep.fiber.rows.array_kernel`, the field's viscosity and U_center).

    ``x_end`` [µm]: where the run passes (default: ``settings.array_rows`` periods
    downstream of :func:`start_x`).
    """
    from fibersweep.fiber.rows import array_kernel

    array = field.array
    if x_end is None:
        x_end = start_x(array) + settings.array_rows * array.period_x
    return array_kernel(
        field,
        settings,
        n_beads_of(length, settings.bead_radius, settings.bead_spacing),
        mu=field.viscosity,
        u_center=field.u_center,
        x_end=x_end,
    )


def _thin(traj: Trajectory, samples: int) -> Trajectory:
    """``samples`` samples spread over the run plus both sides of every change of contact."""
    n = traj.t.size
    c = traj.contact.astype(np.int8)
    change = np.flatnonzero(np.diff(c) != 0)
    idx = np.unique(
        np.concatenate([np.linspace(0, n - 1, min(samples, n)).astype(int), change, change + 1])
    )
    from fibersweep.analysis.observables import take

    return take(traj, idx)


def simulate_array(field, settings, start: FiberStart, *, rng_seed: int | None = None) -> RunResult:
    """Run one fiber through ``settings.array_rows`` rows of the array of ``field``.

    Parameters
    ----------
    field : fibersweep.flow.cell.CellField
        Unit-cell midplane velocity [µm/s] and its array.
    settings : FiberSettings
        Fiber model (rigid or bead-spring) and integrator, contact, step, trap rule, effects
        acting in the kernels.
    start : FiberStart
        theta0 [deg], y0 [fraction of period_y], length [µm].
    rng_seed : int, optional
        Seed of the effects' randomness.

    Returns
    -------
    RunResult
        ``cls`` empty and ``delta`` NaN (channel quantities); the transport in the
        array columns. Status 'failed' with the reason for a run that blew up or
        reached ``t_max``.

    Raises
    ------
    InputError
        A non-finite start, y0 outside [0, 1], a fiber shorter than one bead, a start
        touching a pillar, or an effect that acts outside the kernels.
    """
    from fibersweep.analysis.modes import summarise_trajectory
    from fibersweep.fiber.models.rigid import seed_numba
    from fibersweep.fiber.rows import array_pillar, check_array_effects

    t_wall = time.perf_counter()
    integrator = integrator_of(settings)
    array = field.array
    a = settings.bead_radius
    for name in ("theta0", "y0", "length"):
        if not math.isfinite(getattr(start, name)):
            raise InputError(f"{name}: must be finite, got {getattr(start, name)!r}")
    if not 0.0 <= start.y0 <= 1.0:
        raise InputError(f"y0: {start.y0} is not a fraction of period_y in [0, 1] (pillar array)")
    if start.length < 2.0 * a - 1e-9:
        raise InputError(
            f"length: L = {start.length} µm is shorter than one bead (2a = {2 * a} µm)"
        )
    n = n_beads_of(start.length, a, settings.bead_spacing)
    if settings.model != "rigid" and n < MIN_BEADS:
        raise InputError(
            f"length: L = {start.length} µm is {n} bead(s); the {settings.model} model needs "
            f"at least {MIN_BEADS} (a sphere runs with the rigid model)"
        )
    effects = check_array_effects(settings)
    pillar = array_pillar(array, settings, field.viscosity, field.u_center)
    if not start_clear(array, pillar, n, a, start.y0, start.theta0, settings.bead_spacing):
        raise InputError(
            f"y0: the fiber at y0 = {start.y0} (fraction of period_y), theta0 = {start.theta0} "
            "deg touches a pillar at the start"
        )
    if effects.random:
        seed_numba(int(np.random.default_rng(rng_seed).integers(0, 2**31 - 1)))
    x0 = start_x(array)
    y0 = start.y0 * array.period_y
    k = array_run_kernel(field, settings, start.length)
    try:
        rec, beads, code = integrator.integrate(k, x0, y0, math.radians(start.theta0), None)
    except (FloatingPointError, np.linalg.LinAlgError, ZeroDivisionError) as exc:
        log.warning("run %s failed: %s", start, exc)
        return RunResult(
            start=start,
            status="failed",
            reason=f"numerical error: {exc}",
            model=settings.model,
            integrator=integrator.name,
        )
    code = int(code)
    npil = rec[:, R.CONTACT]  # pillars in contact at each step
    contact = npil > 0.5
    t = rec[:, R.T]
    has_beads = beads is not None and len(beads) > 0
    kept = _thin(R.trajectory_from_record(rec, beads if has_beads else None),
                 max(settings.record.samples, 2))  # fmt: skip
    if kept.beads is not None and not settings.record.all_beads:
        kept = dataclasses.replace(kept, beads=None)
    summ = summarise_trajectory(kept, array, k.params.trap_speed)
    common = dict(
        start=start,
        model=settings.model,
        integrator=integrator.name,
        n_beads=n,
        n_steps=integrator.steps(k, rec),
        wall_time=time.perf_counter() - t_wall,
        x_f=float(rec[-1, R.XC]),
        y_f=float(rec[-1, R.YC]),
        theta_f=float(kept.theta[-1]),
        t_end=float(t[-1]),
        min_clearance=float(np.min(rec[:, R.MIN_DIST]) - a),
        contact=bool(contact.any()),
        rows=summ.rows,
        shift_per_row=summ.shift_per_row,
        migration_angle=summ.angle_deg,
        fraction=summ.fraction,
        mode=summ.mode,
        wraps=summ.wraps,
        contacts=int(np.sum(np.diff(np.concatenate([[False], contact]).astype(np.int8)) > 0)),
        bridging=int(np.sum(npil >= 2)),
        time_on_pillars=float(np.sum(np.diff(t) * contact[:-1])) if t.size > 1 else 0.0,
        trajectory=kept,
    )
    if has_beads:
        common.update(_deformation(array, pillar, beads, npil, settings))
    if code < 0:
        return RunResult(status="failed", reason=R.STOP_REASONS[code], **common)
    return RunResult(status="ok", **common)


def _deformation(array, pillar, beads: np.ndarray, npil: np.ndarray, settings) -> dict:
    """Deformation observables of a bead-spring run (``fiber.deformation.deformation``).

    Each recorded configuration is moved by the lattice vector of the pillar nearest
    to its centre, so that this pillar is the cell's own (row 0, column 0), whose
    outline the wrap angle is measured against.

    Parameters
    ----------
    beads : ndarray, shape (rows, n, 2)
        Bead positions [µm], unwrapped lab frame.
    npil : ndarray, shape (rows,)
        Pillars in contact at each row.
    """
    from fibersweep.fiber.models.deformation import deformation

    cx, cy = array.shape.centroid
    mid = beads.mean(axis=1)
    row = np.rint((mid[:, 0] - cx) / array.period_x)
    col = np.rint((mid[:, 1] - cy - row * array.lateral_shift) / array.period_y)
    shift = np.stack([row * array.period_x, row * array.lateral_shift + col * array.period_y], 1)
    return deformation(
        beads - shift[:, None, :],
        (npil > 0.5).astype(np.float64),
        pillar.vertices,
        pillar.circle,
        pillar.r_cut,
        settings.bead_radius,
        settings.young_modulus,
        settings.bead_spacing,
    )
