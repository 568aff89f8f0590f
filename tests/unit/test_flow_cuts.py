"""Exact link cuts of the pillar and the interpolated bounce-back link tables."""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.flow.cuts import pillar_cuts, polygon_cuts
from fibersweep.flow.ibb import aa_interpolated, family_coefficients, ibb_coefficients
from fibersweep.flow.lattice import OPP, Q, aa_tables, make_grid
from fibersweep.units import Geometry

DX = 4.0


def _geometry(y_base: float) -> Geometry:
    return Geometry(width=200.0, depth=16.0, length=240.0, pillar_y_base=y_base)


def _inside_closed(g: Geometry, x, y) -> np.ndarray:
    """Points inside or on the triangle (µm)."""
    v = g.vertices
    ok = np.ones(np.shape(x), dtype=bool)
    for k in range(3):
        (ax, ay), (bx, by) = v[k], v[(k + 1) % 3]
        ok &= (bx - ax) * (y - ay) - (by - ay) * (x - ax) > -1e-9
    return ok


@pytest.mark.parametrize("y_base", [60.0, 61.0, 62.0, 63.0, 62.3])
def test_cut_fractions_match_a_brute_force_search(y_base):
    # For every link from a fluid node that enters the pillar, the first point of
    # the segment inside the closed triangle (found by sampling 2 001 points) lies
    # at the tabulated q within 1e-3; links not in the table never enter it
    # (tolerance: the sampling step 5e-4, doubled). A link that only touches the
    # outline is a cut if it ends in a (closed) solid node, else not.
    g = _geometry(y_base)
    grid = make_grid(g, DX, symmetry=True, closed=True)
    cuts = polygon_cuts(grid, g.vertices)
    t = np.linspace(0.0, 1.0, 2_001)
    index = cuts.lookup(grid.nx, grid.ny)
    fi, fj = np.nonzero(~grid.solid)
    v = g.vertices
    near = (np.abs((fi + 0.5) * DX - g.base_center[0]) < 50 + 2 * DX) & (
        ((fj + 0.5) * DX > v[0, 1] - 2 * DX) & ((fj + 0.5) * DX < v[2, 1] + 2 * DX)
    )
    checked = 0
    for i, j in zip(fi[near], fj[near], strict=True):
        x0, y0 = (i + 0.5) * DX, (j + 0.5) * DX
        for ex in (-1, 0, 1):
            for ey in (-1, 0, 1):
                if ex == ey == 0:
                    continue
                inside = _inside_closed(g, x0 + t * ex * DX, y0 + t * ey * DX)
                m = index[i, j]
                q = cuts.q[m, ex + 1, ey + 1] if m >= 0 else np.nan
                if not inside.any():
                    assert np.isnan(q), (i, j, ex, ey, q)
                    continue
                end_solid = grid.solid[i + ex, j + ey]
                if inside.sum() == 1 and not end_solid:  # touches a vertex only: no cut
                    assert np.isnan(q), (i, j, ex, ey, q)
                    continue
                assert abs(q - t[np.argmax(inside)]) < 1e-3, (i, j, ex, ey, q)
                assert 0.0 < q <= 1.0
                checked += 1
    assert checked > 40
    assert cuts.links == checked


def test_corner_cutting_links_are_found():
    # Near the 60° vertices some links pass through the pillar between two fluid
    # nodes; at the SPEC placement (dx = 4 µm) there are 12 such in-plane links.
    g = Geometry()
    grid = make_grid(g, DX, symmetry=True, closed=True)
    cuts = pillar_cuts(grid, g.vertices, "interpolated")
    n = 0
    for ex in (-1, 0, 1):
        for ey in (-1, 0, 1):
            if ex == ey == 0:
                continue
            cut = np.isfinite(cuts.q[:, ex + 1, ey + 1])
            n += int((cut & ~grid.solid[cuts.i + ex, cuts.j + ey]).sum())
    assert n == 12
    assert pillar_cuts(grid, g.vertices, "staircase") is None
    with pytest.raises(ValueError, match="unknown pillar boundary"):
        pillar_cuts(grid, g.vertices, "spline")


def test_closed_grid_puts_nodes_on_the_outline_in_the_solid():
    # Base line on a row of nodes (y = 62 = (15 + 1/2) * 4): open grid leaves them
    # fluid (staircase), closed grid makes them solid so every fluid link has q > 0.
    g = _geometry(62.0)
    open_, closed = (make_grid(g, DX, True, closed=c) for c in (False, True))
    assert (closed.solid & ~open_.solid).sum() > 0
    assert not (open_.solid & ~closed.solid).any()
    assert np.nanmin(polygon_cuts(closed, g.vertices).q) > 0.0


def test_coefficients_conserve_rest_state_and_reduce_to_half_way_bounce_back():
    q = np.linspace(0.0, 1.0, 41)
    for scheme in ("trt", "bfl"):
        c = ibb_coefficients(q, 0.3, 3.0 / 16.0, scheme=scheme)
        np.testing.assert_allclose(c.sum(axis=1), 1.0, atol=1e-12)  # rest state kept
        assert np.abs(c).max() <= 2.0 + 1e-12  # bounded weights
        np.testing.assert_allclose(c[20], [1.0, 0.0, 0.0], atol=1e-12)  # q = 1/2
    # the family reproduces BFL (q < 1/2: ρ = (1 − q)/q) and CLI (ρ = 1/(2q))
    qs = np.array([0.1, 0.3])
    np.testing.assert_allclose(
        family_coefficients(qs, (1 - qs) / qs), ibb_coefficients(qs, 0.3, 0.1875, scheme="bfl")
    )
    np.testing.assert_allclose(
        family_coefficients(qs, 1 / (2 * qs)),
        np.column_stack([np.ones(2), -(1 - 2 * qs) / (1 + 2 * qs), (1 - 2 * qs) / (1 + 2 * qs)]),
    )
    # no upstream fluid node: half-way bounce-back
    c = ibb_coefficients(np.array([0.2]), 0.3, 0.1875, np.array([False]), "trt")
    np.testing.assert_allclose(c, [[1.0, 0.0, 0.0]])


@pytest.mark.parametrize("symmetry", [True, False])
def test_aa_tables_cover_every_cut_link_once(symmetry):
    # Every (fluid node, gathered population) whose odd-step source lies across the
    # wall gets exactly one "before" row writing that source and one "after" row
    # writing the node's own slot; no two rows write the same slot.
    g = Geometry(width=200.0, depth=16.0, length=240.0)
    grid = make_grid(g, DX, symmetry, closed=True)
    cuts = polygon_cuts(grid, g.vertices)
    gather, scatter = aa_tables(grid)
    before, after = aa_interpolated(grid, cuts, gather, scatter, 1.25, 1.1)
    assert before.dst.size == after.dst.size == _expected_links(grid, cuts)
    assert np.unique(before.dst).size == before.dst.size
    assert np.unique(after.dst).size == after.dst.size
    plane = (grid.nz + 2) * (grid.ny + 2) * (grid.nx + 2)
    # "after" writes slot opp(p) = q of the fluid node; "before" its solid-side source
    assert set(np.unique(after.dst // plane)) <= set(range(1, Q))
    np.testing.assert_array_equal(before.dst, after.src[:, 0])
    assert np.all(OPP[after.dst // plane] == after.src[:, 2] // plane)


def _expected_links(grid, cuts) -> int:
    """3D links p from fluid nodes whose in-plane part is cut and whose layer k + e_z exists.

    Above the symmetric top the link reaches the mirror image, which is cut too;
    below the bottom (and above a no-slip top) it ends on the channel wall.
    """
    from fibersweep.flow.lattice import E

    n = 0
    for p in range(1, Q):
        ex, ey, ez = E[p]
        if ex == ey == 0:
            continue
        per_layer = int(np.isfinite(cuts.q[:, ex + 1, ey + 1]).sum())
        layers = sum(
            1 for k in range(grid.nz) if 0 <= k + ez < grid.nz or (grid.symmetry and k + ez >= 0)
        )
        n += per_layer * layers
    return n
