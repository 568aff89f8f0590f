"""sweep.refine: a declared, validated section; every problem names its field (exit 2)."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from fibersweep.cli import app
from fibersweep.config import ConfigError, load_config

BASE = """sweep:
  theta0: [-4.0, 0.0, 4.0]
  y0: [0.1, 0.3, 0.5]
  length: 0.8
  refine:
    axes: [y0, theta0]
    tolerance: {y0: 0.005, theta0: 0.5}
    max_runs: 50
"""


def _write(tmp_path: Path, text: str = BASE) -> Path:
    p = tmp_path / "c.yaml"
    p.write_text(text)
    return p


def _problems(tmp_path: Path, *overrides: str, text: str = BASE) -> str:
    with pytest.raises(ConfigError) as err:
        load_config(_write(tmp_path, text), overrides)
    return str(err.value)


def test_valid_refine_section_round_trips(tmp_path):
    cfg = load_config(_write(tmp_path))
    r = cfg.sweep.refine
    assert r.axes == ["y0", "theta0"] and r.tolerance == {"y0": 0.005, "theta0": 0.5}
    assert r.max_runs == 50 and r.rounds == 12 and r.delta_jump is None
    assert cfg.model_dump(mode="json")["sweep"]["refine"]["max_runs"] == 50
    plain = load_config(_write(tmp_path), ["sweep.refine=null"])
    assert "refine" not in plain.model_dump(mode="json")["sweep"]  # written only when used


@pytest.mark.parametrize(
    ("overrides", "expected"),
    [
        (["sweep.refine.axes=[y0, theta]"],
         "sweep.refine.axes.1 (override sweep.refine.axes=[y0, theta]): 'theta' cannot be "
         "refined; did you mean 'theta0'?"),
        (["sweep.refine.axes=[y0, fiber.effects.friction]"], "valid: theta0, y0, length"),
        (["sweep.refine.axes=[y0, y0]"], "sweep.refine.axes (override"),
        (["sweep.refine.tolerance={y0: 0.005}"],
         "sweep.refine.tolerance (override sweep.refine.tolerance={y0: 0.005}): no tolerance "
         "for theta0"),
        (["sweep.refine.tolerance.length=0.1"],
         "sweep.refine.tolerance.length (override sweep.refine.tolerance.length=0.1): not a "
         "refine axis"),
        (["sweep.refine.tolerance.y0=-0.1"], "sweep.refine.tolerance.y0 (override"),
        (["sweep.refine.max_runs=0"],
         "sweep.refine.max_runs (override sweep.refine.max_runs=0): Input should be greater "
         "than or equal to 1"),
        (["sweep.refine.rounds=0"], "sweep.refine.rounds (override"),
        (["sweep.refine.delta_jump=-1"], "sweep.refine.delta_jump (override"),
        (["sweep.refine.round=3"],
         "sweep.refine.round (override sweep.refine.round=3): unknown key; did you mean "
         "'rounds'?"),
        (["sweep.theta0=0.0"],
         "sweep.refine.axes.1 (line 6): theta0 has one value in the grid: nothing to bisect"),
        (["sweep.refine.max_runs=300000"],
         "with the 300,000 refinement runs of sweep.refine.max_runs), more than run.max_points"),
    ],
)  # fmt: skip
def test_refine_errors_name_the_field(tmp_path, overrides, expected):
    assert expected in _problems(tmp_path, *overrides)


def test_refine_errors_in_the_file_give_its_line(tmp_path):
    text = BASE.replace("max_runs: 50", "max_runs: 50\n    colour: red")
    msg = _problems(tmp_path, text=text)
    assert "sweep.refine.colour (line 9): unknown key. Valid keys here: axes, tolerance" in msg


def test_cli_exits_2_on_a_refine_error(tmp_path):
    res = CliRunner().invoke(app, ["config", str(_write(tmp_path)), "sweep.refine.axes=[y]"])
    out = res.output + (res.stderr if res.stderr_bytes is not None else "")
    assert res.exit_code == 2, out
    assert "sweep.refine.axes.0" in out and "did you mean 'y0'?" in out
