"""Pillar-array command ``sort-report`` (and ``run-array``, removed: use ``fibersweep run``)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer

from fibersweep.cli._app import ConfigArg, Overrides, Verbose, _errors, _setup_logging, app
from fibersweep.errors import InputError
from fibersweep.fiber.settings import ARRAY_ROWS


@app.command("run-array", hidden=True)
def run_array(
    config: ConfigArg,
    overrides: Overrides = None,
    verbose: Verbose = False,
) -> None:
    """Removed: a pillar-array sweep is ``fibersweep run CONFIG`` with ``flow.array`` set."""
    _setup_logging(verbose)
    with _errors():
        raise InputError(
            "run-array: removed; use fibersweep run CONFIG (a pillar array is the flow.array "
            "section of the standard config: see configs/array.yaml and docs/arrays.md)"
        )


@app.command("sort-report")
def sort_report(
    results: Annotated[Path, typer.Argument(help="Output folder of an array sweep.")],
    rows: Annotated[
        int | None, typer.Option(help="Rows of the device [default: fiber.array_rows].")
    ] = None,
    outlets: Annotated[
        str, typer.Option(help="Outlet edges, fractions of the full displacement, comma separated.")
    ] = "0.5",
    figures: Annotated[bool, typer.Option(help="Write the figures.")] = True,
    zigzag_max: Annotated[float, typer.Option(help="Mode rule: |f| below this is zigzag.")] = 0.25,
    displacement_min: Annotated[float, typer.Option(help="f above this is displacement.")] = 0.75,
    verbose: Verbose = False,
) -> None:
    """Migration angle against length, critical lengths, purity and recovery per outlet."""
    _setup_logging(verbose)
    with _errors():
        import pandas as pd

        from fibersweep.analysis.modes import ModeSettings
        from fibersweep.sweep import sort_report as sr

        runs, settings, cfg = sr.load_array_results(results)
        try:
            edges = [float(e) for e in outlets.split(",") if e.strip()]
        except ValueError:
            raise InputError(f"--outlets: not a list of numbers: {outlets!r}") from None
        modes = ModeSettings(zigzag_max=zigzag_max, displacement_min=displacement_min)
        trap_speed = cfg["fiber"]["classify"]["trap_speed"]
        runs = sr.relabel(runs, settings, modes, trap_speed)
        table = sr.migration_table(runs)
        n_rows = rows or cfg["fiber"].get("array_rows", ARRAY_ROWS)
        pd.set_option("display.width", 160)
        typer.echo("migration angle [deg] and mode fractions per setting and length:")
        typer.echo(table.round(3).to_string(index=False))
        for s, crit in sr.critical_lengths(table).items():
            lab = settings[s]["label"] or "array"
            typer.echo(
                f"critical length(s) of {lab} (mean fraction 0.5): "
                + (", ".join(f"{c:.1f} µm" for c in crit) or "none in the swept range")
            )
        for s, new in sr.refine_lengths(table).items():
            if new:
                lab = settings[s]["label"] or "array"
                typer.echo(
                    f"to bisect the critical length of {lab}: add {new} to sweep.length and "
                    "run the same config into this folder again (only the new lengths run)"
                )
        out = sr.outlet_table(runs, settings, n_rows, edges)
        typer.echo(
            f"device of {n_rows} rows, outlet edges {edges} (fraction of full "
            "displacement): recovery and purity per outlet"
        )
        typer.echo(out.round(3).to_string(index=False))
        table.to_csv(results / "migration.csv", index=False)
        out.to_csv(results / "outlets.csv", index=False)
        if figures:
            _figures(results, runs, table, settings, cfg)


def _figures(results: Path, runs, table, settings: list[dict], cfg: dict) -> None:
    from fibersweep.flow.cache import get_flow_field
    from fibersweep.flow.settings import FlowSettings
    from fibersweep.plots import array as pa
    from fibersweep.plots.style import paper_style, save_figure

    written = []
    with paper_style():
        for i, s in enumerate(settings):
            # the sweep's cell field, from the cache (solved again if it was removed)
            flow = FlowSettings.model_validate(s["flow"])
            field, _ = get_flow_field(flow, cfg["run"]["cache_dir"])
            array = field.array
            written.append(save_figure(pa.cell_flow_figure(field), results / f"cell-flow-{i}.png",
                                       dpi=110))  # fmt: skip
            sub = runs[runs["setting"] == i]
            picks = [sub[sub["mode"] == m].iloc[0].to_dict() for m in
                     ("zigzag", "displacement", "wrap-and-jump", "mixed", "trapped")
                     if (sub["mode"] == m).any()]  # fmt: skip
            fig = pa.chrono_figure(array, picks, cfg["fiber"]["bead_radius"])
            written.append(save_figure(fig, results / f"chrono-{i}.png", dpi=100))
            fig = pa.overlay_figure(sub, array.period_x, sorted(sub["length"].unique()))
            written.append(save_figure(fig, results / f"overlay-{i}.png", dpi=110))
        tilts = {i: math.degrees(math.atan(s["array"]["shift"])) for i, s in enumerate(settings)}
        labels = {i: s["label"] for i, s in enumerate(settings)}
        written.append(save_figure(pa.migration_figure(table, tilts, labels),
                                   results / "migration.png"))  # fmt: skip
    for w in written:
        typer.echo(f"figure: {w}")
