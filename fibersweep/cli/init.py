"""``fibersweep init``: a commented starter config and the shipped examples."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from fibersweep.cli._app import SETUP, _errors, app
from fibersweep.examples import EXAMPLES

_WRITTEN = ", ".join(name for name in EXAMPLES.values() if name != "fibersweep.yaml")
INIT_HELP = (
    "Write fibersweep.yaml (a commented starter) and the shipped examples: "
    f"{_WRITTEN}. Existing files are kept unless --force."
)


@app.command(help=INIT_HELP, rich_help_panel=SETUP)
def init(
    directory: Annotated[
        Path, typer.Argument(help="Folder to write the configs into (created if missing).")
    ] = Path("."),
    force: Annotated[bool, typer.Option("--force", help="Overwrite existing files.")] = False,
) -> None:
    """Write the starter config and the examples (help text: ``INIT_HELP``)."""
    with _errors():
        from fibersweep.examples import write_examples

        written = write_examples(directory, force=force)
    for p in written:
        typer.echo(f"wrote {p}")
    typer.echo(f"next: fibersweep run {written[0]}")
