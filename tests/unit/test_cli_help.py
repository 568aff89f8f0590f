"""The help says what the tool does today, in groups, every description whole."""

from __future__ import annotations

import re

from typer.main import get_command
from typer.testing import CliRunner

import fibersweep
from fibersweep.cli import app
from fibersweep.cli._app import PANELS, short_help


def _help(*args: str) -> str:
    res = CliRunner().invoke(app, [*args, "--help"], terminal_width=100)
    assert res.exit_code == 0, res.output
    return res.output


def test_commands_are_grouped_and_every_description_is_whole():
    text = _help()
    group = get_command(app)
    visible = {n: c for n, c in group.commands.items() if not c.hidden}
    heads = [p for p in PANELS if f"\n{p}:\n" in text]
    assert heads == list(PANELS)  # sweep, figures, arrays, measurements, setup
    listing = text.split("\nSweeps:\n")[1]
    assert "..." not in listing  # no description cut
    for name, cmd in visible.items():
        assert cmd.rich_help_panel in PANELS, name
        line = short_help(cmd)
        assert line.endswith("."), (name, line)  # a whole sentence
        words = " ".join(text.split())
        assert f"{name} {line}" in words, name  # listed whole, wrapped but not cut
    assert text.index("run ") < text.index("plot-phase") < text.index("sort-report")
    assert text.index("sort-report") < text.index("discrepancy") < text.index("init ")


def test_help_says_what_the_tool_does_today():
    for text in (_help(), fibersweep.__doc__):
        assert "rigid fibers meeting a triangular pillar" not in text
        assert "flexible" in text and "array" in text


def test_stale_options_are_gone_and_examples_fit_their_command():
    assert "--effects" not in _help("discrepancy")
    sim = " ".join(_help("simulate").split())
    assert "sweep." not in sim  # no sweep override as the example of one run
    assert re.search(r"fiber\.model=bead-\s?spring", sim), sim
    assert "period_y" in sim and "[µm]" in sim  # the array's units of the start
