"""One fiber run: validate the start, integrate (rigid or bead-spring), classify, report.

:func:`simulate` is the public entry point the sweep calls thousands of times:
a module-level function (picklable), Numba kernels compiled once per process
(``cache=True``), per-length body mobilities cached (``body_mobility``).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass

import numpy as np

from fibersweep.analysis.classify import classify
from fibersweep.analysis.observables import (
    fiber_angle,
    first_contact_index,
    pass_time,
    take,
    thin_indices,
    trajectory_from_record,
)
from fibersweep.errors import InputError
from fibersweep.fiber import record as R
from fibersweep.fiber.contact import Pillar, make_pillar, outline_distance
from fibersweep.fiber.effects import DynamicsContext, DynamicsParams, build_effects
from fibersweep.fiber.kparams import pack
from fibersweep.fiber.mobility import body_mobility, fiber_offsets
from fibersweep.fiber.result import FiberStart, RunResult, Trajectory
from fibersweep.fiber.rigid import integrate_rigid, seed_numba
from fibersweep.fiber.settings import FiberSettings
from fibersweep.flow.field import FlowField

__all__ = ["Setup", "prepare", "simulate", "simulate_for", "simulate_reversible"]

log = logging.getLogger(__name__)

CHUNK = 20_000  # record rows per kernel call
MIN_BEADS = 2


@dataclass(frozen=True)
class Setup:
    """Everything a kernel needs for one run, validated.

    Attributes
    ----------
    field : FlowField
        The (effect-transformed) field.
    settings : FiberSettings
    start : FiberStart
    n : int
        Beads.
    x0, y0_abs, th0 : float
        Start centre [µm] and directed angle of the axis towards bead n-1 [rad]
        (bead n-1 is the head: the one that leads).
    pillar : Pillar
    params : DynamicsParams
    u_center : float
        Signed centreline speed of the field [µm/s].
    """

    field: FlowField
    settings: FiberSettings
    start: FiberStart
    n: int
    x0: float
    y0_abs: float
    th0: float
    pillar: Pillar
    params: DynamicsParams
    u_center: float


def _finite(name: str, value: float) -> None:
    if not math.isfinite(value):
        raise InputError(f"{name}: must be finite, got {value!r}")


def prepare(
    field: FlowField, settings: FiberSettings, start: FiberStart, rng: np.random.Generator
) -> Setup:
    """Apply effects and check the start; InputError naming the parameter when it is bad."""
    effects = build_effects(settings.effects)
    field = effects.field(field)
    settings = effects.settings(settings)
    start = effects.start(start, rng)
    for name in ("theta0", "y0", "length"):
        _finite(name, float(getattr(start, name)))
    geo = field.geometry
    a = settings.bead_radius
    u_center = float(field.fluid.u_center)
    _finite("u_center", u_center)
    if u_center == 0.0:
        raise InputError("u_center: the field has zero speed")
    length_um = start.length * geo.pillar_base_length
    n = int(round(length_um / (2.0 * a)))
    if start.length <= 0 or n < MIN_BEADS:
        raise InputError(
            f"length: L/l_obs = {start.length} is {length_um:.3g} µm, {n} bead(s) of "
            f"radius {a} µm; at least {MIN_BEADS} beads are needed"
        )
    if length_um < 2.0 * field.dx:
        raise InputError(
            f"length: L = {length_um:.3g} µm is shorter than two grid spacings "
            f"(dx = {field.dx} µm): the flow field cannot resolve it"
        )
    x0 = geo.length / 4.0 if settings.x0 is None else float(settings.x0)
    _finite("x0", x0)
    y0_abs = geo.y_from_base(start.y0)
    th0 = math.radians(start.theta0)
    if math.cos(th0) < 0.0:  # keep bead n-1 as the leading bead (the head)
        th0 += math.pi
    s = fiber_offsets(n, a)
    bx = x0 + s * math.cos(th0)
    by = y0_abs + s * math.sin(th0)
    if by.min() - a <= 0.0 or by.max() + a >= geo.width:
        raise InputError(
            f"y0: y0/h = {start.y0} with theta0 = {start.theta0}° puts beads outside the "
            f"channel (bead y from {by.min():.1f} to {by.max():.1f} µm, width {geo.width} µm)"
        )
    if bx.min() - a <= 0.0 or bx.max() + a >= geo.length:
        raise InputError(f"x0: the fiber at x0 = {x0} µm does not fit in the channel length")
    f_ref = settings.contact.f_ref or 6.0 * math.pi * field.fluid.viscosity * a * abs(u_center)
    pillar = make_pillar(geo, settings.contact, a, f_ref)
    for xb, yb in zip(bx, by, strict=True):
        d = outline_distance(float(xb), float(yb), pillar.vertices)
        if d < pillar.r_cut:
            raise InputError(
                f"y0: the start (theta0 = {start.theta0}°, y0/h = {start.y0}, x0 = {x0} µm) "
                f"overlaps the pillar (bead at {d:.2f} µm from its outline)"
            )
    ctx = DynamicsContext(bead_radius=a, dx=float(field.dx), depth=geo.depth)
    params = effects.params(ctx)
    return Setup(field, settings, start, n, x0, y0_abs, th0, pillar, params, u_center)


def kernel_params(setup: Setup, mode: int = 0, t_stop: float = math.nan) -> np.ndarray:
    """The kparams vector of a run."""
    st = setup.settings
    geo = setup.field.geometry
    p = setup.params
    a = st.bead_radius
    u = abs(setup.u_center)
    x_pass = float(setup.pillar.vertices[:, 0].max())
    return pack(
        a=a,
        kind=setup.pillar.kind,
        r_cut=setup.pillar.r_cut,
        r_eq=setup.pillar.r_eq,
        f_ref=setup.pillar.f_ref,
        vscale=p.velocity_scale,
        mu_f=p.friction,
        hyd_s=p.hydro_strength,
        hyd_l=p.hydro_length,
        kT=p.kT,
        max_disp=st.step.max_displacement,
        contact_disp=st.step.contact_displacement,
        dt_max=st.classify.trap_time / 20.0,
        t_max=st.step.t_max,
        x_stop=x_pass + st.step.x_end,
        t_stop=t_stop,
        mode=mode,
        trap_speed=st.classify.trap_speed * u,
        trap_time=st.classify.trap_time,
        y_lo=a,
        y_hi=geo.width - a,
        dt=st.step.dt if st.step.dt is not None else math.nan,
        stretch=st.young_modulus * math.pi * a**2,  # Pa == pN/µm²
        bend=st.young_modulus * math.pi * a**4 / 4.0,
        mu=setup.field.fluid.viscosity,
    )


def _run_rigid(
    setup: Setup, prm: np.ndarray, x0: float, y0: float, th0: float
) -> tuple[np.ndarray, None, int]:
    st = setup.settings
    bm = body_mobility(setup.n, float(st.bead_radius), float(setup.field.fluid.viscosity))
    f = setup.field
    pil = setup.pillar
    ux = np.ascontiguousarray(f.ux, dtype=np.float64)
    uy = np.ascontiguousarray(f.uy, dtype=np.float64)
    pbx = np.ascontiguousarray(pil.beads[:, 0])
    pby = np.ascontiguousarray(pil.beads[:, 1])
    state = np.array([0.0, x0, y0, th0, math.nan])
    chunks = []
    while True:
        rec = np.empty((CHUNK, R.NCOLS))
        rows, code = integrate_rigid(
            state, bm.offsets, bm.P, bm.N, bm.chol, bm.tip_mobility, ux, uy, float(f.dx),
            pil.vertices, pbx, pby, pil.curves, prm, rec,
        )  # fmt: skip
        chunks.append(rec[:rows])
        if code != R.CHUNK_FULL:
            return np.concatenate(chunks), None, code


def _integrate(
    setup: Setup,
    prm: np.ndarray,
    x0: float,
    y0: float,
    th0: float,
    beads0: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray | None, int]:
    """Run the selected model; returns (record rows, bead positions or None, stop code)."""
    if setup.settings.model == "rigid":
        return _run_rigid(setup, prm, x0, y0, th0)
    from fibersweep.fiber.beadspring import run_bead_spring

    return run_bead_spring(setup, prm, x0, y0, th0, beads0)


def _seed(rng: np.random.Generator, setup: Setup) -> None:
    if setup.params.kT > 0.0:
        seed_numba(int(rng.integers(0, 2**31 - 1)))


def _result(
    setup: Setup, rec: np.ndarray, beads: np.ndarray | None, code: int, wall: float
) -> RunResult:
    st = setup.settings
    geo = setup.field.geometry
    traj = trajectory_from_record(rec, beads)
    common = dict(
        start=setup.start,
        n_steps=int(len(rec) - 1),
        wall_time=wall,
        model=st.model,
        n_beads=setup.n,
        min_clearance=float(np.min(rec[:, R.MIN_DIST]) - st.bead_radius),
        x_f=float(traj.x[-1]),
        y_f=float(traj.y[-1]),
        theta_f=float(traj.theta[-1]),
        t_end=float(traj.t[-1]),
    )
    k = first_contact_index(traj)
    if k is not None:
        common.update(
            contact=True,
            theta_c=fiber_angle(float(traj.theta[k])),
            y_c=float(geo.y_over_h(rec[k, R.CY])),
            t_contact=float(traj.t[k]),
        )
    common["t_pass"] = pass_time(traj, float(setup.pillar.vertices[:, 0].max()), setup.u_center)
    if st.record.trajectories:
        idx = thin_indices(traj, st.record.samples, setup.u_center, st.classify)
        kept = take(traj, idx)
        if st.record.all_beads and kept.beads is None:
            s = fiber_offsets(setup.n, st.bead_radius)
            th = rec[idx, R.TH]
            bx = rec[idx, R.XC][:, None] + np.cos(th)[:, None] * s[None, :]
            by = rec[idx, R.YC][:, None] + np.sin(th)[:, None] * s[None, :]
            kept = take(traj, idx).__class__(**{**kept.__dict__, "beads": np.stack([bx, by], -1)})
        elif not st.record.all_beads and kept.beads is not None:
            kept = kept.__class__(**{**kept.__dict__, "beads": None})
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
    field : FlowField
        Steady midplane flow [µm/s].
    settings : FiberSettings
        Model, contact, stepping, classification, recording, effects.
    start : FiberStart
        theta0 [deg], y0 / h_obs, L / l_obs.
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
        an unknown effect.
    """
    t_wall = time.perf_counter()
    rng = np.random.default_rng(rng_seed)
    setup = prepare(field, settings, start, rng)
    _seed(rng, setup)
    prm = kernel_params(setup)
    try:
        rec, beads, code = _integrate(setup, prm, setup.x0, setup.y0_abs, setup.th0)
    except (FloatingPointError, np.linalg.LinAlgError, ZeroDivisionError) as exc:
        log.warning("run %s failed: %s", start, exc)
        return RunResult(
            start=start, status="failed", reason=f"numerical error: {exc}", model=settings.model
        )
    return _result(setup, rec, beads, code, time.perf_counter() - t_wall)


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
    prm = kernel_params(setup, mode=1, t_stop=t_total)
    th_f = math.radians(fwd.theta_f)
    beads_f = fwd_beads[-1] if fwd_beads is not None else None
    rec, beads, code = _integrate(setup, prm, fwd.x_f, fwd.y_f, th_f, beads_f)
    if code < 0:
        return fwd, math.nan
    s = fiber_offsets(setup.n, settings.bead_radius)
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
    prm = kernel_params(setup, mode=1, t_stop=duration)
    rec, beads, code = _integrate(setup, prm, setup.x0, setup.y0_abs, setup.th0)
    return trajectory_from_record(rec, beads), R.STOP_REASONS.get(code, "")
