"""Command-line overrides: dotted KEY=VALUE, validated by the schema with the same messages."""

from __future__ import annotations

import pytest
import yaml
from typer.testing import CliRunner

from fibersweep.cli import app
from fibersweep.config import ConfigError, load_config


@pytest.fixture()
def cfg_file(tmp_path):
    p = tmp_path / "c.yaml"
    p.write_text("fiber:\n  contact:\n    chi: 1.1\nsweep:\n  y0: 0.5\n")
    return p


def test_overrides_replace_and_add_values_of_any_type(cfg_file):
    cfg = load_config(
        cfg_file,
        ["fiber.contact.chi=1.2", "flow.dx=2", "sweep.y0=[0.3, 0.4]", "fiber.contact.pillar=smooth",
         "fiber.effects={friction: 0.3}", "fiber.contact.chi=1.25"],
    )  # fmt: skip
    assert cfg.fiber.contact.chi == 1.25  # the later override wins
    assert cfg.flow.dx == 2.0 and cfg.sweep.y0 == [0.3, 0.4]
    assert cfg.fiber.contact.pillar == "smooth" and cfg.fiber.effects == {"friction": 0.3}
    assert load_config(cfg_file).fiber.contact.chi == 1.1  # the file is untouched


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("fiber.contact.chii=1.2",
         "fiber.contact.chii (override fiber.contact.chii=1.2): unknown key; did you mean 'chi'?"),
        ("flow.dx=abc", "flow.dx (override flow.dx=abc): Input should be a valid number"),
        ("run.workers=0", "run.workers (override run.workers=0): Input should be greater than"),
        ("fiberx", "override 'fiberx': expected KEY=VALUE with a dotted key"),
        ("=3", "override '=3': expected KEY=VALUE"),
        ("fiber.contact.chi.x=2",
         "override 'fiber.contact.chi.x=2': fiber.contact.chi is a value, not a section"),
        ("sweep.y0=[0.3", "override 'sweep.y0=[0.3': the value is not valid YAML"),
    ],
)  # fmt: skip
def test_bad_overrides_name_the_key_and_the_override(cfg_file, override, message):
    with pytest.raises(ConfigError) as ei:
        load_config(cfg_file, [override])
    assert message in str(ei.value)


def test_config_command_prints_the_resolved_config_and_exits_2_on_errors(cfg_file):
    runner = CliRunner()
    r = runner.invoke(app, ["config", str(cfg_file), "fiber.contact.chi=1.3"])
    assert r.exit_code == 0, r.output
    resolved = yaml.safe_load(r.output)
    assert resolved["fiber"]["contact"]["chi"] == 1.3
    assert resolved["flow"]["dx"] == 4.0  # defaults filled in
    r = runner.invoke(app, ["config", str(cfg_file), "fiber.contact.chii=1"])
    assert r.exit_code == 2 and "did you mean 'chi'?" in r.output
