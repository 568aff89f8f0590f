"""Unit-cell flow of a tilted pillar array against an explicit block, fluxes, the first
streamline and the Hele-Shaw permeability of a square array of cylinders."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from fibersweep.errors import InputError
from fibersweep.flow.analytic import duct_velocity
from fibersweep.flow.cell import (
    U_LATTICE,
    _solve,
    _tau,
    _transposed,
    cell_grid,
    field_of,
    first_streamline_width,
    solve_block,
    solve_cell,
)
from fibersweep.geometry.array import PillarArray


def _array(eps: float, shape: str = "circle") -> PillarArray:
    return PillarArray(pillar_shape=shape, pillar_size=40.0, period_x=80.0, period_y=80.0,
                       shift=eps, depth=40.0)  # fmt: skip


@pytest.mark.parametrize("eps", [pytest.param(0.1, marks=pytest.mark.slow), 0.2])
def test_unit_cell_equals_block_of_one_over_eps_rows(eps):
    """Shifted periodic cell vs 1/ε explicit rows with plain periodic ends (dx = 4 µm).

    Both use staircase pillars (the block's pillars straddle the lateral edge)
    and the same τ and start; node by node the arithmetic is the same, so any
    error in the shifted boundary shows at O(1). Tolerance: 1e-9 of the peak speed.
    """
    a = _array(eps)
    rows = round(1 / eps)
    cell = solve_cell(a, 4.0, boundary="staircase", tolerance=1e-7, precision="float64",
                      mean_flow="force")  # fmt: skip
    block = solve_block(a, 4.0, rows, tau=cell.tau)
    nx, s = cell.grid.nx, cell.shift_cells
    peak = np.abs(cell.u).max()
    for r in range(rows):
        part = block.u[:, :, :, r * nx : (r + 1) * nx]
        assert np.abs(part - np.roll(cell.u, r * s, axis=2)).max() < 1e-9 * peak
    # every gap of the block carries the same flux: one gap per row and lateral period
    flux = block.u[0].sum(axis=(0, 1))  # per x column
    centres = [int((a.centre(r, 0)[0]) / 4.0) for r in range(rows)]
    assert np.ptp(flux[centres]) < 1e-9 * flux.mean()


def test_transposed_cell_equals_block_along_y():
    """The y-face shift (used to drive the flow across) vs an explicit block stacked in y."""
    a = _array(0.2)
    shape_t = _transposed(a.shape)
    g = cell_grid([shape_t], 20, 20, 10, 4.0, True, False)
    tau = _tau(g)
    cell = _solve(g, 0, None, tau, 1e-7, 50_000, 100, np.float64, shift_y=4)
    shapes = [shape_t.moved(math.fmod(r * 16.0, 80.0) + c * 80.0, r * 80.0)
              for r in range(5) for c in (-1, 0, 1)]  # fmt: skip
    gb = cell_grid(shapes, 20, 100, 10, 4.0, True, False)
    block = _solve(gb, 0, None, tau, 1e-7, 50_000, 100, np.float64)
    peak = np.abs(cell.u).max()
    for r in range(5):
        part = block.u[:, :, r * 20 : (r + 1) * 20, :]
        assert np.abs(part - np.roll(cell.u, r * 4, axis=3)).max() < 1e-9 * peak


@pytest.mark.slow
def test_mean_flow_along_x_and_flux_through_every_section():
    """The lateral force makes the mean lateral velocity vanish; every x-section carries
    the same flux. Sections clear of the pillar: 1e-4 (what is left of the
    transient at the solver's stop, 1e-6 change per 100 steps; measured 1e-5).
    Sections through it: 1 % (the node sum
    is a first-order quadrature next to a sub-grid wall; measured 0.5 %)."""
    a = _array(0.1, "triangle")
    free = field_of(a, solve_cell(a, 4.0, mean_flow="force"), 600.0, "interpolated")
    sol = solve_cell(a, 4.0)
    along = field_of(a, sol, 600.0, "interpolated")
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
    a = _array(eps, "circle")
    beta, gap = first_streamline_width(a, solve_cell(a, 2.0).u, 2.0)
    assert beta == pytest.approx(parab * gap, rel=0.15)
    assert beta == pytest.approx(duct, rel=0.10)
    t = _array(eps, "triangle")
    beta_t, gap_t = first_streamline_width(t, solve_cell(t, 2.0).u, 2.0)
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
    a = PillarArray(pillar_shape="circle", pillar_size=80.0, period_x=320.0, period_y=320.0,
                    shift=0.0, depth=16.0)  # fmt: skip
    sol = solve_cell(a, 2.0, tolerance=1e-7, precision="float64")
    ratio = sol.u[0].mean() / (2.0 / 3.0 * U_LATTICE)

    def rayleigh(r):
        phi = math.pi * r * r / 320.0**2
        return 1 - 2 * phi / (1 + phi - 0.305827 * phi**4)

    assert rayleigh(40.0 + 16.0 / math.sqrt(12.0)) < ratio < rayleigh(40.0)


def test_shift_that_is_not_whole_cells_is_an_input_error():
    with pytest.raises(InputError, match=r"array\.shift"):
        solve_cell(PillarArray(period_y=100.0, shift=0.1), 4.0)
