"""Packaging: the examples ship with the package, `init` writes them, `--version` answers."""

from __future__ import annotations

from typer.testing import CliRunner

from fibersweep import __version__
from fibersweep.cli import app
from fibersweep.config import load_config
from fibersweep.examples import EXAMPLES


def test_version():
    r = CliRunner().invoke(app, ["--version"])
    assert r.exit_code == 0 and r.output.strip() == f"fibersweep {__version__}"


def test_init_writes_valid_configs_and_never_overwrites_silently(tmp_path):
    runner = CliRunner()
    r = runner.invoke(app, ["init", str(tmp_path / "here")])
    assert r.exit_code == 0, r.output
    written = sorted(p.name for p in (tmp_path / "here").iterdir())
    assert written == sorted(EXAMPLES.values())
    for name in EXAMPLES.values():  # every shipped example is a valid config
        assert load_config(tmp_path / "here" / name).sweep.size > 0
    (tmp_path / "here" / "fibersweep.yaml").write_text("# mine\n")
    r = runner.invoke(app, ["init", str(tmp_path / "here")])
    assert r.exit_code == 2 and "use --force to overwrite" in r.output
    assert (tmp_path / "here" / "fibersweep.yaml").read_text() == "# mine\n"
    assert runner.invoke(app, ["init", str(tmp_path / "here"), "--force"]).exit_code == 0
    assert (tmp_path / "here" / "fibersweep.yaml").read_text().startswith("# fibersweep starter")
