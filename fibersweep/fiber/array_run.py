"""One fiber run through a tilted pillar array: the array case of the run path (:mod:`.case`).

``simulate(field, settings, start)`` (:mod:`fibersweep.fiber.run`) runs this case,
:data:`ARRAY`, when ``field`` is a unit-cell :class:`~fibersweep.flow.cell.CellField`
(``flow.array`` set); its kernel is assembled by :mod:`fibersweep.fiber.rows` (the
:class:`~fibersweep.fiber.frame.Lattice` frame). The start is read in the array's units:

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
import math

import numpy as np

from fibersweep.analysis.modes import summarise_trajectory
from fibersweep.analysis.observables import take
from fibersweep.config.fiber import FiberSettings
from fibersweep.errors import InputError
from fibersweep.fiber.case import Outcome, Placed
from fibersweep.fiber.kernel import record as R
from fibersweep.fiber.kernel.bundles import Kernel
from fibersweep.fiber.models.deformation import deformation
from fibersweep.fiber.models.spacing import DEFAULT_SPACING, n_beads, offsets
from fibersweep.fiber.result import FiberStart, RunResult, Trajectory
from fibersweep.fiber.rows import array_kernel, array_pillar, check_array_effects
from fibersweep.fiber.setup import MIN_BEADS
from fibersweep.flow.cell import CellField

__all__ = ["ARRAY", "ArrayCase", "array_run_kernel", "n_beads_of", "start_clear", "start_x"]


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


def array_run_kernel(
    field: CellField, settings: FiberSettings, length: float, x_end: float | None = None
) -> Kernel:
    """The kernel of one fiber of length L [µm] in the array of ``field``
    (:func:`fibersweep.fiber.rows.array_kernel`, the field's viscosity and U_center).

    ``x_end`` [µm]: where the run passes (default: ``settings.array_rows`` periods
    downstream of :func:`start_x`, as :data:`ARRAY` places a run).
    """
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
    return take(traj, idx)


class ArrayCase:
    """One fiber through ``fiber.array_rows`` rows of the array of a unit-cell
    :class:`~fibersweep.flow.cell.CellField` (see the module docstring)."""

    name = "array"

    def accepts(self, field) -> bool:
        """A pillar array's unit cell (``flow.array`` set)."""
        return isinstance(field, CellField)

    def place(
        self,
        field: CellField,
        settings: FiberSettings,
        start: FiberStart,
        rng: np.random.Generator,
        *,
        mode: int = 0,
        t_stop: float = math.nan,
    ) -> Placed:
        """Check the start (array units), place the fiber in the row gap, build the kernel.

        ``rng`` is not drawn from: the effects that draw at the start are refused here.

        Raises
        ------
        InputError
            A non-finite start, y0 outside [0, 1], a fiber shorter than one bead (or than
            the model's least), a start touching a pillar, or an effect that acts outside
            the kernels.
        """
        array = field.array
        a = settings.bead_radius
        for name in ("theta0", "y0", "length"):
            if not math.isfinite(getattr(start, name)):
                raise InputError(f"{name}: must be finite, got {getattr(start, name)!r}")
        if not 0.0 <= start.y0 <= 1.0:
            raise InputError(
                f"y0: {start.y0} is not a fraction of period_y in [0, 1] (pillar array)"
            )
        if start.length < 2.0 * a - 1e-9:
            raise InputError(
                f"length: L = {start.length} µm is shorter than one bead (2a = {2 * a} µm)"
            )
        n = n_beads_of(start.length, a, settings.bead_spacing)
        if settings.model != "rigid" and n < MIN_BEADS:
            raise InputError(
                f"length: L = {start.length} µm is {n} bead(s); the {settings.model} model "
                f"needs at least {MIN_BEADS} (a sphere runs with the rigid model)"
            )
        effects = check_array_effects(settings)
        pillar = array_pillar(array, settings, field.viscosity, field.u_center)
        if not start_clear(array, pillar, n, a, start.y0, start.theta0, settings.bead_spacing):
            raise InputError(
                f"y0: the fiber at y0 = {start.y0} (fraction of period_y), theta0 = "
                f"{start.theta0} deg touches a pillar at the start"
            )
        x0 = start_x(array)
        k = array_kernel(
            field,
            settings,
            n,
            mu=field.viscosity,
            u_center=field.u_center,
            x_end=x0 + settings.array_rows * array.period_x,
            mode=mode,
            t_stop=t_stop,
            effects=effects,
            pillar=pillar,
        )
        y0 = start.y0 * array.period_y
        return Placed(k, x0, y0, math.radians(start.theta0), n, effects.random, pillar)

    def measure(
        self,
        placed: Placed,
        field: CellField,
        settings: FiberSettings,
        start: FiberStart,
        out: Outcome,
    ) -> RunResult:
        """The transport columns from the thinned trajectory, the deformation of a bead chain.

        ``cls`` stays empty and ``delta`` NaN (channel quantities); status 'failed' with
        the reason for a run that blew up or reached ``t_max``.
        """
        array = field.array
        rec, beads, code = out.rec, out.beads, out.code
        npil = rec[:, R.CONTACT]  # pillars in contact at each step
        contact = npil > 0.5
        t = rec[:, R.T]
        has_beads = beads is not None and len(beads) > 0
        kept = _thin(R.trajectory_from_record(rec, beads if has_beads else None),
                     max(settings.record.samples, 2))  # fmt: skip
        if kept.beads is not None and not settings.record.all_beads:
            kept = dataclasses.replace(kept, beads=None)
        summ = summarise_trajectory(kept, array, placed.kernel.params.trap_speed)
        common = dict(
            start=start,
            model=settings.model,
            integrator=out.integrator.name,
            n_beads=placed.n,
            n_steps=out.integrator.steps(placed.kernel, rec),
            wall_time=out.wall,
            x_f=float(rec[-1, R.XC]),
            y_f=float(rec[-1, R.YC]),
            theta_f=float(kept.theta[-1]),
            t_end=float(t[-1]),
            min_clearance=float(np.min(rec[:, R.MIN_DIST]) - settings.bead_radius),
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
            common.update(_deformation(array, placed.state, beads, npil, settings))
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


#: The array case (:mod:`fibersweep.fiber.case`).
ARRAY = ArrayCase()
