"""Pillar-array commands: ``run-array`` (a sweep through a tilted array) and ``sort-report``."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer

from fibersweep.cli._app import ConfigArg, Overrides, Verbose, _errors, _setup_logging, app
from fibersweep.errors import InputError


@app.command("run-array")
def run_array(
    config: ConfigArg,
    overrides: Overrides = None,
    workers: Annotated[int | None, typer.Option(help="Worker processes.")] = None,
    refine: Annotated[
        int, typer.Option(help="Rounds of bisection of the critical length (adds lengths).")
    ] = 0,
    verbose: Verbose = False,
) -> None:
    """Fibers through a tilted pillar array: unit-cell flow, seeded random starts, many rows."""
    _setup_logging(verbose)
    with _errors():
        from fibersweep.sweep.arrays import load_array_config, run_array_sweep

        cfg = load_array_config(config, overrides or ())
        df = run_array_sweep(cfg, workers, refine=refine)
        typer.echo(f"{len(df)} runs -> {Path(cfg.run.output) / 'runs.parquet'}")
        typer.echo(df.groupby(["setting", "length"])["mode"].value_counts().unstack(fill_value=0)
                   .to_string())  # fmt: skip


@app.command("sort-report")
def sort_report(
    results: Annotated[Path, typer.Argument(help="Output folder of run-array.")],
    rows: Annotated[
        int | None, typer.Option(help="Rows of the device [default: swept rows].")
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

        try:
            runs = pd.read_parquet(results / "runs.parquet")
            meta = json.loads((results / "array.json").read_text())
        except (OSError, ValueError) as exc:
            raise InputError(f"RESULTS: {results} holds no array sweep ({exc})") from None
        try:
            edges = [float(e) for e in outlets.split(",") if e.strip()]
        except ValueError:
            raise InputError(f"--outlets: not a list of numbers: {outlets!r}") from None
        cfg = meta["config"]
        trap_speed = cfg["fiber"]["classify"]["trap_speed"] * cfg["flow"]["u_center"]
        modes = ModeSettings(zigzag_max=zigzag_max, displacement_min=displacement_min,
                             trap_speed=trap_speed)  # fmt: skip
        runs = sr.relabel(runs, meta["settings"], modes)
        table = sr.migration_table(runs)
        n_rows = rows or cfg["sweep"]["rows"]
        pd.set_option("display.width", 160)
        typer.echo("migration angle [deg] and mode fractions per setting and length:")
        typer.echo(table.round(3).to_string(index=False))
        for s, crit in sr.critical_lengths(table).items():
            lab = meta["settings"][s]["label"] or "array"
            typer.echo(
                f"critical length(s) of {lab} (mean fraction 0.5): "
                + (", ".join(f"{c:.1f} µm" for c in crit) or "none in the swept range")
            )
        out = sr.outlet_table(runs, meta["settings"], n_rows, edges)
        typer.echo(
            f"device of {n_rows} rows, outlet edges {edges} (fraction of full "
            "displacement): recovery and purity per outlet"
        )
        typer.echo(out.round(3).to_string(index=False))
        table.to_csv(results / "migration.csv", index=False)
        out.to_csv(results / "outlets.csv", index=False)
        if figures:
            _figures(results, runs, table, meta, cfg)


def _figures(results: Path, runs, table, meta, cfg) -> None:
    from fibersweep.plots import array as pa
    from fibersweep.plots.style import paper_style, save_figure
    from fibersweep.sweep.arrays import load_field

    written = []
    with paper_style():
        for i, s in enumerate(meta["settings"]):
            array = _array_of(s["array"])
            field = load_field(results / f"field-{i}.npz", array)
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
        tilts = {i: _array_of(s["array"]).tilt_deg for i, s in enumerate(meta["settings"])}
        labels = {i: s["label"] for i, s in enumerate(meta["settings"])}
        written.append(save_figure(pa.migration_figure(table, tilts, labels),
                                   results / "migration.png"))  # fmt: skip
    for w in written:
        typer.echo(f"figure: {w}")


def _array_of(stored: dict):
    from fibersweep.sweep.arrays import ArraySettings

    return ArraySettings.model_validate(stored).to_array()
