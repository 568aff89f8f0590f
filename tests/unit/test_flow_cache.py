"""Flow-field cache: content key, hit/miss, corruption detection, atomic writes."""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.config.flow import FlowSettings, GeometrySettings
from fibersweep.flow import cache
from fibersweep.flow.cache import cache_key, get_flow_field

TINY = FlowSettings(
    geometry=GeometrySettings(width=40.0, depth=32.0, length=48.0, pillar_height=12.0),
    dx=4.0,
    tolerance=1e-5,
)


def _entries(root):
    return sorted(p.name for p in root.iterdir())


def test_miss_then_hit_memory_mapped_read_only(tmp_path):
    f1, i1 = get_flow_field(TINY, tmp_path)
    f2, i2 = get_flow_field(TINY, tmp_path)
    assert (i1.hit, i2.hit) == (False, True)
    assert i1.key == i2.key == cache_key(TINY) and i1.path == i2.path
    assert isinstance(f2.ux, np.memmap) and not f2.ux.flags.writeable
    np.testing.assert_array_equal(f1.ux, f2.ux)
    np.testing.assert_array_equal(f1.uy, f2.uy)
    np.testing.assert_array_equal(f1.solid, f2.solid)
    assert f2.meta["cache_key"] == i1.key
    assert i2.steps == i1.steps > 0 and i2.grid == (12, 10, 4, 8)
    assert i2.u_center_reached == pytest.approx(TINY.fluid.u_center)
    # only the entry itself remains: no temporary directories
    assert _entries(tmp_path) == [f"flow-{i1.key}"]
    # force recomputes and replaces
    _, i3 = get_flow_field(TINY, tmp_path, force=True)
    assert not i3.hit and _entries(tmp_path) == [f"flow-{i1.key}"]


@pytest.mark.parametrize(
    "update",
    [
        {"dx": 2.0},
        {"collision": "bgk"},
        {"tau": 0.9},
        {"magic": 0.25},
        {"tolerance": 1e-6},
        {"symmetry": False},
        {"pillar_boundary": "staircase"},  # the default is interpolated
        {"geometry": TINY.geometry.model_copy(update={"pillar_height": 10.0})},
        {"fluid": TINY.fluid.model_copy(update={"u_center": 500.0})},
    ],
)
def test_key_changes_with_everything_that_changes_the_field(update):
    assert cache_key(TINY) == cache_key(FlowSettings.model_validate(TINY.model_dump()))
    assert cache_key(TINY.model_copy(update=update)) != cache_key(TINY)


@pytest.mark.parametrize("damage", ["truncate", "flip", "manifest", "missing"])
def test_corrupt_entry_is_detected_and_recomputed(tmp_path, damage):
    f1, i1 = get_flow_field(TINY, tmp_path, mmap=False)
    ux_file = i1.path / "ux.npy"
    if damage == "truncate":
        data = ux_file.read_bytes()
        ux_file.write_bytes(data[: len(data) // 2])
    elif damage == "flip":  # same size, one changed byte: only a checksum sees it
        data = bytearray(ux_file.read_bytes())
        data[-3] ^= 0xFF
        ux_file.write_bytes(bytes(data))
    elif damage == "manifest":
        (i1.path / "manifest.json").write_text("{not json")
    else:
        (i1.path / "uy.npy").unlink()
    with pytest.raises(cache.CorruptCacheError):
        cache.load_entry(i1.path, TINY)
    f2, i2 = get_flow_field(TINY, tmp_path)
    assert not i2.hit
    np.testing.assert_array_equal(np.asarray(f2.ux), f1.ux)
    assert _entries(tmp_path) == [f"flow-{i1.key}"]
    assert get_flow_field(TINY, tmp_path)[1].hit


def test_crash_while_writing_leaves_no_entry(tmp_path, monkeypatch):
    # Fault injection: the writer dies after the first array. Nothing may be
    # visible under the entry name, and no temporary directory may remain.
    real = np.save
    calls = {"n": 0}

    def dying_save(path, arr):
        calls["n"] += 1
        if calls["n"] == 2:
            raise OSError("disk full")
        real(path, arr)

    monkeypatch.setattr(cache.np, "save", dying_save)
    with pytest.raises(OSError, match="disk full"):
        get_flow_field(TINY, tmp_path)
    assert _entries(tmp_path) == []
    monkeypatch.undo()
    _, info = get_flow_field(TINY, tmp_path)
    assert not info.hit and _entries(tmp_path) == [f"flow-{info.key}"]


def test_entry_installed_concurrently_is_kept_or_replaced_atomically(tmp_path, monkeypatch):
    # Another process installs the same key while this one is solving: the
    # result must be one complete, valid entry either way.
    real_solve = cache.solve_flow

    def solve_and_race(settings):
        field = real_solve(settings)
        monkeypatch.setattr(cache, "solve_flow", real_solve)
        get_flow_field(settings, tmp_path)  # the "other process"
        return field

    monkeypatch.setattr(cache, "solve_flow", solve_and_race)
    field, info = get_flow_field(TINY, tmp_path)
    assert _entries(tmp_path) == [f"flow-{info.key}"]
    cache.load_entry(info.path, TINY)  # verifies every checksum
    np.testing.assert_array_equal(
        np.asarray(field.ux), np.asarray(get_flow_field(TINY, tmp_path)[0].ux)
    )


def test_keep_3d_stores_the_full_depth_field(tmp_path):
    settings = TINY.model_copy(update={"keep_3d": True})
    f1, info = get_flow_field(settings, tmp_path)
    f2, _ = get_flow_field(settings, tmp_path)
    assert isinstance(f2.u3d, np.memmap) and f2.u3d.shape == (3, 8, 10, 12)
    u = np.asarray(f2.u3d)
    # mirror symmetric about the midplane: ux, uy even, uz odd
    np.testing.assert_array_equal(u[:2], u[:2, ::-1])
    np.testing.assert_array_equal(u[2], -u[2, ::-1])
    # its IB average at z = H/2 is the stored midplane field at every fluid node (the
    # midplane field of a sub-grid pillar holds ghost values at solid nodes next to the
    # wall, for interpolation; the 3D field keeps the solver's zeros there)
    w = 0.25 * (1 + np.cos(np.pi * np.array([1.5, 0.5, 0.5, 1.5]) / 2))
    mid = np.tensordot(w, u[0, 2:6], axes=1).T
    fluid = ~np.asarray(f2.solid, dtype=bool)
    assert fluid.sum() > 0.9 * fluid.size
    np.testing.assert_allclose(mid[fluid], np.asarray(f2.ux)[fluid], rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(mid[~fluid], 0.0)
