"""``fibersweep config``: the resolved config, as every command would see it."""

from __future__ import annotations

import typer

from fibersweep.cli._app import SETUP, ConfigArg, Overrides, _errors, _load, app


@app.command("config", rich_help_panel=SETUP)
def show_config(config: ConfigArg, overrides: Overrides = None) -> None:
    """Print CONFIG with the OVERRIDES applied and every default filled in (YAML)."""
    import yaml

    with _errors():
        cfg = _load(config, overrides)
    data = cfg.model_dump(mode="json")
    array = cfg.flow.array is not None
    if array:  # the unit cell is the domain: no channel
        data["flow"].pop("geometry", None)
    typer.echo(yaml.safe_dump(data, sort_keys=False).rstrip())
    if array:
        typer.echo("# flow.geometry (the single channel) is unused with flow.array")
