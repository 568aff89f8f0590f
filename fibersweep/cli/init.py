"""``fibersweep init``: a commented starter config and the shipped examples."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from fibersweep.cli._app import _errors, app


@app.command()
def init(
    directory: Annotated[
        Path, typer.Argument(help="Folder to write the configs into (created if missing).")
    ] = Path("."),
    force: Annotated[bool, typer.Option("--force", help="Overwrite existing files.")] = False,
) -> None:
    """Write fibersweep.yaml (a commented starter) and the quick and paper examples."""
    with _errors():
        from fibersweep.examples import write_examples

        written = write_examples(directory, force=force)
    for p in written:
        typer.echo(f"wrote {p}")
    typer.echo(f"next: fibersweep run {written[0]}")
