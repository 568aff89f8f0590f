"""The discrepancy commands (issue 6): ``synth`` and ``discrepancy``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from fibersweep.cli._app import (
    ConfigArg,
    Overrides,
    Verbose,
    Workers,
    _errors,
    _load,
    _setup_logging,
    app,
)


def _sweep_box(cfg) -> dict[str, tuple[float, float]]:
    from fibersweep.config import axis_values

    box = {}
    for name in ("theta0", "y0", "length"):
        v = axis_values(getattr(cfg.sweep, name))
        box[name] = (float(v.min()), float(v.max()))
    return box


@app.command()
def synth(
    config: ConfigArg,
    overrides: Overrides = None,
    effect: Annotated[
        list[str] | None,
        typer.Option("--effect", help="Hidden effect NAME=VALUE (repeatable)."),
    ] = None,
    n: Annotated[int, typer.Option("--n", help="Number of fibers.")] = 100,
    seed: Annotated[int, typer.Option(help="Random seed.")] = 0,
    output: Annotated[
        Path, typer.Option("--output", "-o", help="Measured table (.parquet or .csv).")
    ] = Path("measured.parquet"),
    truth: Annotated[
        Path | None, typer.Option(help="Truth file [OUTPUT with suffix .truth.json].")
    ] = None,
    workers: Workers = None,
    verbose: Verbose = False,
) -> None:
    """Measured-like fibers from the model with hidden effects and measurement noise.

    Starts are uniform in the range of CONFIG's sweep axes; the truth (effects,
    noise, true starts) goes to a separate JSON file.
    """
    import json

    _setup_logging(verbose)
    with _errors():
        cfg = _load(config, overrides)
        from fibersweep.discrepancy.schema import write_table
        from fibersweep.discrepancy.synth import parse_effects, synthesize
        from fibersweep.flow.cache import get_flow_field

        effects = parse_effects(effect)
        field, _ = get_flow_field(cfg.flow, cfg.run.cache_dir)
        table, tr = synthesize(
            field, cfg.fiber, _sweep_box(cfg), n, effects, seed=seed,
            workers=workers or cfg.run.workers, executor=cfg.run.executor,
            scheduler=cfg.run.scheduler,
        )  # fmt: skip
        write_table(table, output)
        tpath = truth or output.with_suffix(".truth.json")
        from fibersweep.atomic import atomic_write

        atomic_write(tpath, json.dumps(tr, indent=2))
    typer.echo(f"wrote {output} ({len(table)} fibers) and {tpath}")
    if tr["failed"]:
        typer.secho(f"  {len(tr['failed'])} failed runs left out (listed in the truth)",
                    fg=typer.colors.YELLOW)  # fmt: skip


@app.command()
def discrepancy(
    measured: Annotated[Path, typer.Argument(help="Measured fibers (.parquet or .csv).")],
    config: ConfigArg,
    overrides: Overrides = None,
    output: Annotated[Path, typer.Option("--output", "-o", help="Report folder.")] = Path("report"),
    budget: Annotated[int | None, typer.Option(help="Most simulations in total.")] = None,
    seed: Annotated[int, typer.Option(help="Random seed.")] = 0,
    copies: Annotated[int, typer.Option(help="Jittered baseline copies per fiber.")] = 8,
    effects: Annotated[
        str | None, typer.Option(help="Comma-separated effects to consider (default: all).")
    ] = None,
    alpha: Annotated[float, typer.Option(help="Family-wise error rate.")] = 0.05,
    trajectories: Annotated[
        Path | None, typer.Option(help="Optional measured trajectories table.")
    ] = None,
    ignore_extra_columns: Annotated[
        bool, typer.Option(help="Ignore columns of MEASURED the schema does not know.")
    ] = False,
    workers: Workers = None,
    verbose: Verbose = False,
) -> None:
    """Where the model disagrees with MEASURED, which effect explains it, and the gap left."""
    _setup_logging(verbose)
    with _errors():
        cfg = _load(config, overrides)
        from fibersweep.discrepancy.report import write_report
        from fibersweep.discrepancy.schema import load_measured
        from fibersweep.discrepancy.workflow import DiscrepancySettings, run_discrepancy
        from fibersweep.flow.cache import get_flow_field

        data = load_measured(measured, trajectories, ignore_extra=ignore_extra_columns)
        settings = DiscrepancySettings(
            copies=copies, budget=budget, seed=seed, alpha=alpha,
            workers=workers or cfg.run.workers,
            executor=cfg.run.executor, scheduler=cfg.run.scheduler,
            effects=tuple(e.strip() for e in effects.split(",")) if effects else None,
        )  # fmt: skip
        field, _ = get_flow_field(cfg.flow, cfg.run.cache_dir)
        res = run_discrepancy(data, field, cfg.fiber, settings)
        s = write_report(res, output, cfg.model_dump(mode="json"))
    typer.echo(f"verdict: {s['verdict']['kind']}: {s['verdict']['text']}")
    typer.echo(f"simulations: {s['simulations']} in {s['seconds']:.0f} s")
    typer.echo(f"wrote {output / 'report.md'} and {output / 'summary.json'}")
    for c in s["updated_configs"]:
        typer.echo(f"wrote {output / c}")
