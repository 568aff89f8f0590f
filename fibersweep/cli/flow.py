"""The ``flow`` command: the steady flow field of a config."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from fibersweep.cli._app import (
    SETUP,
    ConfigArg,
    Overrides,
    Verbose,
    _errors,
    _setup_logging,
    app,
)


@app.command(rich_help_panel=SETUP)
def flow(
    config: ConfigArg,
    overrides: Overrides = None,
    force: Annotated[
        bool, typer.Option("--force", help="Recompute the field even if it is cached.")
    ] = False,
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot",
            help="Write a figure of the field (PNG/PDF/SVG by suffix); with several fields, "
            "one per field, its key added to the name.",
        ),
    ] = None,
    verbose: Verbose = False,
) -> None:
    """Compute (or load from the cache) the steady flow field of CONFIG: a channel's, or a
    pillar array's unit cell.

    A sweep over flow settings (``sweep: {flow.dx: [4, 2]}``) has one field per
    distinct flow setting: each is computed (or found) once and reported.
    """
    from fibersweep import api

    _setup_logging(verbose)
    with _errors():
        fields = api.flow_field(config, *(overrides or []), force=force, plot=plot, progress=True)
    for k, rep in enumerate(fields):
        if len(fields) > 1:
            typer.echo(f"field {k + 1} of {len(fields)} ({rep.label}):")
        _report(rep, "  " if len(fields) > 1 else "")


def _report(rep, pad: str) -> None:
    """What one field is (:class:`fibersweep.api.FieldReport`)."""
    settings, info, field = rep.settings, rep.info, rep.field
    nx, ny, nz, nz_full = info.grid
    depth = f"half depth, {nz} of {nz_full} nodes + symmetry plane" if nz < nz_full else "full"
    typer.echo(f"{pad}cache: {'hit' if info.hit else 'miss (computed)'}  {info.path}")
    if settings.patch is None:
        typer.echo(f"{pad}grid: {nx} x {ny} x {nz} nodes ({depth}), dx = {settings.dx:g} µm")
    else:
        box = field.meta["patch"]
        typer.echo(
            f"{pad}patch: {nx} x {ny} x {nz} nodes ({depth}), dx = {settings.patch.dx:g} µm, "
            f"from x = {box['x0_um']:g}, y = {box['y0_um']:g} µm, nested in the channel "
            f"at dx = {settings.dx:g} µm ({box['channel_report']['steps']} steps)"
        )
    if settings.array is not None:
        typer.echo(f"{pad}unit cell of the pillar array (flow.array, docs/arrays.md)")
    conv = "converged" if info.converged else "NOT converged (max_steps reached)"
    coarse = f" (after {info.coarse_steps} on coarser grids)" if info.coarse_steps else ""
    typer.echo(
        f"{pad}solver: {settings.collision.upper()}, {info.steps} steps{coarse}, {conv}, "
        f"relative change per check {info.residual:.2e} (tolerance {settings.tolerance:g})"
    )
    took = rep.seconds
    typer.echo(
        f"{pad}time: solve {info.seconds:.1f} s"
        + (f" (when cached); load {took:.2f} s" if info.hit else f"; total {took:.1f} s")
    )
    typer.echo(
        f"{pad}U_center reached: {info.u_center_reached:.3f} µm/s "
        f"(target {settings.fluid.u_center:g} µm/s)"
    )
    if settings.array is not None:  # a pillar array's unit cell: no far upstream
        _report_cell(field, pad)
    elif rep.separatrix is None:  # no streamline bracket (e.g. a toy channel)
        typer.echo(f"{pad}separatrix far upstream: not located ({rep.separatrix_error})")
    else:
        _echo_separatrix(rep.separatrix, settings.pillar_boundary, pad)
    if rep.figure is not None:
        typer.echo(f"{pad}wrote {rep.figure}")


def _report_cell(field, pad: str) -> None:
    """What a unit-cell field adds: its array and mean flow direction."""
    d = field.array.describe()
    typer.echo(
        f"{pad}array: gap {d['gap']:.3g} µm, row shift {field.array.lateral_shift:.3g} µm "
        f"(tilt {field.array.tilt_deg:.2f} deg); mean flow at "
        f"{field.meta['mean_flow_angle_deg']:.3f} deg to x"
    )


def _echo_separatrix(est, boundary: str, pad: str = "") -> None:
    """Print a :class:`fibersweep.flow.uncertainty.SeparatrixEstimate`."""
    typer.echo(
        f"{pad}separatrix far upstream: y/h_obs = {est.traced:.4f} +- {est.error:.4f} "
        f"({boundary} pillar)"
    )
    typer.echo(
        f"{pad}  model spread: traced {est.traced:.4f} vs flux {est.flux:.4f} "
        f"-> {est.model_spread:.4f}"
    )
    if est.grid_error is None:
        typer.echo(f"{pad}  grid error: no level at 2 dx or dx/2 in the cache (not estimated)")
    else:
        typer.echo(
            f"{pad}  grid error: Richardson (p = 2) with cached dx = {est.other_dx:g} µm "
            f"(traced {est.other_traced:.4f}) -> {est.grid_error:.4f}, "
            f"extrapolated {est.extrapolated:.4f}"
        )
