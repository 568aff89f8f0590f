"""The fine patch's pieces: settings, cache keys, placement, boundary interpolation, composing.

The patch's accuracy against the whole fine grid is a slow validation test
(tests/validation/test_flow_patch_fine.py).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from fibersweep.config.flow import FlowSettings
from fibersweep.flow.cache import cache_key
from fibersweep.flow.field import FlowField
from fibersweep.flow.lattice import Grid, make_grid
from fibersweep.flow.lbm import LatticeSolution, SolveReport
from fibersweep.flow.patch import boundary_field, compose, patch_box, patch_geometry

GEO = {"width": 400.0, "length": 800.0}


def _patched(dx=4.0, pdx=2.0, margin=40.0, **kw) -> FlowSettings:
    return FlowSettings.model_validate(
        {"geometry": GEO, "dx": dx, "patch": {"dx": pdx, "margin": margin}, **kw}
    )


def test_patch_settings_refuse_bad_spacings():
    """patch.dx must divide dx 2+ times and give an even depth count; no keep_3d."""
    with pytest.raises(ValueError, match="patch.dx"):
        _patched(pdx=3.0)
    with pytest.raises(ValueError, match="patch.dx"):
        _patched(pdx=4.0)
    with pytest.raises(ValueError, match="keep_3d"):
        _patched(keep_3d=True)
    assert _patched().field_dx == 2.0 and FlowSettings().field_dx == FlowSettings().dx


def test_cache_key_without_patch_unchanged(flow_cache_dir):
    """No patch: the key is that of the settings dump without the new key (old entries hit)."""
    s = FlowSettings.model_validate({"geometry": GEO, "dx": 4.0})
    dump = s.model_dump(mode="json")
    assert dump.pop("patch") is None
    old = FlowSettings.model_validate(dump)  # what the settings were before the field existed
    assert cache_key(s) == cache_key(old)
    assert cache_key(_patched()) != cache_key(s)
    assert cache_key(_patched(margin=80.0)) != cache_key(_patched())
    # every stored test-cache entry still has the key it was stored under
    for entry in flow_cache_dir.glob("flow-*/meta.json"):
        meta = json.loads(entry.read_text())
        assert f"flow-{cache_key(FlowSettings.model_validate(meta['settings']))}" == (
            entry.parent.name
        )


@pytest.mark.parametrize("margin", [20.0, 41.0, 300.0])
def test_patch_nodes_sit_on_the_fine_grid(margin):
    """The patch's pillar nodes are the whole fine grid's nodes in its box (same placement)."""
    s = _patched(margin=margin)
    box = patch_box(s)
    assert box.x0 % s.dx == 0 and box.y0 % s.dx == 0
    geom = s.geometry.to_geometry()
    full = make_grid(geom, 2.0, True, closed=True)
    patch = make_grid(patch_geometry(geom, box), 2.0, True, closed=True)
    sub = full.solid[box.i0 : box.i0 + box.nx, box.j0 : box.j0 + box.ny]
    np.testing.assert_array_equal(patch.solid, sub)
    assert patch.solid.sum() == full.solid.sum()  # the whole pillar is inside
    x0, y0, x1, y1 = geom.shape.bounds
    assert box.x0 <= x0 - margin and box.x0 + box.nx * box.dx >= x1 + margin
    assert box.y0 == max(0.0, box.y0) and box.y0 + box.ny * box.dx <= GEO["width"]


def test_patch_beyond_the_period_refused():
    with pytest.raises(ValueError, match="margin"):
        patch_box(_patched(margin=400.0))


def test_boundary_field_exact_for_hele_shaw_with_linear_amplitude():
    """A channel field U(x, y) p(z) with U linear and p the depth parabola is reproduced.

    Bilinear interpolation is exact for linear U and the least-squares parabola fit
    for p, so the fine values agree to rounding (1e-12 relative).
    """
    dc, df, depth = 4.0, 2.0, 40.0
    nx, ny, nz = 40, 30, 5
    grid = Grid(nx, ny, nz, 10, True, dc, np.zeros((nx, ny), dtype=bool))
    x = (np.arange(nx) + 0.5) * dc
    y = (np.arange(ny) + 0.5) * dc
    z = (np.arange(nz) + 0.5) * dc
    amp_x = lambda X, Y: 1.0 + 0.01 * X - 0.02 * Y  # noqa: E731
    amp_y = lambda X, Y: 0.5 - 0.003 * X + 0.004 * Y  # noqa: E731
    Z, Y, X = np.meshgrid(z, y, x, indexing="ij")
    p = Z * (depth - Z)
    u = np.stack([amp_x(X, Y) * p, amp_y(X, Y) * p, np.zeros_like(p)])
    rho = np.broadcast_to(1e-3 * (X - 2 * Y), u.shape[1:]).copy()
    report = SolveReport(1, True, 0.0, 0.0, 0.0, 1.0, 1.0, 1e-6, (nx, ny, nz, 10))
    sol = LatticeSolution(u=u, rho=rho, grid=grid, report=report)
    from fibersweep.flow.patch import PatchBox

    box = PatchBox(x0=20.0, y0=16.0, nx=30, ny=20, dx=df)
    uf, rf = boundary_field(sol, box, 10, density_scale=0.5, ring=1)
    xf = box.x0 + (np.arange(-1, box.nx + 1) + 0.5) * df
    yf = box.y0 + (np.arange(-1, box.ny + 1) + 0.5) * df
    zf = (np.arange(10) + 0.5) * df
    Zf, Yf, Xf = np.meshgrid(zf, yf, xf, indexing="ij")
    pf = Zf * (depth - Zf)
    np.testing.assert_allclose(uf[0], amp_x(Xf, Yf) * pf, rtol=1e-12)
    np.testing.assert_allclose(uf[1], amp_y(Xf, Yf) * pf, rtol=1e-12)
    assert not uf[2].any()
    np.testing.assert_allclose(rf, 0.5e-3 * (Xf - 2 * Yf), rtol=1e-12, atol=1e-15)


def test_compose_patch_inside_channel_outside():
    """Inside the box the patch's values; outside (and on the frame ring) the channel's."""
    s = _patched()
    geom = s.geometry.to_geometry()
    box = patch_box(s)
    lin = lambda X, Y: (3.0 + 0.01 * X + 0.02 * Y, -0.5 + 0.001 * X)  # noqa: E731
    coarse = FlowField.from_function(lin, geom, 4.0)
    pux = np.full((box.nx, box.ny), 7.0)
    psolid = np.zeros((box.nx, box.ny), dtype=bool)
    psolid[3, 4] = True
    ux, uy, solid = compose(coarse, pux, -pux, psolid, box)
    fine = FlowField.from_function(lin, geom, 2.0)
    inside = np.zeros(ux.shape, dtype=bool)  # the patch less its frame ring
    inside[box.i0 + 1 : box.i0 + box.nx - 1, box.j0 + 1 : box.j0 + box.ny - 1] = True
    assert np.all(ux[inside] == 7.0) and np.all(uy[inside] == -7.0)
    assert solid.sum() == 1 and solid[box.i0 + 3, box.j0 + 4]
    # exact away from the walls (bilinear of a linear field; the wall ghosts are odd)
    away = ~inside
    away[:, :2] = away[:, -2:] = False
    away[:2] = away[-2:] = False  # periodic wrap of a non-periodic test field
    np.testing.assert_allclose(ux[away], fine.ux[away], rtol=1e-12)
    np.testing.assert_allclose(uy[away], fine.uy[away], rtol=1e-12, atol=1e-12)


def test_patch_levels_for_the_error_estimate(flow_cache_dir, small_field, tmp_path):
    """The patch's coarser level is the channel alone; its finer one the patch at half dx."""
    from fibersweep.flow.cache import cache_key
    from fibersweep.flow.uncertainty import other_level

    s = _patched(margin=160.0)
    level = other_level(s, flow_cache_dir)  # the small channel at dx = 4 µm is cached
    assert level is not None
    other, field = level
    assert other.patch is None and other.dx == 4.0 and field.dx == 4.0
    finer = (tmp_path / f"flow-{cache_key(_patched(pdx=1.0, margin=160.0))}").name
    assert finer != f"flow-{cache_key(s)}"
    assert other_level(s, tmp_path) is None  # nothing cached there
