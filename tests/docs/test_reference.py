"""The reference pages (docs/reference/) are what the code generates now, and complete."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from fibersweep import docgen
from fibersweep.config.schema import Config

REPO = Path(__file__).resolve().parents[2]
REF = REPO / "docs" / "reference"


@pytest.mark.parametrize("name", list(docgen.PAGES))
def test_reference_page_is_current(name: str) -> None:
    """A changed config key, command, option or column fails here until the page is rewritten."""
    path = REF / f"{name}.md"
    have = path.read_text(encoding="utf-8") if path.exists() else ""
    assert have == docgen.render(name), (
        f"docs/reference/{name}.md is out of date with the code: "
        f"run `{docgen.REGENERATE}` to update it"
    )


def _keys(model, prefix=""):
    for name, info in model.model_fields.items():
        yield prefix + name
        nested = docgen._nested_model(info.annotation)
        if nested is not None:
            yield from _keys(nested, f"{prefix}{name}.")


def test_every_config_key_is_in_the_config_page() -> None:
    """Walked from the schema independently of the page's own order and layout."""
    page = docgen.render("config")
    missing = [k for k in _keys(Config) if "." in k and f"`{k}`" not in page]
    assert not missing, missing


def test_every_command_and_option_is_in_the_commands_page() -> None:
    """Every visible command of the click group typer builds, and each of its options."""
    import typer

    from fibersweep.cli import app

    page = docgen.render("commands")

    def walk(group, prefix):
        for name, cmd in group.commands.items():
            if cmd.hidden:
                continue
            yield f"{prefix} {name}", cmd
            if hasattr(cmd, "commands"):  # a group: its commands too
                yield from walk(cmd, f"{prefix} {name}")

    for full, cmd in walk(typer.main.get_command(app), "fibersweep"):
        assert f"## {full}\n" in page, full
        section = page.split(f"## {full}\n", 1)[1].split("\n## ", 1)[0]
        for param in cmd.params:
            if getattr(param, "hidden", False):
                continue
            for opt in param.opts:
                if opt.startswith("-"):
                    assert opt in section, f"{full}: {opt}"


def test_every_column_is_in_the_columns_page() -> None:
    from fibersweep.sweep.coldocs import RUN_EXTRA_DOCS, TRAJ_COLUMN_DOCS
    from fibersweep.sweep.store import RUN_COLUMNS

    page = docgen.render("columns")
    for name in [*RUN_COLUMNS, *RUN_EXTRA_DOCS, *TRAJ_COLUMN_DOCS]:
        assert f"`{name}`" in page, name


def test_every_api_function_and_parameter_is_in_the_api_page() -> None:
    """Each function of ``fibersweep.API`` with each of its parameters, and each result
    object of ``fibersweep.api`` with its fields."""
    import dataclasses
    import inspect

    import fibersweep
    from fibersweep import api

    page = docgen.render("api")
    for name in fibersweep.API:
        assert f"## fibersweep.{name}\n" in page, name
        section = page.split(f"## fibersweep.{name}\n", 1)[1].split("\n## ", 1)[0]
        for param in inspect.signature(getattr(api, name)).parameters.values():
            star = "*" if param.kind is param.VAR_POSITIONAL else ""
            assert f"`{star}{param.name}`" in section, f"{name}: {param.name}"
    for name in api.__all__:
        cls = getattr(api, name)
        if not dataclasses.is_dataclass(cls):
            continue
        section = page.split(f"### {name}\n", 1)[1].split("\n### ", 1)[0]
        for f in dataclasses.fields(cls):
            assert re.search(rf"`([\w, ]*\b)?{f.name}\b", section), f"{name}.{f.name}"


@pytest.mark.parametrize(
    ("text", "unit"),
    [
        ("lattice spacing [µm]", "µm"),
        ("start x [µm]; None: L_ch/4", "µm"),
        ("uniform in theta0 and y0 given as [lo, hi] (off when absent)", ""),
        ("width [deg for theta0, h_obs for y0]", "deg for theta0, h_obs for y0"),
        ("no unit", ""),
    ],
)
def test_unit_is_read_from_the_description(text: str, unit: str) -> None:
    assert docgen._unit(text) == unit
