"""Physical checks of the flow past the pillar (SPEC section 2)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.config.flow import FlowSettings, GeometrySettings
from fibersweep.flow.analysis import flux_separatrix, fore_aft_asymmetry, peak_speeds
from fibersweep.flow.analytic import duct_velocity
from fibersweep.flow.solver import field_from_solution, solve_lattice

SMALL = GeometrySettings(width=200.0, depth=40.0, length=400.0, pillar_height=75.0)


@pytest.fixture(scope="module")
def small_half():
    """3D lattice solution of a small pillar channel (half depth, symmetric), dx = 4 µm,
    interpolated (sub-grid) pillar."""
    settings = FlowSettings(geometry=SMALL, dx=4.0, tolerance=1e-7, pillar_boundary="interpolated")
    return settings, solve_lattice(settings)


def _plane_flux(sol) -> np.ndarray:
    """Σ_yz ρ ux through every x-plane of nodes, shape (nx,)."""
    return ((1.0 + sol.rho) * sol.u[0]).sum(axis=(0, 1))


def test_mass_flux_constant_along_x(small_half):
    # Steady mass conservation: the x-momentum flux Σ_yz ρ ux through every
    # x-plane is the same. With the interpolated pillar the node sum is exact
    # only in planes that do not meet the pillar: tolerance 1e-4 relative there
    # (measured 1e-7; the residual is the convergence tolerance and float32
    # storage). In planes through the pillar the sum of node values misses the
    # fractions of cells between the last nodes and the sub-grid wall: a
    # quadrature error, bounded by 2 % (measured 0.6 %).
    _, sol = small_half
    flux = _plane_flux(sol)
    cols = sol.grid.solid.any(axis=1)
    near = np.convolve(cols, np.ones(5), mode="same") > 0  # within 2 planes of the pillar
    assert np.ptp(flux[~near]) / flux.mean() < 1e-4, np.ptp(flux[~near]) / flux.mean()
    assert np.ptp(flux) / flux.mean() < 2e-2, np.ptp(flux) / flux.mean()
    # the pillar really is there: the flux passes around it
    assert sol.grid.solid.sum() > 100


def test_mass_flux_exactly_constant_with_staircase_pillar():
    # Half-way bounce-back on a staircase of cells conserves mass link by link:
    # the plane flux is the same everywhere, tolerance 1e-4 (measured 6e-7).
    settings = FlowSettings(geometry=SMALL, dx=4.0, tolerance=1e-7, pillar_boundary="staircase")
    flux = _plane_flux(solve_lattice(settings))
    assert np.ptp(flux) / flux.mean() < 1e-4, np.ptp(flux) / flux.mean()


def test_half_depth_with_symmetry_plane_equals_full_depth(small_half):
    # The midplane field of the half-depth solve with a free-slip top equals that
    # of the full-depth solve; tolerance 1e-4 U_center (measured 4e-7).
    settings, sol = small_half
    full_settings = settings.model_copy(update={"symmetry": False})
    full = solve_lattice(full_settings)
    f_half = field_from_solution(settings, sol)
    f_full = field_from_solution(full_settings, full)
    u = settings.fluid.u_center
    assert np.abs(f_half.ux - f_full.ux).max() < 1e-4 * u
    assert np.abs(f_half.uy - f_full.uy).max() < 1e-4 * u
    # full-depth 3D field is symmetric about the midplane
    nz = full.grid.nz
    assert np.abs(full.u[0:2] - full.u[0:2, ::-1]).max() < 1e-5 * np.abs(full.u[0]).max()
    assert nz == 2 * sol.grid.nz


def _ghost_layer(f) -> np.ndarray:
    """Solid nodes that carry a ghost value (within GHOST_REACH nodes of the fluid)."""
    from scipy.ndimage import binary_dilation

    from fibersweep.flow.ghost import GHOST_REACH

    reach = binary_dilation(~f.solid, np.ones((3, 3), bool), iterations=GHOST_REACH)
    return reach & f.solid


def _wall_and_offset_speeds(f, offset: float) -> tuple[np.ndarray, np.ndarray]:
    """|u| / U_center at 81 points on each pillar face (corners excluded: t in [0.1, 0.9])
    and at the same points moved ``offset`` µm out along the face's outward normal."""
    v = np.asarray(f.geometry.vertices, float)
    c = np.asarray(f.geometry.centroid, float)
    t = np.linspace(0.1, 0.9, 81)[:, None]
    wall, out = [], []
    for k in range(len(v)):
        a, b = v[k], v[(k + 1) % len(v)]
        n = np.array([-(b - a)[1], (b - a)[0]]) / np.hypot(*(b - a))
        if np.dot((a + b) / 2 - c, n) < 0:
            n = -n
        p = a + t * (b - a)
        wall.append(np.hypot(*f.velocity(p).T))
        out.append(np.hypot(*f.velocity(p + offset * n).T))
    u = f.fluid.u_center
    return np.concatenate(wall) / u, np.concatenate(out) / u


def test_solid_nodes_at_rest_and_no_slip(coarse_field):
    # Default (interpolated, sub-grid) pillar. Solid nodes within GHOST_REACH nodes of
    # the fluid carry ghost values (fibersweep/flow/ghost.py: u(s) = -u(mirror)), so that
    # the interpolated field vanishes on the exact wall; deeper solid nodes are at rest.
    f = coarse_field
    assert f.meta["settings"]["pillar_boundary"] == "interpolated"
    ghost = _ghost_layer(f)
    deep = f.solid & ~ghost
    assert deep.sum() > 0 and ghost.sum() > 0
    assert np.all(f.ux[deep] == 0.0) and np.all(f.uy[deep] == 0.0)
    assert np.abs(f.ux[ghost]).max() > 0.0  # the ghost layer is filled
    # the IB kernel (two nodes each side) at the centroid reaches only deep nodes: zero
    xc, yc = f.geometry.centroid
    assert np.all(f.velocity(np.array([[xc, yc]])) == 0.0)
    # No slip at the exact wall: the interpolated speed on each face is below
    # 0.05 U_center (measured at most 0.039, near the apex where the shear is largest)
    # and its mean is below a tenth of the mean speed one lattice spacing out along the
    # normal (measured 0.008 U against 0.23 U).
    wall, out = _wall_and_offset_speeds(f, f.dx)
    assert wall.max() < 0.05, wall.max()
    assert wall.mean() < 0.1 * out.mean(), (wall.mean(), out.mean())


def test_staircase_solid_nodes_at_rest(flow_cache_dir):
    # Staircase pillar (kept for comparison): every solid node is at rest (no ghosts),
    # and the centroid reads zero.
    from fibersweep.flow.cache import get_flow_field

    f, _ = get_flow_field(FlowSettings(dx=4.0, pillar_boundary="staircase"), flow_cache_dir)
    assert f.solid.sum() > 0
    assert np.all(f.ux[f.solid] == 0.0) and np.all(f.uy[f.solid] == 0.0)
    xc, yc = f.geometry.centroid
    assert np.all(f.velocity(np.array([[xc, yc]])) == 0.0)


def test_scaled_to_u_center_and_far_field_is_duct_flow(coarse_field):
    # Far from the pillar the midplane field is the duct profile averaged in z with
    # the IB weights φ(±1/2) = 0.4268, φ(±3/2) = 0.0732, scaled so that the
    # centreline speed at z = H/2 is U_center. Tolerance 1 % of U_center
    # (lattice error at 10 nodes across the depth is ~0.4 %).
    f = coarse_field
    g = f.geometry
    assert f.meta["u_center_reached"] == pytest.approx(f.fluid.u_center, rel=1e-9)
    i_far = int(np.argmin(np.abs(f.x_nodes - (g.base_center[0] + g.length / 2) % g.length)))
    y = f.y_nodes
    mid = g.depth / 2.0
    zs = mid + f.dx * np.array([-1.5, -0.5, 0.5, 1.5])
    w = 0.25 * (1.0 + np.cos(np.pi * (zs - mid) / (2.0 * f.dx)))
    assert w.sum() == pytest.approx(1.0)
    prof = sum(
        wk * duct_velocity(y, zk, g.width, g.depth, 1.0) for wk, zk in zip(w, zs, strict=True)
    )
    centre = duct_velocity(np.array(g.width / 2), np.array(mid), g.width, g.depth, 1.0)
    expect = prof / centre * f.fluid.u_center
    assert np.abs(f.ux[i_far] - expect).max() < 1e-2 * f.fluid.u_center
    assert np.abs(f.uy[i_far]).max() < 1e-3 * f.fluid.u_center


def test_fore_aft_symmetry(coarse_field):
    # Stokes flow past a pillar symmetric about x = x_c: |u| is fore-aft symmetric.
    # Tolerance 5e-4 U_center. Measured 5e-5; the residual asymmetry is the
    # lattice's own inertia (it scales as 1/ν and with the lattice speed: 5e-4
    # at U_lattice = 1e-4, 5e-5 at the 1e-5 used), Re_lattice ~ 2e-3.
    assert fore_aft_asymmetry(coarse_field) < 5e-4


def test_separatrix_far_upstream_near_one_third(coarse_field):
    # SPEC: the streamline ending on the upstream face sits near y/h_obs ≈ 1/3 far
    # upstream (an independent BGK check gave 0.36). Accept 0.30..0.40.
    # Measured: 0.313 (TRT, dx = 4 µm, interpolated pillar; 0.342 with the staircase).
    sep = flux_separatrix(coarse_field)
    assert 0.30 < sep.y_far_over_h < 0.40, sep
    # the flux below the pillar is the same in every column through it (2D
    # continuity of the z-averaged field); tolerance 1 % (measured 0.1 %)
    assert sep.psi_spread < 1e-2, sep


def test_peak_speeds_in_the_gaps(coarse_field):
    # SPEC: about 1.5 U_center just above the apex. Accept 1.3..1.7 (measured 1.51; staircase 1.50).
    # Below the flat base no peak can be slower than the mean speed there, fixed
    # by mass balance: flux below the pillar / gap width (measured peak 1.20,
    # mean 1.01; staircase 1.22 and ~1.1; see the report about the SPEC's "1.5 below the base").
    f = coarse_field
    above, below = peak_speeds(f)
    assert 1.3 < above < 1.7, above
    sep = flux_separatrix(f)
    gap = f.geometry.base_center[1]
    mean_below = sep.psi / gap / f.fluid.u_center
    assert below > mean_below > 0.9, (below, mean_below)
    assert math.isfinite(below) and below < 1.7


def test_traced_and_flux_separatrix_agree_within_a_cell(coarse_field):
    # Two independent methods: RK4 tracing of the midplane field (canonical, what a
    # fiber follows) and the flux passing below the pillar (assumes the z-averaged
    # field is 2D divergence-free, which it is not exactly near the full-depth
    # pillar). Tolerance: one lattice spacing, dx/h_obs. Measured 0.322 vs 0.313
    # (interpolated pillar; staircase 0.351 vs 0.342).
    from fibersweep.flow.streamlines import separatrix_y

    traced = separatrix_y(coarse_field)
    flux = flux_separatrix(coarse_field).y_far_over_h
    assert abs(traced - flux) < coarse_field.dx / coarse_field.geometry.pillar_height
    assert traced >= flux  # the 3D effect lifts the traced streamline
