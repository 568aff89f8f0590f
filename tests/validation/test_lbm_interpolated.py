"""Interpolated bounce-back: walls between lattice nodes (issue 10, part 1).

A rectangular duct whose side walls y = y_lo, y_hi are plane walls placed at
an arbitrary fraction q of a link from the last fluid node (q = 1/2 is the
half-way wall), handled by the same link tables and kernel as the pillar
(:mod:`fibersweep.flow.cuts`, :mod:`fibersweep.flow.ibb`); the top and bottom
walls stay half-way. Compared with the series solution of the duct of width
y_hi − y_lo. Started from rest: the steady state is the solver's own.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.config.flow import FlowSettings, GeometrySettings
from fibersweep.flow.analytic import duct_velocity
from fibersweep.flow.cuts import slab_cuts
from fibersweep.flow.lattice import Grid
from fibersweep.flow.solver import solve_lattice

PAD = 2  # solid rows on each side
TAU = 0.8  # the solver's own choice for the SPEC channel at dx = 4 µm (Λ+ = 0.3)


def walled_duct(nodes: int, q: float, scheme: str = "trt", kernel: str = "aa"):
    """Duct of ``nodes`` fluid rows, walls q beyond the outer rows; depth ``nodes`` (half solved).

    Returns (relative L2 error of ux against the series, solve report).
    """
    nx, ny = 2, PAD + nodes + PAD
    y_lo = PAD + 0.5 - q
    y_hi = PAD + nodes - 0.5 + q
    y = np.arange(ny) + 0.5
    fluid = (y > y_lo) & (y < y_hi)
    grid = Grid(nx, ny, nodes // 2, nodes, True, 1.0, np.broadcast_to(~fluid, (nx, ny)).copy())
    settings = FlowSettings(
        geometry=GeometrySettings(width=ny, depth=nodes, length=nx, pillar_height=0.5),
        dx=1.0,
        tau=TAU,
        tolerance=1e-7,
        max_steps=60_000,
    )
    sol = solve_lattice(
        settings,
        initial=np.zeros((3, grid.nz, ny, nx)),
        grid=grid,
        cuts=slab_cuts(grid, y_lo, y_hi, scheme),
        kernel=kernel,
    )
    assert sol.report.converged, sol.report
    assert sol.report.boundary == "interpolated"
    nu = (sol.report.tau - 0.5) / 3.0
    z = np.arange(grid.nz) + 0.5
    exact = duct_velocity(
        y[fluid][None, :] - y_lo, z[:, None], y_hi - y_lo, nodes, sol.report.force / nu
    )
    ux = sol.u[0][:, fluid, 0]
    assert np.ptp(sol.u[0], axis=-1).max() < 1e-6 * np.abs(ux).max()  # uniform in x
    return float(np.linalg.norm(ux - exact) / np.linalg.norm(exact)), sol.report


QS = [0.1, 0.25, 0.4, 0.6, 0.75, 0.9]


@pytest.fixture(scope="module")
def errors_16():
    """Errors at 16 fluid rows and 16 depth nodes for both schemes, and the half-way wall."""
    out = {s: {q: walled_duct(16, q, s)[0] for q in QS} for s in ("trt", "bfl")}
    out["half"] = walled_duct(16, 0.5)[0]
    return out


def test_walls_at_any_fraction_are_accurate_and_q_independent(errors_16):
    # 16 nodes across: the half-way wall (q = 1/2, exact for plane Poiseuille
    # with TRT Λ = 3/16) leaves 0.09 % (the duct's own O(Δx²) error, measured).
    # The default scheme is exact for plane Poiseuille at every q (CLI plus the
    # curvature correction below 1/2, the exact linear member above), so what
    # remains is the same O(Δx²) error of the non-parabolic duct profile with a
    # q-dependent constant: every q must stay within 3x the half-way error
    # (0.26 %; the target is 1 % at 20 nodes) and the spread over q
    # below 2x it. Measured: 0.059 % (q = 0.4) .. 0.145 % (q = 0.9).
    err = errors_16["trt"]
    half = errors_16["half"]
    assert half < 2e-3, half
    for q in QS:
        assert err[q] < 3.0 * half, (q, err[q], half)
    assert max(err.values()) - min(err.values()) < 2.0 * half, err


def test_default_scheme_beats_plain_bfl_at_every_fraction(errors_16):
    # Steady-state analysis (fibersweep.flow.ibb): BFL's Poiseuille wall error
    # is (1/2 − q)((1/2 + q)/2 + Λ+) ∂²e⁻ for q < 1/2 and (q − 1/2)((q + 1/2)/2 − Λ+)
    # ∂²e⁻ above, while the default removes it. So the default error is never
    # larger. Measured: 2x (q = 0.6) .. 14x (q = 0.1) smaller.
    for q in QS:
        assert errors_16["trt"][q] < errors_16["bfl"][q], (q, errors_16)


@pytest.mark.parametrize("q", [0.25, 0.75])
def test_second_order_with_walls_between_nodes(q):
    # Halving Δx (8 -> 16 -> 32 nodes at the same q) must divide the error by
    # about 4; accept an observed order above 1.8 on both refinements.
    # Measured: q = 0.25 (corrected CLI branch) 2.65, 2.16; q = 0.75 (exact
    # linear branch) 2.31, 2.21; errors 4.1e-3, 6.6e-4, 1.5e-4 and 5.7e-3, 1.2e-3, 2.5e-4.
    e = [walled_duct(n, q)[0] for n in (8, 16, 32)]
    orders = [math.log2(e[i] / e[i + 1]) for i in range(2)]
    assert min(orders) > 1.8, (e, orders)


def test_pull_kernel_applies_the_same_walls():
    # The two-array pull kernel uses its own link table for the same cuts: same
    # steady state to the convergence tolerance (1e-5 relative in the error;
    # measured identical to all printed digits, 3.15e-3).
    e_aa, _ = walled_duct(8, 0.3)
    e_pull, _ = walled_duct(8, 0.3, kernel="pull")
    assert abs(e_aa - e_pull) < 1e-5 * max(e_aa, 1e-3) + 1e-6, (e_aa, e_pull)


def test_mass_is_conserved_to_rounding():
    # Linear interpolated bounce-back does not conserve mass exactly: each link
    # returns V instead of the outgoing f*_p, a leak of Σ (V − f*_p) per step.
    # Bound: the total fluid mass may change by at most 1e-8 relative over the
    # whole run (δρ of 1e-8 changes u = j/ρ by 1e-8 relative, far below the
    # solver's 1e-7 stopping tolerance). Measured: below 1e-11 (float rounding)
    # in the ducts and the pillar channel, every q.
    for q in (0.1, 0.4, 0.9):
        _, rep = walled_duct(16, q)
        assert abs(rep.mass_change) < 1e-8, (q, rep.mass_change)
    settings = FlowSettings(
        geometry=GeometrySettings(width=200.0, depth=40.0, length=400.0, pillar_height=75.0),
        dx=4.0,
        tolerance=1e-7,
        pillar_boundary="interpolated",
    )
    sol = solve_lattice(settings)
    assert sol.report.boundary == "interpolated" and sol.report.steps > 1000
    assert abs(sol.report.mass_change) < 1e-8, sol.report.mass_change
