"""The ``simulate`` command: one fiber past the pillar, or through a pillar array."""

from __future__ import annotations

import math
import typing
from pathlib import Path
from typing import Annotated

import typer

from fibersweep.cli._app import (
    SWEEP,
    ConfigArg,
    RunOverrides,
    Verbose,
    _errors,
    _setup_logging,
    app,
    choices,
)
from fibersweep.config.fiber import LEGACY_MODELS, FiberSettings

# the models FiberSettings accepts (the model registry matches them, tested), and former names
Model = choices(
    "Model", (*typing.get_args(FiberSettings.model_fields["model"].annotation), *LEGACY_MODELS)
)


#: Seconds above which making the kernels ready means they were compiled, not loaded.
COMPILED_S = 2.0


@app.command(rich_help_panel=SWEEP)
def simulate(
    config: ConfigArg,
    theta0: Annotated[float, typer.Option("--theta0", help="Start angle from +x [deg].")],
    y0: Annotated[
        float,
        typer.Option(
            "--y0",
            help="Start lateral position: y0/h_obs past one pillar; in a pillar array "
            "(flow.array) a fraction of period_y in the gap before row 0.",
        ),
    ],
    length: Annotated[
        float,
        typer.Option(
            "--length", help="Fiber length: L/l_obs past one pillar; in a pillar array L [µm]."
        ),
    ],
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot",
            help="Write a chronophotograph (PNG/PDF/SVG by suffix); a flexible fiber is drawn "
            "through all its beads.",
        ),
    ] = None,
    model: Annotated[
        Model | None, typer.Option("--model", help="Fiber model.", show_default="fiber.model")
    ] = None,
    reversible: Annotated[
        bool, typer.Option("--reversible", help="Also reverse the flow and report the return.")
    ] = False,
    seed: Annotated[int | None, typer.Option("--seed", help="Seed of random effects.")] = None,
    verbose: Verbose = False,
    overrides: RunOverrides = None,
) -> None:
    """Run one fiber and print what it did: past one pillar its class, δ and contact; through
    a pillar array its mode, rows, shift per row, f and migration angle.

    The fiber kernels are compiled on first use (then loaded from the disk cache); the
    time that takes is said, apart from the run's. A start that touches a pillar is
    refused before the flow field and the kernels, naming the free ranges of y0 at
    that angle and length. Settings outside the validated range are warned about.
    """
    from fibersweep import api

    _setup_logging(verbose)
    with _errors():
        one = api.simulate(
            config, *(overrides or []), theta0=theta0, y0=y0, length=length,
            model=model.value if model is not None else None, reversible=reversible,
            seed=seed, plot=plot, progress=True,
        )  # fmt: skip
    res, fiber = one.result, one.fiber
    for message in one.warnings:  # outside the validated range, naming what to change
        typer.secho(f"warning: {message}", err=True, fg=typer.colors.YELLOW)
    if one.ready_s > COMPILED_S:
        typer.echo(
            f"first use: compiled the {fiber.model} kernels in {one.ready_s:.1f} s (cached on "
            "disk: the next runs load them)"
        )
    if one.array is not None:
        _echo_array(res, one.array, fiber)
    else:
        _echo_channel(res, fiber, reversible, one.returned)
    if math.isfinite(res.min_end_to_end):
        typer.echo(
            f"deformation: max curvature {res.max_curvature:.4f} 1/µm, min end-to-end "
            f"{res.min_end_to_end:.3f} of the contour, max tension "
            f"{res.max_tension:.3g} pN, max wrap {res.max_wrap:.1f}°"
        )
    typer.echo(f"steps: {res.n_steps} in {res.wall_time:.2f} s (the run alone)")
    if reversible:
        typer.echo(f"reversed flow: returns within {_f(one.returned, '.3g')} µm of the start")
    if one.figure is not None:
        typer.echo(f"wrote {one.figure}")
    if res.status != "ok":
        raise typer.Exit(1)


def _f(v: float, fmt: str) -> str:
    return "-" if not math.isfinite(v) else format(v, fmt)


def _effects(fiber) -> str:
    """The active effects as ``; effects near_wall = 1, friction = 0.2`` (empty when none)."""
    on = {k: v for k, v in fiber.effects.items() if v != 0}
    return "; effects " + ", ".join(f"{k} = {v:g}" for k, v in on.items()) if on else ""


def _echo_channel(res, fiber, reversible: bool, back: float) -> None:
    st = res.start
    typer.echo(
        f"start: theta0 = {st.theta0:g}°, y0/h = {st.y0:g}, L/l_obs = {st.length:g} "
        f"({res.n_beads} beads), model {fiber.model} ({fiber.resolved_integrator}), "
        f"pillar {fiber.contact.pillar}{_effects(fiber)}"
    )
    if res.status != "ok":
        typer.echo(f"status: failed ({res.reason})")
    typer.echo(f"class: {res.cls or '-'}")
    if math.isfinite(res.delta):
        typer.echo(f"delta: {res.delta:.4f} h_obs (lateral displacement y_f - y0)")
    else:
        typer.echo("delta: none (defined only for a fiber that passes the pillar)")
    if res.contact:
        typer.echo(
            f"contact: yes, theta_c = {_f(res.theta_c, '.2f')}°, y_c/h = {_f(res.y_c, '.3f')}, "
            f"t_contact = {_f(res.t_contact, '.3f')} s"
        )
    else:
        typer.echo("contact: no")
    passed = (
        f"t_pass: {res.t_pass:.3f} s"
        if math.isfinite(res.t_pass)
        else "t_pass: never (the centre of mass did not pass the pillar)"
    )
    typer.echo(
        f"{passed}; final x = {_f(res.x_f, '.1f')} µm, "
        f"y = {_f(res.y_f, '.1f')} µm, theta = {_f(res.theta_f, '.1f')}°; "
        f"min clearance {_f(res.min_clearance, '.3f')} µm"
    )


def _echo_array(res, array, fiber) -> None:
    """What one fiber did in a pillar array, in the array's terms."""
    st = res.start
    typer.echo(
        f"start: theta0 = {st.theta0:g}°, y0 = {st.y0:g} of period_y (in the gap before row "
        f"0), L = {st.length:g} µm ({res.n_beads} beads), "
        f"model {fiber.model} ({fiber.resolved_integrator}){_effects(fiber)}"
    )
    typer.echo(
        f"array: periods {array.period_x:g} x {array.period_y:g} µm, shift {array.shift:g} "
        f"(each row {array.lateral_shift:g} µm higher, tilt {array.tilt_deg:.2f}°), "
        f"{fiber.array_rows} rows"
    )
    if res.status != "ok":
        typer.echo(f"status: failed ({res.reason})")
    typer.echo(
        f"mode: {res.mode or '-'}; rows crossed: {res.rows if res.rows is not None else '-'}"
    )
    typer.echo(
        f"shift per row: {_f(res.shift_per_row, '.2f')} µm, f = {_f(res.fraction, '.3f')} of "
        f"the tilt's {array.lateral_shift:g} µm (1: follows the tilt, 0: the flow); migration "
        f"angle {_f(res.migration_angle, '.2f')}° (tilt {array.tilt_deg:.2f}°)"
    )
    typer.echo(
        f"contacts: {res.contacts} episodes, {res.wraps} wraps, {res.bridging} steps touching "
        f"two pillars, {_f(res.time_on_pillars, '.2f')} s on pillars; min clearance "
        f"{_f(res.min_clearance, '.3f')} µm; ended at t = {_f(res.t_end, '.2f')} s"
    )
