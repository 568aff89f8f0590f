"""Small things a user trips on: empty or broken configs, the init help, completion."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from fibersweep.analysis.classify import RULES
from fibersweep.cli import app
from fibersweep.config import load_config
from fibersweep.config.errors import ConfigError
from fibersweep.examples import EXAMPLES

REPO = Path(__file__).resolve().parents[2]
runner = CliRunner()


@pytest.mark.parametrize("text", ["", "\n\n", "# only a comment\n"])
def test_an_empty_config_is_refused_with_exit_2(tmp_path, text):
    p = tmp_path / "empty.yaml"
    p.write_text(text)
    with pytest.raises(ConfigError, match="holds no settings"):
        load_config(p)
    res = runner.invoke(app, ["run", str(p), "--dry-run"])
    assert res.exit_code == 2 and "holds no settings" in res.output
    assert not (tmp_path / "results").exists()


def test_yaml_errors_name_the_file(tmp_path):
    p = tmp_path / "broken.yaml"
    p.write_text("flow:\n  dx: [1\n")
    with pytest.raises(ConfigError) as exc:
        load_config(p)
    msg = str(exc.value)
    assert f'in "{p}", line 2' in msg and "<unicode string>" not in msg


def test_init_help_lists_every_file_it_writes():
    res = runner.invoke(app, ["init", "--help"], terminal_width=200)
    assert res.exit_code == 0
    for name in EXAMPLES.values():
        assert name in res.output, name


def _complete(words: str) -> list[str]:
    env = {
        **os.environ,
        "PYTHONPATH": str(REPO),
        "_FIBERSWEEP_COMPLETE": "complete_bash",
        "COMP_WORDS": words,
        "COMP_CWORD": str(len(words.split()) - (0 if words.endswith(" ") else 1)),
    }
    out = subprocess.run(
        [sys.executable, "-m", "fibersweep"], env=env, capture_output=True, text=True, check=True
    ).stdout
    return out.split()


def test_shell_completion_completes_commands_options_and_choices():
    assert sorted(_complete("fibersweep plot")) == [
        "plot-delta",
        "plot-fractions",
        "plot-phase",
        "plot-tracks",
    ]
    assert _complete("fibersweep plot-p") == ["plot-phase"]
    assert "--executor" in _complete("fibersweep run c.yaml --exe")
    assert sorted(_complete("fibersweep classify r --rule ")) == sorted(RULES)
    res = runner.invoke(app, ["--help"])
    assert "--install-completion" in res.output and "--show-completion" in res.output
