"""Unit-cell flow of a tilted pillar array against an explicit block, fluxes, the first
streamline and the Hele-Shaw permeability of a square array of cylinders."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from fibersweep.config.flow import FlowSettings
from fibersweep.flow.analytic import duct_velocity
from fibersweep.flow.cell import (
    cell_solution,
    field_of,
    first_streamline_width,
    solve_block,
    solve_cell,
)
from fibersweep.flow.lattice import U_LATTICE
from fibersweep.flow.schemes import get_collision


def _settings(eps: float, shape: str = "circle", **flow) -> FlowSettings:
    """80 µm periods, pillar 40 µm, 40 µm deep, dx = 4 µm unless ``flow`` says otherwise."""
    array = {"pillar_shape": shape, "pillar_size": 40.0, "period_x": 80.0, "period_y": 80.0,
             "shift": eps, "depth": 40.0, **flow.pop("array", {})}  # fmt: skip
    return FlowSettings.model_validate({"dx": 4.0, "array": array, **flow})


def _block_settings(eps: float, **flow) -> FlowSettings:
    """Staircase pillars (the block's straddle the lateral edge), float64, tight tolerance."""
    return _settings(eps, pillar_boundary="staircase", tolerance=1e-7, precision="float64",
                     array={"mean_flow": "force"}, **flow)  # fmt: skip


def _cell_vs_block(s: FlowSettings, eps: float, axis: int = 0, kernel: str = "aa") -> float:
    """Largest difference between the cell and each row of its 1/ε-row block, over the peak."""
    rows = round(1 / eps)
    cell = cell_solution(s, axis, kernel=kernel)
    block = solve_block(s, rows, axis, kernel=kernel)
    nx, shift = cell.grid.nx, cell.grid.shift
    peak = np.abs(cell.u).max()
    worst = 0.0
    for r in range(rows):
        part = block.u[:, :, :, r * nx : (r + 1) * nx]
        worst = max(worst, float(np.abs(part - np.roll(cell.u, r * shift, axis=2)).max()))
    return worst / peak


@pytest.mark.parametrize("eps", [pytest.param(0.1, marks=pytest.mark.slow), 0.2])
def test_unit_cell_equals_block_of_one_over_eps_rows(eps):
    """Shifted periodic cell vs 1/ε explicit rows with plain periodic ends (dx = 4 µm).

    Both use staircase pillars (the block's pillars straddle the lateral edge)
    and the same τ and start; node by node the arithmetic is the same, so any
    error in the shifted boundary shows at O(1). Tolerance: 1e-9 of the peak speed.
    """
    s = _block_settings(eps)
    assert _cell_vs_block(s, eps) < 1e-9
    # every gap of the block carries the same flux: one gap per row and lateral period
    a = s.array.to_array()
    rows = round(1 / eps)
    block = solve_block(s, rows)
    flux = block.u[0].sum(axis=(0, 1))  # per x column
    centres = [int((a.centre(r, 0)[0]) / 4.0) for r in range(rows)]
    assert np.ptp(flux[centres]) < 1e-9 * flux.mean()


@pytest.mark.parametrize("kernel", ["aa", "pull"])
def test_cell_driven_across_equals_block_and_the_turned_square_cell(kernel):
    """The force along y (the kernels' turned frame) through the shifted boundary, both steppers.

    (1) The cell vs its 1/ε-row block, both driven along y: the same arithmetic
    node by node, tolerance 1e-9 of the peak. (2) A square cell with a centred
    circle and no shift is invariant under a quarter turn, so the field driven
    along y is the one driven along x turned by 90° (R: (x, y) → (−y, x)):
    u(r) = R u'(R⁻¹ r), i.e. (ux, uy, uz)(x, y) = (−u'y, u'x, u'z)(y, −x) about the
    cell's centre. The turned frame makes the same sums in the same order at the
    turned nodes, so tolerance 1e-12 of the peak (float64 rounding; measured 0).
    """
    assert _cell_vs_block(_block_settings(0.2), 0.2, axis=1, kernel=kernel) < 1e-9
    s = _block_settings(0.0)
    along = cell_solution(s, 0, kernel=kernel).u
    across = cell_solution(s, 1, kernel=kernel).u
    # node (x, y) = (i, j) of `across` reads node (j, n − 1 − i) of `along`: R⁻¹ r
    turned = np.empty_like(along)
    turned[0] = -np.rot90(along[1], k=-1, axes=(1, 2))
    turned[1] = np.rot90(along[0], k=-1, axes=(1, 2))
    turned[2] = np.rot90(along[2], k=-1, axes=(1, 2))
    assert np.abs(across - turned).max() < 1e-12 * np.abs(along).max()
    assert across[1].sum() > 0 and abs(across[0].sum()) < 1e-9 * across[1].sum()


@pytest.mark.parametrize(("collision", "magic"), [("bgk", 3 / 16), ("trt", 1 / 4), ("trt", 1 / 12)])
def test_array_cell_runs_other_collision_schemes(collision, magic):
    """BGK, and TRT with a Λ other than 3/16, on the unit cell (ε = 0.2, dx = 4 µm, τ = 1.5).

    (1) The cell equals its 1/ε-row block node by node: tolerance 1e-9 of the
    peak, as for the default scheme. (2) Every x-section clear of the pillar
    carries the same flux (mass conservation of the bounce-back walls, up to
    the stop at a change of 1e-7 per 100 steps): 1e-5 of the mean, measured
    3e-6. (3) The solver's ω− is the registry's for the scheme and Λ.
    (4) TRT: the steady state depends on τ only through Λ (Ginzburg's
    parametrisation; the force scales with ν), so τ = 0.8 gives the field of
    τ = 1.5: 2e-5 of the peak, what the two stops leave (measured 3e-6; BGK
    fields move by 10 % between those τ). BGK is TRT with Λ = (τ − ½)²: the
    same operator, so the same field to float64 rounding, 1e-12 of the peak.
    """
    s = _block_settings(0.2, collision=collision, magic=magic, tau=1.5)
    assert _cell_vs_block(s, 0.2) < 1e-9
    sol = cell_solution(s)
    flux = sol.u[0].sum(axis=(0, 1))
    x0, _, x1, _ = s.array.to_array().shape.bounds
    xs = (np.arange(flux.size) + 0.5) * 4.0
    clear = (xs < x0 - 4.0) | (xs > x1 + 4.0)
    assert np.ptp(flux[clear]) < 1e-5 * flux.mean()
    assert sol.report.omega_minus == get_collision(collision).rates(1.5, magic)[1]
    peak = np.abs(sol.u).max()
    if collision == "trt":
        other = cell_solution(s.model_copy(update={"tau": 0.8})).u
        assert np.abs(other - sol.u).max() < 2e-5 * peak
    else:
        trt = cell_solution(s.model_copy(update={"collision": "trt", "magic": 1.0})).u
        assert np.abs(trt - sol.u).max() < 1e-12 * peak


@pytest.mark.slow
def test_mean_flow_along_x_and_flux_through_every_section():
    """The lateral force makes the mean lateral velocity vanish; every x-section carries
    the same flux. Sections clear of the pillar: 1e-4 (what is left of the
    transient at the solver's stop, 1e-6 change per 100 steps; measured 1e-5).
    Sections through it: 1 % (the node sum
    is a first-order quadrature next to a sub-grid wall; measured 0.5 %)."""
    s = _settings(0.1, "triangle")
    a = s.array.to_array()
    free_settings = _settings(0.1, "triangle", array={"mean_flow": "force"})
    free = field_of(free_settings, solve_cell(free_settings))
    sol = solve_cell(s)
    along = field_of(s, sol)
    assert abs(free.meta["mean_flow_angle_deg"]) > 0.1  # the tilted cell turns the flow
    assert abs(along.meta["mean_flow_angle_deg"]) < 1e-9
    flux = sol.u[0].sum(axis=(0, 1))
    x0, _, x1, _ = a.shape.bounds
    xs = (np.arange(flux.size) + 0.5) * 4.0
    clear = (xs < x0 - 4.0) | (xs > x1 + 4.0)
    assert np.ptp(flux[clear]) < 1e-4 * flux.mean()
    assert np.ptp(flux) < 1e-2 * flux.mean()


@pytest.mark.slow
def test_first_streamline_width_against_dld_estimates():
    """β from the simulated gap profile (dx = 2 µm) vs the standard parabolic estimate
    (β/G)²(3 − 2β/G) = ε and the depth-averaged profile of a G × H duct.

    Circle: within 15 % of the parabola and 10 % of the duct (the gap is a
    curved, converging channel, not a straight one); measured 0.88 and 0.92.
    Triangle: the flow is skewed away from the apex, so β is below the
    parabolic estimate (known for triangular posts; measured 0.61 of it).
    """
    eps = 0.1
    parab = brentq(lambda b: b * b * (3 - 2 * b) - eps, 0.0, 1.0)
    yy = np.linspace(0.0, 40.0, 801)[:, None]
    zz = np.linspace(0.0, 40.0, 801)[None, :]
    ud = duct_velocity(yy, zz, 40.0, 40.0, 1.0).mean(axis=1)
    qd = np.concatenate([[0.0], np.cumsum(0.5 * (ud[1:] + ud[:-1]) * np.diff(yy[:, 0]))])
    duct = float(np.interp(eps * qd[-1], qd, yy[:, 0]))
    c = _settings(eps, "circle", dx=2.0)
    beta, gap = first_streamline_width(c.array.to_array(), solve_cell(c).u, 2.0)
    assert beta == pytest.approx(parab * gap, rel=0.15)
    assert beta == pytest.approx(duct, rel=0.10)
    t = _settings(eps, "triangle", dx=2.0)
    beta_t, gap_t = first_streamline_width(t.array.to_array(), solve_cell(t).u, 2.0)
    assert beta_t < parab * gap_t


@pytest.mark.slow
def test_hele_shaw_permeability_of_a_square_cylinder_array():
    """Shallow square array of cylinders (D = 80, λ = 320, H = 16 µm, dx = 2 µm).

    Far from the pillars the depth-averaged flow is Darcy flow with k = H²/12,
    and the pillars are impermeable inclusions: the superficial velocity over
    that of the empty cell is Rayleigh's conductivity of a square array,
    1 − 2φ / (1 + φ − 0.3058 φ⁴). The Brinkman layer of thickness √k = H/√12
    round each pillar acts as extra excluded area, so the LBM value must lie
    between Rayleigh's at radius R + H/√12 and at R.
    """
    array = {"pillar_shape": "circle", "pillar_size": 80.0, "period_x": 320.0,
             "period_y": 320.0, "shift": 0.0, "depth": 16.0}  # fmt: skip
    s = FlowSettings.model_validate(
        {"dx": 2.0, "tolerance": 1e-7, "precision": "float64", "array": array}
    )
    sol = solve_cell(s)
    ratio = sol.u[0].mean() / (2.0 / 3.0 * U_LATTICE)

    def rayleigh(r):
        phi = math.pi * r * r / 320.0**2
        return 1 - 2 * phi / (1 + phi - 0.305827 * phi**4)

    assert rayleigh(40.0 + 16.0 / math.sqrt(12.0)) < ratio < rayleigh(40.0)


def test_shift_that_is_not_whole_cells_is_refused_by_the_settings():
    with pytest.raises(ValueError, match="row shift"):
        FlowSettings.model_validate({"dx": 4.0, "array": {"period_y": 100.0, "shift": 0.1}})
