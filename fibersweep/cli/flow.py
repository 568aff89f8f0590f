"""The ``flow`` command (issue 2): the steady flow field of a config."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from fibersweep.cli._app import (
    ConfigArg,
    Overrides,
    Verbose,
    _errors,
    _load,
    _setup_logging,
    app,
    flow_progress,
)


@app.command()
def flow(
    config: ConfigArg,
    overrides: Overrides = None,
    force: Annotated[
        bool, typer.Option("--force", help="Recompute the field even if it is cached.")
    ] = False,
    plot: Annotated[
        Path | None,
        typer.Option("--plot", help="Write a figure of the field (PNG/PDF/SVG by suffix)."),
    ] = None,
    verbose: Verbose = False,
) -> None:
    """Compute (or load from the cache) the steady flow field of CONFIG."""
    import time

    _setup_logging(verbose)
    with _errors():
        cfg = _load(config, overrides)
        from fibersweep.flow.cache import get_flow_field

        t0 = time.perf_counter()
        with flow_progress():
            field, info = get_flow_field(cfg.flow, cfg.run.cache_dir, force=force)
        took = time.perf_counter() - t0
        nx, ny, nz, nz_full = info.grid
        depth = f"half depth, {nz} of {nz_full} nodes + symmetry plane" if nz < nz_full else "full"
        typer.echo(f"cache: {'hit' if info.hit else 'miss (computed)'}  {info.path}")
        typer.echo(f"grid: {nx} x {ny} x {nz} nodes ({depth}), dx = {cfg.flow.dx:g} µm")
        conv = "converged" if info.converged else "NOT converged (max_steps reached)"
        coarse = f" (after {info.coarse_steps} on coarser grids)" if info.coarse_steps else ""
        typer.echo(
            f"solver: {cfg.flow.collision.upper()}, {info.steps} steps{coarse}, {conv}, "
            f"relative change per check {info.residual:.2e} (tolerance {cfg.flow.tolerance:g})"
        )
        typer.echo(
            f"time: solve {info.seconds:.1f} s"
            + (f" (when cached); load {took:.2f} s" if info.hit else f"; total {took:.1f} s")
        )
        typer.echo(
            f"U_center reached: {info.u_center_reached:.3f} µm/s "
            f"(target {cfg.flow.fluid.u_center:g} µm/s)"
        )
        if plot is not None:
            from fibersweep.plots.flow import plot_flow

            typer.echo(f"wrote {plot_flow(field, plot)}")
