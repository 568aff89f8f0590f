"""D3Q19 lattice constants, pull table, pillar links, prolongation, midplane weights."""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.config.flow import FlowSettings, GeometrySettings
from fibersweep.flow.lattice import (
    CS2,
    MIRROR_Z,
    OPP,
    E,
    Grid,
    Q,
    W,
    aa_tables,
    boundary_links,
    make_grid,
    pull_sources,
    table_cells,
)
from fibersweep.flow.lbm import solve_lattice
from fibersweep.flow.prolong import prolong
from fibersweep.flow.solver import midplane_weights
from fibersweep.units import Geometry

SMALL = Geometry(width=40.0, depth=32.0, length=48.0, pillar_height=12.0)


def test_d3q19_moments_are_isotropic_to_fourth_order():
    # Σw = 1, Σw e = 0, Σw e_a e_b = c_s² δ_ab, Σw e_a e_b e_c = 0,
    # Σw e_a e_b e_c e_d = c_s⁴ (δ_ab δ_cd + δ_ac δ_bd + δ_ad δ_bc) (exact, to 1e-15).
    e = E.astype(float)
    d = np.eye(3)
    assert Q == 19 and W.sum() == pytest.approx(1.0, abs=1e-15)
    np.testing.assert_allclose(np.einsum("q,qa->a", W, e), 0, atol=1e-15)
    np.testing.assert_allclose(np.einsum("q,qa,qb->ab", W, e, e), CS2 * d, atol=1e-15)
    np.testing.assert_allclose(np.einsum("q,qa,qb,qc->abc", W, e, e, e), 0, atol=1e-15)
    iso = CS2**2 * (
        np.einsum("ab,cd->abcd", d, d)
        + np.einsum("ac,bd->abcd", d, d)
        + np.einsum("ad,bc->abcd", d, d)
    )
    m4 = np.einsum("q,qa,qb,qc,qd->abcd", W, e, e, e, e)
    np.testing.assert_allclose(m4, iso, atol=1e-15)


def test_opposite_and_mirror_indices():
    np.testing.assert_array_equal(E[OPP], -E)
    np.testing.assert_array_equal(E[MIRROR_Z], E * np.array([1, 1, -1]))
    np.testing.assert_array_equal(OPP[OPP], np.arange(Q))
    np.testing.assert_array_equal(MIRROR_Z[MIRROR_Z], np.arange(Q))


@pytest.mark.parametrize("symmetry", [True, False])
def test_pull_table_follows_the_boundary_rules(symmetry):
    grid = make_grid(SMALL, 4.0, symmetry)
    src = pull_sources(grid)
    nz, ny = grid.nz, grid.ny
    for k in range(nz):
        for j in range(ny):
            for q in range(Q):
                ex, ey, ez = E[q]
                qs, zs, ys, xo = src[k * ny + j, q]
                if not (0 <= j - ey < ny) or k - ez < 0 or (k - ez >= nz and not symmetry):
                    assert (qs, zs, ys, xo) == (OPP[q], k + 1, j + 1, 1)  # bounce-back
                elif k - ez >= nz:
                    assert (qs, zs, ys, xo) == (MIRROR_Z[q], k + 1, j - ey + 1, 1 - ex)
                else:
                    assert (qs, zs, ys, xo) == (q, k - ez + 1, j - ey + 1, 1 - ex)


def test_pillar_links_cover_every_fluid_solid_link():
    # Brute force: every (fluid node t, q) whose pull source t − e_q is solid must
    # find, at that solid slot, the bounce-back value g[opp q](t).
    grid = make_grid(SMALL, 2.0, symmetry=True)
    links, cells = boundary_links(grid)
    g = np.random.default_rng(0).random(grid.padded_shape).astype(np.float32)
    flat = g.reshape(Q, -1)
    flat[:, cells] = 0.0
    for q, dst, qs, s in links:
        flat[q, dst] = flat[qs, s]
    src = pull_sources(grid)
    checked = 0
    for k in range(grid.nz):
        for j in range(grid.ny):
            for i in range(grid.nx):
                if grid.solid[i, j]:
                    continue
                for q in range(Q):
                    qs, zs, ys, xo = src[k * grid.ny + j, q]
                    xs = xo + i
                    ii = (xs - 1) % grid.nx
                    jj = ys - 1
                    if 0 <= jj < grid.ny and grid.solid[ii, jj]:
                        want = g[OPP[q], k + 1, j + 1, i + 1]
                        assert g[qs, zs, ys, xs] == want
                        checked += 1
    assert checked > 50
    assert len(np.unique(cells)) == grid.solid.sum() * grid.nz


def test_prolong_keeps_linear_fields_and_boundary_conditions():
    coarse = make_grid(SMALL, 4.0, symmetry=True, pillar=False)
    fine = make_grid(SMALL, 2.0, symmetry=True, pillar=False)
    z = (np.arange(coarse.nz) + 0.5)[:, None, None] * coarse.dx
    y = (np.arange(coarse.ny) + 0.5)[None, :, None] * coarse.dx
    x = (np.arange(coarse.nx) + 0.5)[None, None, :] * coarse.dx
    # ux linear in y inside (exact for trilinear interpolation away from walls)
    u = np.zeros((3, coarse.nz, coarse.ny, coarse.nx))
    u[0] = (y + 0 * z + 0 * x) * 1e-3
    rho = np.broadcast_to(2e-4 * np.cos(2 * np.pi * x / SMALL.length), u[0].shape)
    uf, rf = prolong(u, rho, coarse, fine, density_scale=0.5)
    yf = (np.arange(fine.ny) + 0.5) * fine.dx
    inner = (yf > coarse.dx / 2) & (yf < SMALL.width - coarse.dx / 2)
    # away from the walls a linear field is reproduced exactly (z: all but the
    # bottom fine layer; the top is the free-slip plane, where ux is mirrored)
    np.testing.assert_allclose(
        uf[0][1:, inner, :],
        np.broadcast_to((yf[inner] * 1e-3)[None, :, None], uf[0][1:, inner].shape),
    )
    # no-slip bottom wall: the fine node at dx_f/2 gets half the coarse node at dx_c/2
    np.testing.assert_allclose(uf[0][0, inner, :], 0.5 * uf[0][1, inner, :] * 1.0)
    assert np.all(uf[1:] == 0)
    # δρ: mean-free, scaled by density_scale
    assert abs(rf.mean()) < 1e-15 and 0.9e-4 < np.abs(rf).max() <= 1e-4 + 1e-12


def test_midplane_weights_are_the_ib_kernel_at_half_depth():
    # Half-way nodes at (k + 1/2) Δx and the midplane H/2 between two nodes:
    # weights φ(±1/2) = 0.4268, φ(±3/2) = 0.0732, summing to 1 (SPEC kernel).
    for symmetry in (True, False):
        grid = make_grid(Geometry(), 4.0, symmetry)
        w = dict(midplane_weights(grid))
        phi = lambda r: 0.25 * (1 + np.cos(np.pi * r / 2))  # noqa: E731
        assert w == pytest.approx(
            {3: 2 * phi(1.5), 4: 2 * phi(0.5)}
            if symmetry
            else {3: phi(1.5), 4: phi(0.5), 5: phi(0.5), 6: phi(1.5)}
        )
        assert sum(w.values()) == pytest.approx(1.0, abs=1e-12)
        assert phi(0.5) == pytest.approx(0.4268, abs=1e-4)


def _box(kind: str, symmetry: bool) -> Grid:
    """The channel SMALL, or a box periodic in y whose x faces are shifted by 3 cells."""
    if kind == "channel":
        return make_grid(SMALL, 4.0, symmetry, pillar=False)
    solid = np.zeros((12, 10), dtype=bool)
    return Grid(12, 10, 4 if symmetry else 8, 8, symmetry, 4.0, solid, periodic_y=True, shift=3)


@pytest.mark.parametrize("kind", ["channel", "shifted cell"])
@pytest.mark.parametrize("symmetry", [True, False])
def test_aa_gather_and_scatter_are_permutations_of_all_slots(symmetry, kind):
    # In-place streaming is only race-free and mass-conserving if every (cell, slot)
    # is read exactly once by the gather and written exactly once by the scatter;
    # in a unit cell also across its shifted periodic faces.
    grid = _box(kind, symmetry)
    gather, scatter = aa_tables(grid)
    i = np.arange(grid.nx)
    for table in (gather, scatter):
        seen = []
        for r in range(grid.nz * grid.ny):
            for q in range(Q):
                (slot, z, y, x), _, _ = table_cells(grid, table, np.full(grid.nx, r), q, i)
                seen.append(((slot * (grid.nz + 2) + z) * (grid.ny + 2) + y) * grid.nx + x - 1)
        seen = np.concatenate(seen)
        assert seen.size == Q * grid.cells and np.unique(seen).size == seen.size


def test_the_scatter_of_a_shifted_cell_reaches_the_node_its_gather_reads():
    # Node x gathers population opp(q) from the slot q of x + e_q that it also pushes
    # f*_q into: the AA pattern's race-freedom, across the shifted faces too.
    grid = _box("shifted cell", True)
    gather, scatter = aa_tables(grid)
    i = np.arange(grid.nx)
    for r in range(grid.nz * grid.ny):
        rows = np.full(grid.nx, r)
        for q in range(Q):
            pushed, _, _ = table_cells(grid, scatter, rows, q, i)
            read, _, _ = table_cells(grid, gather, rows, OPP[q], i)
            for a, b in zip(pushed, read, strict=True):
                np.testing.assert_array_equal(a, b)


def test_grid_wrap_moves_rows_across_the_shifted_x_faces():
    grid = _box("shifted cell", True)
    i, j, inside = grid.wrap(np.array([-1, 12, 25, 3]), np.array([0, 0, 9, -1]))
    np.testing.assert_array_equal(i, [11, 0, 1, 3])
    np.testing.assert_array_equal(j, [3, 7, (9 - 6) % 10, 9])  # u(x + nx, y + s) = u(x, y)
    assert inside is True
    channel = _box("channel", True)
    assert list(channel.wrap(np.array([-1, 3]), np.array([0, 10]))[2]) == [True, False]
    with pytest.raises(ValueError, match="periodic in y"):
        Grid(4, 4, 2, 4, True, 1.0, np.zeros((4, 4), bool), shift=1)


@pytest.mark.parametrize("symmetry", [True, False])
def test_aa_and_pull_kernels_reach_the_same_steady_state(symmetry):
    # Same collision, same boundary rules, different memory pattern: the steady
    # fields agree to the convergence tolerance (1e-5 relative; measured 6e-7).
    settings = FlowSettings(
        geometry=GeometrySettings(width=120.0, depth=32.0, length=160.0, pillar_height=40.0),
        dx=4.0,
        symmetry=symmetry,
        tolerance=1e-7,
    )
    aa = solve_lattice(settings, kernel="aa")
    pull = solve_lattice(settings, kernel="pull")
    assert aa.report.converged and pull.report.converged
    assert np.abs(aa.u - pull.u).max() < 1e-5 * np.abs(pull.u).max()
    with pytest.raises(ValueError, match="valid: \\['aa', 'pull'\\]"):
        solve_lattice(settings, kernel="push")
