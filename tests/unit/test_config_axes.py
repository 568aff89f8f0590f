"""Any setting as a sweep axis: product and zip expansion, validation, errors (issue 11)."""

from __future__ import annotations

import pytest

from fibersweep.config import ConfigError, load_config, parse_config, setting_column
from fibersweep.sweep.starts import PHYSICS


def _write(tmp_path, text):
    p = tmp_path / "c.yaml"
    p.write_text(text)
    return p


def _cfg(**sweep):
    return parse_config({"sweep": {"theta0": [-5.0, 5.0], "y0": 0.8, **sweep}})


def test_product_axes_in_written_order_first_slowest():
    cfg = _cfg(
        **{"fiber.effects.friction": [0, 0.3, 0.6], "fiber.contact.pillar": ["rough", "smooth"]}
    )
    combos = cfg.combinations()
    assert [c.values for c in combos] == [
        {"fiber.effects.friction": f, "fiber.contact.pillar": p}
        for f in (0.0, 0.3, 0.6)
        for p in ("rough", "smooth")
    ]
    # each combination is a whole config with the value applied and no setting axes left
    assert combos[3].config.fiber.effects == {"friction": 0.3}
    assert combos[3].config.fiber.contact.pillar == "smooth"
    assert combos[3].config.sweep.setting_keys == []
    assert cfg.sweep.n_combinations == 6 and cfg.sweep.size == 2


def test_zip_group_sweeps_keys_together_and_ranges_work():
    cfg = _cfg(
        **{
            "flow.dx": {"start": 2.0, "stop": 4.0, "num": 2},
            "zip": {"fiber.bead_radius": [2.0, 1.5, 1.0], "fiber.contact.chi": [1.1, 1.2, 1.3]},
        }
    )
    vals = [c.values for c in cfg.combinations()]
    assert len(vals) == 2 * 3
    assert vals[0] == {"flow.dx": 2.0, "fiber.bead_radius": 2.0, "fiber.contact.chi": 1.1}
    assert vals[5] == {"flow.dx": 4.0, "fiber.bead_radius": 1.0, "fiber.contact.chi": 1.3}
    # several zip groups multiply with each other
    two = _cfg(zip=[{"fiber.bead_radius": [2.0, 1.5]}, {"fiber.model": ["rigid", "bead-spring"]}])
    assert len(two.combinations()) == 4


def test_no_setting_axes_is_one_combination_of_the_config_itself():
    cfg = _cfg()
    (only,) = cfg.combinations()
    assert only.values == {} and only.config is cfg and only.label == ""


def test_config_round_trips_through_its_dump():
    cfg = _cfg(**{"fiber.model": ["rigid", "bead-spring"], "zip": {"flow.dx": [4, 2]}})
    again = parse_config(cfg.model_dump(mode="json"))
    assert [c.values for c in again.combinations()] == [c.values for c in cfg.combinations()]


def test_max_points_counts_every_combination():
    data = {
        "sweep": {"theta0": [0.0, 1.0], "y0": 0.8, "fiber.effects.friction": [0, 0.1, 0.2]},
        "run": {"max_points": 5},
    }
    with pytest.raises(ConfigError, match=r"6 points \(2 starts x 3 setting combinations\)"):
        parse_config(data)
    data["run"]["max_points"] = 6
    assert parse_config(data).sweep.n_combinations == 3


@pytest.mark.parametrize(
    ("line", "expected"),
    [
        (
            "  fiber.effects.friction: [0, -0.3]",
            "sweep.fiber.effects.friction (line 3): value -0.3: effects.friction: must be >= 0",
        ),
        (
            "  fiber.effects.frction: [0, 0.3]",
            "sweep.fiber.effects.frction (line 3): value 0.0: unknown effect 'frction' "
            "(did you mean 'friction'?)",
        ),
        (
            "  fiber.contact.pillar: [rough, smoth]",
            "sweep.fiber.contact.pillar (line 3): value 'smoth': Input should be 'rough' or "
            "'smooth'",
        ),
        (
            "  fiber.contct.chi: [1.2]",
            "sweep.fiber.contct.chi (line 3): unknown setting 'contct' in fiber; "
            "did you mean 'contact'?",
        ),
        ("  lenght: [1]", "sweep.lenght (line 3): unknown key; did you mean 'length'?"),
        ("  run.workers: [1, 2]", "sweep.run.workers (line 3): run.* settings do not change"),
        ("  fiber.classify.trap_time: [1]", "`fibersweep classify`"),
        ("  fiber.model: {a: 1}", "sweep.fiber.model (line 3): expected a value, a list"),
        (
            "  zip:\n    fiber.contact.chi: [1.2, 1.3]\n    flow.dx: [4]",
            "sweep.zip (line 3): zipped keys need value lists of the same length; "
            "got fiber.contact.chi: 2, flow.dx: 1",
        ),
        ("  zip: {}", "sweep.zip (line 3): expected a mapping of setting keys to value lists"),
        (
            "  fiber.bead_radius: [2]\n  zip: {fiber.bead_radius: [1.5]}",
            "sweep.zip.fiber.bead_radius (line 4): fiber.bead_radius is swept twice",
        ),
        # a combination whose starts fail: named at the axis, with the failing field
        (
            "  fiber.x0: [600, 1200]\n  y0: 0.333",
            "sweep.fiber.x0 (line 3): with fiber.x0 = 1200: sweep.y0: the start",
        ),
    ],
)
def test_bad_axes_name_the_key_and_line(tmp_path, line, expected):
    text = "sweep:\n  theta0: 0.0\n" + line + "\n"
    if "y0:" not in line:
        text += "  y0: 0.8\n"
    with pytest.raises(ConfigError) as ei:
        load_config(_write(tmp_path, text), physics=PHYSICS)
    assert expected in str(ei.value), str(ei.value)
    assert len(ei.value.problems) == 1


def test_an_unknown_swept_key_is_reported_with_the_other_sections_problems(tmp_path):
    """The whole config resolves swept keys, field by field: a problem elsewhere
    (flow.dx) does not hide the unknown key, nor the key the other problem."""
    p = _write(tmp_path, "flow:\n  dx: -1\nsweep:\n  fiber.contct.chi: [1.1, 1.2]\n")
    with pytest.raises(ConfigError) as ei:
        load_config(p)
    problems = ei.value.problems
    assert len(problems) == 2, problems
    assert problems[0].startswith("flow.dx (line 2): Input should be greater than 0")
    assert problems[1].startswith("sweep.fiber.contct.chi (line 4): unknown setting 'contct'")


def test_bad_axis_in_an_override_is_named_as_the_override(tmp_path):
    p = _write(tmp_path, "sweep:\n  y0: 0.8\n")
    with pytest.raises(ConfigError, match=r"sweep\.fiber\.contact\.chi \(override .*\): value 0.5"):
        load_config(p, ["sweep.fiber.contact.chi=[1.2, 0.5]"])


def test_each_combination_gets_the_fast_start_check():
    """A start inside the channel for one pillar height is outside it for another: named."""
    ok = {"sweep": {"y0": 2.0, "flow.geometry.pillar_height": [75, 200]}}
    assert len(parse_config(ok, physics=PHYSICS).combinations(PHYSICS)) == 2
    bad = {"sweep": {"y0": 2.0, "flow.geometry.pillar_height": [75, 300]}}
    with pytest.raises(ConfigError) as ei:
        parse_config(bad, physics=PHYSICS)
    msg = str(ei.value)
    assert "sweep.flow.geometry.pillar_height: with flow.geometry.pillar_height = 300: " in msg
    assert "sweep.y0: y0/h = 2.0" in msg and "outside the channel" in msg, msg


def test_columns_are_typed_with_units():
    assert setting_column("flow.geometry.pillar_height")[:2] == ("float", "µm")
    assert setting_column("fiber.contact.pillar")[0] == "string"
    assert setting_column("fiber.record.samples")[0] == "int"
    assert setting_column("fiber.effects.friction")[0] == "float"
    assert setting_column("fiber.young_modulus")[:2] == ("float", "Pa")


def test_shipped_axis_example_is_valid():
    from pathlib import Path

    cfg = load_config(Path(__file__).parents[2] / "configs" / "friction_axis.yaml")
    assert cfg.sweep.setting_keys == ["fiber.effects.friction", "fiber.contact.pillar"]
    assert len(cfg.combinations()) == 6 and cfg.sweep.size == 18
