"""The ``flow.array`` section and ``sweep.random`` in the standard config.

A channel config (no ``flow.array``) dumps, keys and ids as before the section
existed; an array config validates its own units; random starts are seeded,
reproducible, uniform in their ranges and clear of the pillars.
"""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.config import FieldError, parse_config
from fibersweep.config.errors import ConfigError
from fibersweep.config.fiber import FiberSettings
from fibersweep.config.flow import FlowSettings
from fibersweep.flow.cache import cache_key
from fibersweep.sweep.draws import start_points
from fibersweep.sweep.starts import PHYSICS

ARRAY = {"flow": {"dx": 4.0, "array": {}}, "sweep": {"length": [20.0], "y0": 0.9}}


def test_a_channel_config_dumps_and_keys_as_before_arrays():
    """No ``array`` in a channel's flow dump (so its manifest and cache key are as they
    were), no ``array_rows`` in its fiber dump (so its run ids are), ``random`` absent."""
    cfg = parse_config({})
    assert "array" not in cfg.flow.model_dump() and "array" not in cfg.flow.model_dump_json()
    assert "array_rows" not in cfg.fiber.model_dump()
    assert "random" not in cfg.sweep.model_dump()
    # the key of the default field, the same before and after this section existed
    assert cache_key(FlowSettings()) == "b2fcb5c29f2c07316cecd89f"


def test_an_array_key_differs_from_the_channel_and_with_each_setting():
    a = FlowSettings.model_validate({"dx": 4.0, "array": {}})
    b = FlowSettings.model_validate({"dx": 4.0, "array": {"shift": 0.2}})
    assert len({cache_key(FlowSettings(dx=4.0)), cache_key(a), cache_key(b)}) == 3
    # the rows a fiber crosses are a fiber setting: they change run ids, not the field
    assert FiberSettings(array_rows=30).model_dump()["array_rows"] == 30


def test_an_array_takes_the_channels_collision_settings_and_keeps_3d(tmp_path):
    """``collision``, ``magic`` and ``keep_3d`` apply to the unit cell: each enters its key,
    and a kept 3D cell field is stored and read back with the midplane field."""
    from fibersweep.flow.cache import get_flow_field

    base = {"dx": 4.0, "tolerance": 1e-4, "array": {"mean_flow": "force"}}
    a = FlowSettings.model_validate(base)
    others = [FlowSettings.model_validate({**base, **u})
              for u in ({"collision": "bgk"}, {"magic": 0.25}, {"keep_3d": True})]  # fmt: skip
    assert len({cache_key(a), *map(cache_key, others)}) == 4
    field, info = get_flow_field(others[2], tmp_path)
    again, hit = get_flow_field(others[2], tmp_path)
    assert not info.hit and hit.hit and field.u3d.shape == (3, 10, 20, 20)
    np.testing.assert_array_equal(again.u3d, field.u3d)
    np.testing.assert_array_equal(field.u3d[:2], field.u3d[:2, ::-1])  # ux, uy even in z


@pytest.mark.parametrize(
    ("data", "field"),
    [
        ({"flow": {"dx": 4.0, "array": {}, "patch": {"dx": 2.0}}}, "flow.patch"),
        ({"flow": {"dx": 4.0, "array": {"period_x": 42.0}}}, "flow.array.period_x"),
        ({"flow": {"dx": 4.0, "array": {"depth": 20.0}}}, "flow.dx"),  # 5 depth nodes
        ({"flow": {"dx": 4.0, "array": {}}, "sweep": {"y0": 0.5, "length": 80.0}}, "sweep.y0"),
    ],
)
def test_bad_array_configs_name_the_field(data, field):
    with pytest.raises((ConfigError, FieldError, ValueError)) as exc:
        parse_config(data, physics=PHYSICS)
    assert field in str(exc.value)


def test_random_starts_are_seeded_uniform_in_their_ranges_and_clear():
    cfg = parse_config({
        **ARRAY,
        "sweep": {"length": [20.0, 120.0], "theta0": [-10.0, 10.0], "y0": [0.0, 1.0],
                  "random": {"count": 50, "seed": 3}},
    })  # fmt: skip
    t, y, L = start_points(cfg)
    assert t.size == y.size == L.size == 100 == cfg.sweep.size
    assert np.all((t >= -10) & (t <= 10)) and np.all((y >= 0) & (y <= 1))
    for a, b in zip(start_points(cfg), (t, y, L), strict=True):
        assert np.array_equal(a, b)  # reproducible
    # a length added later leaves the others' draws as they were
    more = cfg.model_copy(
        update={"sweep": cfg.sweep.model_copy(update={"length": [20.0, 60.0, 120.0]})}
    )
    t2, y2, L2 = start_points(more)
    assert np.array_equal(t2[L2 == 120.0], t[L == 120.0])
    # a 120 µm fiber spans the cell: some draws touched a pillar and were drawn again
    from fibersweep.fiber.array_run import start_clear
    from fibersweep.fiber.rows import array_pillar

    arr = cfg.flow.array.to_array()
    pil = array_pillar(arr, cfg.fiber, 0.34, 600.0)
    assert all(
        start_clear(arr, pil, 30, 2.0, yi, ti) for ti, yi in zip(t[50:], y[50:], strict=True)
    )
    rng = np.random.default_rng([3, int(np.float64(120.0).view(np.uint64))])
    first = [(rng.uniform(-10, 10), rng.uniform(0, 1)) for _ in range(50)]
    assert not all(start_clear(arr, pil, 30, 2.0, yi, ti) for ti, yi in first)


def test_random_starts_in_the_channel_are_redrawn_off_the_pillar():
    cfg = parse_config({
        "sweep": {"length": [1.0], "theta0": [-8.0, 8.0], "y0": [0.0, 1.0],
                  "random": {"count": 20, "seed": 0}},
    })  # fmt: skip
    t, y, L = start_points(cfg)
    assert t.size == 20 and np.all((y >= 0) & (y <= 1)) and np.all(L == 1.0)


@pytest.mark.parametrize(
    ("sweep", "field"),
    [
        ({"y0": [0.1, 0.2, 0.3], "random": {"count": 2}}, "sweep.y0"),
        ({"theta0": [5.0, -5.0], "random": {"count": 2}}, "sweep.theta0"),
        (
            {"y0": [0.1, 0.5], "random": {"count": 2},
             "refine": {"axes": ["y0"], "tolerance": {"y0": 0.01}, "max_runs": 10}},
            "sweep.refine.axes",
        ),
        (  # a channel: random starts have no critical length to refine
            {"y0": [0.1, 0.5], "random": {"count": 2},
             "refine": {"axes": ["length"], "tolerance": {"length": 0.1}, "max_runs": 10}},
            "sweep.refine",
        ),
    ],
)  # fmt: skip
def test_random_needs_ranges_and_refines_only_an_arrays_length(sweep, field):
    with pytest.raises((ConfigError, FieldError, ValueError)) as exc:
        parse_config({"sweep": sweep})
    assert field in str(exc.value)


def test_config_of_an_array_leaves_out_the_unused_channel():
    import yaml
    from typer.testing import CliRunner

    from fibersweep.cli import app

    r = CliRunner().invoke(app, ["config", "configs/array.yaml"])
    assert r.exit_code == 0, r.output
    shown = yaml.safe_load(r.output)
    assert "geometry" not in shown["flow"] and shown["flow"]["array"]["shift"] == 0.1
    assert "flow.geometry (the single channel) is unused" in r.output
