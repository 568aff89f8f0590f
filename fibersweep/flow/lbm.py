"""The D3Q19 lattice-Boltzmann time loop: steady state of a lattice in lattice units.

The flow is driven by a uniform body force (periodic ends). The lattice speed
is kept tiny (``U_LATTICE``) so the lattice Reynolds number is far below one
and the quadratic terms of the equilibrium are negligible: the result is
Stokes flow, linear in the force, rescaled later (:mod:`fibersweep.flow.solver`
for the pillar channel, :mod:`fibersweep.flow.cell` for an array's unit cell).
:func:`run_stepper` is the one time loop with its convergence test: the
channel (:func:`solve_lattice`), its fine patch and the unit cell all run it.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, replace

import numba
import numpy as np

from fibersweep.config.flow import FlowSettings
from fibersweep.errors import SolverError
from fibersweep.flow import progress
from fibersweep.flow.analytic import duct_center_velocity
from fibersweep.flow.cuts import Cuts, pillar_cuts
from fibersweep.flow.initial import duct_guess, hele_shaw_guess, velocity_gradient
from fibersweep.flow.lattice import MACH_LIMIT, U_LATTICE, Grid, make_grid
from fibersweep.flow.prolong import prolong
from fibersweep.flow.schemes import get_collision, get_wall_scheme
from fibersweep.flow.steppers import make_stepper

__all__ = [
    "SOLVER_VERSION",
    "SolveReport",
    "LatticeSolution",
    "choose_tau",
    "rates",
    "run_stepper",
    "wall_kind",
    "solve_lattice",
    "solve_nested",
    "coarser_settings",
    "lattice_of",
]

log = logging.getLogger(__name__)

SOLVER_VERSION = "d3q19-trt-guo-3"  # 3: sub-grid (interpolated) pillar, closed solid set
SERIAL_BELOW_CELLS = 250_000  # smaller grids run on one thread (fork/join costs more)
DEFAULT_KERNEL = "aa"
REPROBE_EVERY = 10  # check intervals between re-timing the other thread counts


@dataclass(frozen=True)
class SolveReport:
    """What the solver did.

    Attributes
    ----------
    steps : int
        LBM steps taken.
    converged : bool
        True if the relative change per check fell below the tolerance.
    residual : float
        Last relative change of the velocity field per check.
    seconds : float
        Wall time of the time loop [s].
    mlups : float
        Million lattice-cell updates per second of the whole loop.
    tau : float
        Relaxation time of the even moments (τ = 3ν + 1/2).
    omega_minus : float
        Relaxation rate of the odd moments.
    force : float
        Body force density along x [lattice units].
    grid : tuple of int
        Interior nodes solved (nx, ny, nz) and nz of the full depth.
    coarse_steps, coarse_seconds : int, float
        Steps and time spent on coarser grids to build the initial guess.
    threads : int
        Thread count that was fastest (and used most) in the time loop.
    mass_change : float
        Relative change of the total fluid mass Σ ρ over the time loop
        (interpolated bounce-back does not conserve mass exactly).
    boundary : str
        How the pillar wall was represented ("interpolated", "staircase", "none").
    """

    steps: int
    converged: bool
    residual: float
    seconds: float
    mlups: float
    tau: float
    omega_minus: float
    force: float
    grid: tuple[int, int, int, int]
    coarse_steps: int = 0
    coarse_seconds: float = 0.0
    threads: int = 1
    mass_change: float = 0.0
    boundary: str = "staircase"


@dataclass(frozen=True)
class LatticeSolution:
    """Raw lattice result: velocity (3, nz, ny, nx) in lattice units, grid, report."""

    u: np.ndarray
    rho: np.ndarray
    grid: Grid
    report: SolveReport


def lattice_of(settings: FlowSettings, pillar: bool = True) -> Grid:
    """The lattice of ``settings``: the closed pillar for interpolated walls, else the open one."""
    return make_grid(
        settings.geometry.to_geometry(),
        settings.dx,
        settings.symmetry,
        pillar=pillar,
        closed=get_wall_scheme(settings.pillar_boundary).sub_grid,
    )


def choose_tau(grid: Grid) -> float:
    """Relaxation time that converges fast.

    The slowest transient is the pressure (density) field: sound waves of the
    longest wavelength damped by Hele-Shaw friction γ ≈ 12ν/H². Critical damping,
    γ ≈ 2 c_s k_min, equilibrates it fastest; it also keeps the z-diffusion
    time H²/(π²ν) short. The longest wave spans the box in x, and in y twice the
    channel between its walls or once a periodic box. τ is clipped to [0.6, 1.5].
    """
    k_min = 2.0 * math.pi / max(grid.nx, (1 if grid.periodic_y else 2) * grid.ny)
    nu = 2.0 * k_min / math.sqrt(3.0) * grid.nz_full**2 / 12.0
    return float(min(max(3.0 * nu + 0.5, 0.6), 1.5))


def rates(settings: FlowSettings, grid: Grid) -> tuple[float, float, float, float]:
    """(τ, ω+, ω−, body force) of ``settings`` on ``grid``.

    The force gives the centre speed U_LATTICE in the empty duct (ρ = 1), or in
    a box periodic in y the empty slit's (plane Poiseuille across the depth).
    The collision scheme's rates come from its registry entry.
    """
    tau = settings.tau if settings.tau is not None else choose_tau(grid)
    nu = (tau - 0.5) / 3.0
    if grid.periodic_y:
        fx = 8.0 * nu * U_LATTICE / grid.nz_full**2
    else:
        fx = U_LATTICE / duct_center_velocity(grid.ny, grid.nz_full, 1.0) * nu
    omega_p, omega_m = get_collision(settings.collision).rates(tau, settings.magic)
    return tau, omega_p, omega_m, fx


def solve_lattice(
    settings: FlowSettings,
    pillar: bool = True,
    initial: np.ndarray | None = None,
    initial_rho: np.ndarray | None = None,
    threads: int | None = None,
    kernel: str = DEFAULT_KERNEL,
    grid: Grid | None = None,
    cuts: Cuts | None = None,
) -> LatticeSolution:
    """Run the LBM to steady state.

    Parameters
    ----------
    settings : FlowSettings
        Geometry, resolution, collision model, τ, tolerance, limits.
    pillar : bool
        False solves the empty duct (validation).
    initial : ndarray, shape (3, nz, ny, nx), optional
        Initial lattice velocity; default is the duct profile, under the 2D
        Hele-Shaw flow around the pillar (:mod:`fibersweep.flow.initial`).
    initial_rho : ndarray, shape (nz, ny, nx), optional
        Initial density deviation δρ; default 0, or the Hele-Shaw pressure with
        the default velocity.
    threads : int, optional
        Numba threads; default 1 below ``SERIAL_BELOW_CELLS`` cells, else the
        faster of all and one, measured while running.
    kernel : {"aa", "pull"}
        In-place AA pattern (default, 152 B per cell update) or the two-array
        pull kernel (228 B). Both give the same field to float32 rounding.
    grid, cuts : Grid, Cuts, optional
        Validation only: solve this lattice (its ``solid`` nodes walled in)
        instead of the settings' channel, with interpolated bounce-back at the
        wall fractions ``cuts`` (None: half-way bounce-back on the solid nodes).
        By default the grid comes from the settings and the pillar wall from
        ``settings.pillar_boundary``.

    Raises
    ------
    SolverError
        If the field becomes non-finite or faster than Mach ``MACH_LIMIT``.
    """
    if grid is None:
        grid = lattice_of(settings, pillar=pillar)
        if pillar:
            shape = settings.geometry.to_geometry().shape
            cuts = pillar_cuts(grid, shape, settings.pillar_boundary)
    tau, omega_p, omega_m, fx = solve_rates = rates(settings, grid)
    nu = (tau - 0.5) / 3.0
    if initial is None and grid.solid.any():
        u0, hs_rho = hele_shaw_guess(grid, fx, fx / nu)
        initial_rho = hs_rho if initial_rho is None else initial_rho
    elif initial is None:
        u0 = duct_guess(grid, fx / nu)
    else:
        u0 = np.asarray(initial, dtype=np.float64)
    if u0.shape != (3, grid.nz, grid.ny, grid.nx):
        raise ValueError(
            f"initial must have shape {(3, grid.nz, grid.ny, grid.nx)}, got {u0.shape}"
        )
    shape3 = (grid.nz, grid.ny, grid.nx)
    rho0 = np.zeros(shape3) if initial_rho is None else np.asarray(initial_rho, np.float64)
    if rho0.shape != shape3:
        raise ValueError(f"initial_rho must have shape {shape3}, got {rho0.shape}")
    stepper = make_stepper(
        kernel, grid, u0, rho0, velocity_gradient(u0, grid), fx, omega_p, omega_m, cuts=cuts,
        dtype=np.dtype(settings.precision),
    )  # fmt: skip
    # the populations now hold the start: drop the float64 copies before the time
    # loop (1.2 GB at dx = 1 µm; solve_nested hands them over without keeping them)
    del u0, rho0, initial, initial_rho
    return run_stepper(settings, grid, stepper, solve_rates, wall_kind(grid, cuts), threads)


def wall_kind(grid: Grid, cuts: Cuts | None) -> str:
    """How the pillar wall enters ``grid``, for the report: none, staircase or interpolated."""
    if not grid.solid.any():
        return "none"
    return "staircase" if cuts is None else "interpolated"


def run_stepper(
    settings: FlowSettings, grid: Grid, stepper, solve_rates: tuple[float, float, float, float],
    boundary: str, threads: int | None = None,
) -> LatticeSolution:  # fmt: skip
    """Step ``stepper`` on ``grid`` to steady state (the time loop and its convergence test).

    Parameters
    ----------
    settings : FlowSettings
        Tolerance, check interval, step limit (and dx for the progress report).
    grid : Grid
    stepper : PullStepper or AAStepper
        Holding the start (:func:`fibersweep.flow.steppers.make_stepper`).
    solve_rates : tuple
        (τ, ω+, ω−, force) it steps with (:func:`rates`), for the report.
    boundary : str
        How the pillar wall is represented, for the report.
    threads : int, optional
        Numba threads; default 1 below ``SERIAL_BELOW_CELLS`` cells, else the
        faster of all and one, measured while running.

    Raises
    ------
    SolverError
        If the field becomes non-finite or faster than Mach ``MACH_LIMIT``.
    """
    tau, _, omega_m, fx = solve_rates
    previous_threads = numba.get_num_threads()
    if threads:
        candidates = [threads]
    elif grid.cells < SERIAL_BELOW_CELLS or previous_threads == 1:
        candidates = [1]
    else:
        candidates = [previous_threads, 1]  # chosen by measurement in _run
    try:
        return _run(settings, grid, stepper, fx, tau, omega_m, candidates, boundary)
    finally:
        numba.set_num_threads(previous_threads)


def _run(settings, grid, stepper, fx, tau, omega_m, candidates, boundary) -> LatticeSolution:
    """Time loop of :func:`run_stepper` (arguments as computed there).

    With several thread counts in ``candidates`` each is timed over one check
    interval, the fastest is used, and the others are re-timed every
    ``REPROBE_EVERY`` intervals: on a machine shared with other jobs one thread
    can beat two (each step ends in a barrier that waits for the slowest thread).
    """
    timing: dict[int, float] = {}
    interval = 0
    fluid = ~grid.solid.T[None, :, :]  # (1, ny, nx) broadcast over z
    fluid3 = np.broadcast_to(fluid, (grid.nz, grid.ny, grid.nx))
    mom = np.zeros((4, grid.nz, grid.ny, grid.nx))
    stepper.moments(mom)
    mass0 = fluid3.sum() + float(mom[0][fluid3].sum())
    u_prev = mom[1:3].copy()
    mult = stepper.step_multiple
    check = -(-settings.check_every // mult) * mult  # whole step pairs for AA
    steps = 0
    residual = math.inf
    converged = False
    t0 = time.perf_counter()
    progress.report(
        progress.SolveProgress(settings.dx, 0, settings.max_steps, residual, settings.tolerance,
                               grid.cells)
    )  # fmt: skip
    while steps < settings.max_steps:
        n = max(mult, min(check, (settings.max_steps - steps) // mult * mult))
        if interval < len(candidates):
            use = candidates[interval]
        else:
            best = min(timing, key=timing.get)
            others = [c for c in candidates if c != best]
            use = (
                others[(interval // REPROBE_EVERY) % len(others)]
                if (others and interval % REPROBE_EVERY == 0)
                else best
            )
        numba.set_num_threads(use)
        t_int = time.perf_counter()
        stepper.advance(n)
        timing[use] = (time.perf_counter() - t_int) / n
        interval += 1
        steps += n
        stepper.moments(mom)
        uxy = mom[1:3] * fluid
        sq = mom[1] ** 2  # |u|² built in place: one extra (nz, ny, nx) array, not four
        sq += mom[2] ** 2
        sq += mom[3] ** 2
        sq *= fluid
        speed_max = float(np.sqrt(sq.max()))
        del sq
        if not math.isfinite(speed_max):
            raise SolverError(
                f"LBM diverged: non-finite velocity after {steps} steps (tau={tau:g})"
            )
        if speed_max > MACH_LIMIT:
            raise SolverError(
                f"LBM diverged: lattice speed {speed_max:.3g} > {MACH_LIMIT} (Mach too high) "
                f"after {steps} steps (tau={tau:g})"
            )
        # numpy's pairwise sums, not BLAS (np.linalg.norm): BLAS threads left spinning
        # after the call slow the next interval's kernels down (2x on a 2-core cell solve)
        change = math.sqrt(sum(float(np.sum((uxy[c] - u_prev[c]) ** 2)) for c in range(2)))
        size = math.sqrt(sum(float(np.sum(uxy[c] ** 2)) for c in range(2)))
        residual = change / max(size, 1e-300)
        u_prev = uxy
        log.debug("step %d residual %.3e", steps, residual)
        progress.report(
            progress.SolveProgress(
                settings.dx, steps, settings.max_steps, residual, settings.tolerance, grid.cells
            )
        )
        if residual < settings.tolerance:
            converged = True
            break
    seconds = time.perf_counter() - t0
    u = mom[1:4] * fluid
    mass_change = (fluid3.sum() + float(mom[0][fluid3].sum())) / mass0 - 1.0
    rho = mom[0].copy()
    # solid nodes carry no density; give them the fluid mean so that a finer
    # grid interpolated from this one (prolong) sees no step at the wall
    rho[~fluid3] = float(rho[fluid3].mean()) if fluid3.any() else 0.0
    report = SolveReport(
        steps=steps,
        converged=converged,
        residual=residual,
        seconds=seconds,
        mlups=grid.cells * steps / max(seconds, 1e-12) / 1e6,
        tau=tau,
        omega_minus=omega_m,
        force=fx,
        grid=(grid.nx, grid.ny, grid.nz, grid.nz_full),
        threads=min(timing, key=timing.get),
        mass_change=mass_change,
        boundary=boundary,
    )
    if not converged:
        log.warning(
            "LBM not converged after max_steps = %d (residual %.2e > tolerance %.1e); "
            "the field is kept and cached as it is",
            steps,
            residual,
            settings.tolerance,
        )
    log.info(
        "LBM %s steps, converged=%s, residual %.2e, %.1f s, %.1f MLUPS, %s thread(s), "
        "%s pillar, mass change %.1e",
        steps,
        converged,
        residual,
        seconds,
        report.mlups,
        report.threads,
        boundary,
        mass_change,
    )
    return LatticeSolution(u=u, rho=rho, grid=grid, report=report)


def coarser_settings(settings: FlowSettings) -> FlowSettings | None:
    """The same problem at 2 Δx if that grid is valid (≥ 8 depth nodes, whole counts)."""
    try:
        return FlowSettings.model_validate({**settings.model_dump(), "dx": 2.0 * settings.dx})
    except ValueError:
        return None


def solve_nested(settings: FlowSettings, threads: int | None = None) -> LatticeSolution:
    """Solve on 2 Δx first (recursively) and start from its interpolated solution.

    On the finer grid the flow then only has to correct the discretisation
    difference, which takes far fewer steps than starting from the duct profile
    (the slow transient, the Hele-Shaw pressure equilibration around the
    pillar, is already done on the cheap grid).
    """
    coarse_settings = coarser_settings(settings)
    if coarse_settings is None:
        return solve_lattice(settings, threads=threads)
    coarse = solve_nested(coarse_settings, threads=threads)
    fine_grid = lattice_of(settings)
    fx = rates(settings, fine_grid)[3]
    density_scale = fx / coarse.report.force * (coarse.grid.dx / fine_grid.dx)
    start = list(prolong(coarse.u, coarse.rho, coarse.grid, fine_grid, density_scale))
    # popped into the call so that solve_lattice holds the only reference and can
    # free them once the populations are set
    fine = solve_lattice(settings, initial=start.pop(0), initial_rho=start.pop(0), threads=threads)
    c = coarse.report
    report = replace(
        fine.report,
        coarse_steps=c.steps + c.coarse_steps,
        coarse_seconds=c.seconds + c.coarse_seconds,
    )
    log.info(
        "nested solve: %d steps at dx=%g, then %d at dx=%g",
        coarse.report.steps,
        coarse.grid.dx,
        fine.report.steps,
        fine_grid.dx,
    )
    return replace(fine, report=report)
