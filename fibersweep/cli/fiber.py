"""The ``simulate`` command (issue 3): one fiber past the pillar."""

from __future__ import annotations

import typing
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
    choices,
    flow_progress,
)
from fibersweep.fiber.settings import LEGACY_MODELS, FiberSettings

# the models FiberSettings accepts (the model registry matches them, tested), and former names
Model = choices(
    "Model", (*typing.get_args(FiberSettings.model_fields["model"].annotation), *LEGACY_MODELS)
)


@app.command()
def simulate(
    config: ConfigArg,
    theta0: Annotated[float, typer.Option("--theta0", help="Start angle from +x [deg].")],
    y0: Annotated[float, typer.Option("--y0", help="Start lateral position y0/h_obs.")],
    length: Annotated[float, typer.Option("--length", help="Fiber length L/l_obs.")],
    plot: Annotated[
        Path | None,
        typer.Option("--plot", help="Write a chronophotograph (PNG/PDF/SVG by suffix)."),
    ] = None,
    model: Annotated[
        Model | None, typer.Option("--model", help="Fiber model.", show_default="fiber.model")
    ] = None,
    reversible: Annotated[
        bool, typer.Option("--reversible", help="Also reverse the flow and report the return.")
    ] = False,
    seed: Annotated[int | None, typer.Option("--seed", help="Seed of random effects.")] = None,
    verbose: Verbose = False,
    overrides: Overrides = None,
) -> None:
    """Run one fiber past the pillar and print its class, δ and contact data."""
    import math

    _setup_logging(verbose)
    with _errors():
        from fibersweep.fiber.result import FiberStart
        from fibersweep.fiber.run import simulate as run_one
        from fibersweep.fiber.run import simulate_reversible
        from fibersweep.flow.cache import get_flow_field

        # --model is the override fiber.model=..., validated with the others (its integrator)
        extra = [f"fiber.model={model.value}"] if model is not None else []
        cfg = _load(config, [*(overrides or []), *extra])
        fiber = cfg.fiber
        if plot is not None:
            rec = fiber.record.model_copy(
                update={"trajectories": True, "samples": max(fiber.record.samples, 2000)}
            )
            fiber = fiber.model_copy(update={"record": rec})
        with flow_progress():
            field, _ = get_flow_field(cfg.flow, cfg.run.cache_dir)
        start = FiberStart(theta0=theta0, y0=y0, length=length)
        back = math.nan
        if reversible:
            res, back = simulate_reversible(field, fiber, start, rng_seed=seed)
        else:
            res = run_one(field, fiber, start, rng_seed=seed)

        def f(v: float, fmt: str) -> str:
            return "-" if not math.isfinite(v) else format(v, fmt)

        typer.echo(
            f"start: theta0 = {theta0:g}°, y0/h = {y0:g}, L/l_obs = {length:g} "
            f"({res.n_beads} beads), model {fiber.model} ({fiber.resolved_integrator}), "
            f"pillar {fiber.contact.pillar}"
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
                f"contact: yes, theta_c = {f(res.theta_c, '.2f')}°, y_c/h = {f(res.y_c, '.3f')}, "
                f"t_contact = {f(res.t_contact, '.3f')} s"
            )
        else:
            typer.echo("contact: no")
        passed = (
            f"t_pass: {res.t_pass:.3f} s"
            if math.isfinite(res.t_pass)
            else "t_pass: never (the centre of mass did not pass the pillar)"
        )
        typer.echo(
            f"{passed}; final x = {f(res.x_f, '.1f')} µm, "
            f"y = {f(res.y_f, '.1f')} µm, theta = {f(res.theta_f, '.1f')}°; "
            f"min clearance {f(res.min_clearance, '.3f')} µm"
        )
        if math.isfinite(res.min_end_to_end):
            typer.echo(
                f"deformation: max curvature {res.max_curvature:.4f} 1/µm, min end-to-end "
                f"{res.min_end_to_end:.3f} of the contour, max tension "
                f"{res.max_tension:.3g} pN, max wrap {res.max_wrap:.1f}°"
            )
        typer.echo(f"steps: {res.n_steps} in {res.wall_time:.2f} s")
        if reversible:
            typer.echo(f"reversed flow: returns within {f(back, '.3g')} µm of the start")
        if plot is not None:
            from fibersweep.plots.chrono import chronophotograph

            typer.echo(f"wrote {chronophotograph(res, field.geometry, plot)}")
    if res.status != "ok":
        raise typer.Exit(1)
