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
    typer.echo(yaml.safe_dump(cfg.model_dump(mode="json"), sort_keys=False).rstrip())
