"""Steady D3Q19 lattice-Boltzmann solve of the pillar channel, and the FlowField it gives.

The flow is driven by a uniform body force along x (periodic ends). The lattice
speed is kept tiny (``U_LATTICE``) so the lattice Reynolds number is far below
one and the quadratic terms of the equilibrium are negligible: the result is
Stokes flow, which is linear in the force, so it is rescaled afterwards so that
the midplane centreline speed far from the pillar equals ``fluid.u_center``.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import asdict, dataclass

import numpy as np

from fibersweep import __version__
from fibersweep.errors import SolverError
from fibersweep.flow import kernels
from fibersweep.flow.analytic import duct_center_velocity, duct_velocity
from fibersweep.flow.field import FlowField, ib_phi
from fibersweep.flow.lattice import E, W, Grid, boundary_links, make_grid, pull_sources
from fibersweep.flow.settings import FlowSettings

__all__ = [
    "SOLVER_VERSION",
    "U_LATTICE",
    "SolveReport",
    "LatticeSolution",
    "choose_tau",
    "solve_lattice",
    "solve_flow",
    "midplane_average",
    "midplane_centre_speed",
]

log = logging.getLogger(__name__)

SOLVER_VERSION = "d3q19-trt-guo-1"
U_LATTICE = 1e-4  # duct centre speed in lattice units: Mach ~ 2e-4, lattice Re << 1
MACH_LIMIT = 0.1  # |u| in lattice units above this means divergence


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


@dataclass(frozen=True)
class LatticeSolution:
    """Raw lattice result: velocity (3, nz, ny, nx) in lattice units, grid, report."""

    u: np.ndarray
    rho: np.ndarray
    grid: Grid
    report: SolveReport


def choose_tau(grid: Grid) -> float:
    """Relaxation time that converges fast.

    The slowest transient is the pressure (density) field: sound waves of the
    longest wavelength damped by Hele-Shaw friction γ ≈ 12ν/H². Critical damping,
    γ ≈ 2 c_s k_min, equilibrates it fastest; it also keeps the z-diffusion
    time H²/(π²ν) short. τ is clipped to [0.6, 1.5].
    """
    k_min = 2.0 * math.pi / max(grid.nx, 2 * grid.ny)
    nu = 2.0 * k_min / math.sqrt(3.0) * grid.nz_full**2 / 12.0
    return float(min(max(3.0 * nu + 0.5, 0.6), 1.5))


def _rates(settings: FlowSettings, grid: Grid) -> tuple[float, float, float]:
    tau = settings.tau if settings.tau is not None else choose_tau(grid)
    omega_p = 1.0 / tau
    if settings.collision == "bgk":
        return tau, omega_p, omega_p
    # Λ = (1/ω+ − 1/2)(1/ω− − 1/2)
    omega_m = 1.0 / (settings.magic / (tau - 0.5) + 0.5)
    return tau, omega_p, omega_m


def _duct_guess(grid: Grid, g_over_nu: float) -> np.ndarray:
    """Duct profile in lattice units, shape (3, nz, ny, nx), zero in the pillar."""
    y = np.arange(grid.ny) + 0.5
    z = np.arange(grid.nz) + 0.5
    prof = duct_velocity(y[None, :], z[:, None], grid.ny, grid.nz_full, g_over_nu)
    u = np.zeros((3, grid.nz, grid.ny, grid.nx))
    u[0] = prof[:, :, None]
    u[0][:, grid.solid.T] = 0.0
    return u


def solve_lattice(
    settings: FlowSettings, pillar: bool = True, initial: np.ndarray | None = None
) -> LatticeSolution:
    """Run the LBM to steady state.

    Parameters
    ----------
    settings : FlowSettings
        Geometry, resolution, collision model, τ, tolerance, limits.
    pillar : bool
        False solves the empty duct (validation).
    initial : ndarray, shape (3, nz, ny, nx), optional
        Initial lattice velocity; default is the analytic duct profile.

    Raises
    ------
    SolverError
        If the field becomes non-finite or faster than Mach ``MACH_LIMIT``.
    """
    geom = settings.geometry.to_geometry()
    grid = make_grid(geom, settings.dx, settings.symmetry, pillar=pillar)
    tau, omega_p, omega_m = _rates(settings, grid)
    nu = (tau - 0.5) / 3.0
    # body force giving U_LATTICE at the centre of the empty duct (ρ = 1)
    fx = U_LATTICE / duct_center_velocity(grid.ny, grid.nz_full, 1.0) * nu
    links, solid_cells = boundary_links(grid)
    sources = pull_sources(grid)
    ex, ey, ez = (np.ascontiguousarray(E[:, k]) for k in range(3))

    g = np.zeros(grid.padded_shape, dtype=np.float32)
    gn = np.zeros_like(g)
    u0 = _duct_guess(grid, fx / nu) if initial is None else np.asarray(initial, dtype=np.float64)
    if u0.shape != (3, grid.nz, grid.ny, grid.nx):
        raise ValueError(f"initial must have shape {(3, grid.nz, grid.ny, grid.nx)}, got {u0.shape}")
    kernels.init_equilibrium(g, u0, W, ex, ey, ez)
    kernels.fill_periodic(g)
    kernels.fill_pillar(g, solid_cells, links)
    fluid = ~grid.solid.T[None, :, :]  # (1, ny, nx) broadcast over z
    mom = np.zeros((4, grid.nz, grid.ny, grid.nx))
    kernels.moments(g, sources, fx, ex, ey, ez, mom)
    u_prev = mom[1:3].copy()
    check = settings.check_every
    steps = 0
    residual = math.inf
    converged = False
    t0 = time.perf_counter()
    while steps < settings.max_steps:
        n = min(check, settings.max_steps - steps)
        for _ in range(n):
            kernels.stream_collide(g, gn, sources, fx, omega_p, omega_m)
            kernels.fill_pillar(gn, solid_cells, links)
            g, gn = gn, g
        steps += n
        kernels.moments(g, sources, fx, ex, ey, ez, mom)
        uxy = mom[1:3] * fluid
        speed_max = float(np.sqrt((mom[1:4] ** 2).sum(axis=0) * fluid).max())
        if not math.isfinite(speed_max):
            raise SolverError(f"LBM diverged: non-finite velocity after {steps} steps (tau={tau:g})")
        if speed_max > MACH_LIMIT:
            raise SolverError(
                f"LBM diverged: lattice speed {speed_max:.3g} > {MACH_LIMIT} (Mach too high) "
                f"after {steps} steps (tau={tau:g})"
            )
        residual = float(np.linalg.norm(uxy - u_prev) / max(np.linalg.norm(uxy), 1e-300))
        u_prev = uxy.copy()
        log.debug("step %d residual %.3e", steps, residual)
        if residual < settings.tolerance:
            converged = True
            break
    seconds = time.perf_counter() - t0
    u = mom[1:4] * fluid
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
    )
    log.info(
        "LBM %s steps, converged=%s, residual %.2e, %.1f s, %.1f MLUPS",
        steps,
        converged,
        residual,
        seconds,
        report.mlups,
    )
    return LatticeSolution(u=u, rho=mom[0].copy(), grid=grid, report=report)


def midplane_weights(grid: Grid) -> list[tuple[int, float]]:
    """(solved z index, IB weight) pairs that average a field at z = H/2.

    Full-depth nodes sit at (k + 1/2) Δx; a node mirrored across the midplane
    (symmetric solve) maps to its image nz_full − 1 − k.
    """
    mid = grid.nz_full / 2.0
    acc: dict[int, float] = {}
    for k in range(grid.nz_full):
        w = ib_phi(k + 0.5 - mid)
        if w == 0.0:
            continue
        ks = k if k < grid.nz else grid.nz_full - 1 - k
        acc[ks] = acc.get(ks, 0.0) + w
    return sorted(acc.items())


def midplane_average(u: np.ndarray, grid: Grid) -> np.ndarray:
    """IB-kernel z-average of the in-plane velocity at z = H/2.

    Parameters
    ----------
    u : ndarray, shape (3, nz, ny, nx)

    Returns
    -------
    ndarray, shape (2, nx, ny)
        (ux, uy) averaged, x-major like FlowField.
    """
    out = np.zeros((2, grid.ny, grid.nx))
    for k, w in midplane_weights(grid):
        out += w * u[0:2, k]
    return out.transpose(0, 2, 1).copy()


def _bilinear_periodic_x(plane: np.ndarray, gx: float, gy: float) -> float:
    """Value of plane (nx, ny) at lattice coordinates (gx, gy) (node i at gx = i)."""
    nx, ny = plane.shape
    i0 = math.floor(gx)
    j0 = min(max(math.floor(gy), 0), ny - 2)
    tx = gx - i0
    ty = gy - j0
    i0 %= nx
    i1 = (i0 + 1) % nx
    return float(
        (1 - tx) * (1 - ty) * plane[i0, j0]
        + tx * (1 - ty) * plane[i1, j0]
        + (1 - tx) * ty * plane[i0, j0 + 1]
        + tx * ty * plane[i1, j0 + 1]
    )


def midplane_centre_speed(u: np.ndarray, grid: Grid, x_far: float, y_mid: float) -> float:
    """ux at (x_far, y_mid, H/2) [positions in µm], from the symmetric z-profile.

    With a node on the midplane it is used directly; otherwise the parabola
    u = a − b ζ² through the nodes at ζ = 1/2 and 3/2 from the midplane gives
    a = (9 u(1/2) − u(3/2)) / 8.
    """
    gx = x_far / grid.dx - 0.5
    gy = y_mid / grid.dx - 0.5
    if grid.nz_full % 2:
        k = grid.nz_full // 2
        return _bilinear_periodic_x(u[0, k].T, gx, gy)
    k1 = grid.nz_full // 2 - 1  # ζ = 1/2, exists in both solves
    k2 = k1 - 1  # ζ = 3/2
    u1 = _bilinear_periodic_x(u[0, k1].T, gx, gy)
    u2 = _bilinear_periodic_x(u[0, k2].T, gx, gy)
    return (9.0 * u1 - u2) / 8.0


def solve_flow(settings: FlowSettings, initial: np.ndarray | None = None) -> FlowField:
    """Steady midplane flow for ``settings``, scaled to ``fluid.u_center``.

    Parameters
    ----------
    settings : FlowSettings
    initial : ndarray, shape (3, nz, ny, nx), optional
        Initial lattice velocity (e.g. an interpolated coarser solution).

    Returns
    -------
    FlowField
        ux, uy [µm/s] of shape (nx, ny), z-averaged with the IB kernel at z = H/2;
        ``meta`` holds the solver report and settings.
    """
    sol = solve_lattice(settings, pillar=True, initial=initial)
    return field_from_solution(settings, sol)


def field_from_solution(settings: FlowSettings, sol: LatticeSolution) -> FlowField:
    """Scale a lattice solution to physical units and build the FlowField."""
    geom = settings.geometry.to_geometry()
    fluid = settings.fluid.to_fluid()
    grid = sol.grid
    x_far = (geom.base_center[0] + geom.length / 2.0) % geom.length
    u_ref = midplane_centre_speed(sol.u, grid, x_far, geom.width / 2.0)
    if not (math.isfinite(u_ref) and u_ref > 0):
        raise SolverError(f"centreline speed far from the pillar is {u_ref!r}; cannot scale")
    scale = fluid.u_center / u_ref
    ux, uy = midplane_average(sol.u, grid) * scale
    meta = {
        "solver_version": SOLVER_VERSION,
        "package_version": __version__,
        "settings": settings.model_dump(mode="json"),
        "report": {**asdict(sol.report), "grid": list(sol.report.grid)},
        "scale_um_per_s_per_lattice": scale,
        "u_center_reached": midplane_centre_speed(sol.u * scale, grid, x_far, geom.width / 2.0),
        "dx_um": grid.dx,
        "units": {"length": "um", "velocity": "um/s"},
    }
    u3d = sol.u * scale if settings.keep_3d else None
    return FlowField(
        ux=ux,
        uy=uy,
        dx=grid.dx,
        geometry=geom,
        fluid=fluid,
        solid=grid.solid.copy(),
        meta=meta,
        u3d=u3d,
    )
