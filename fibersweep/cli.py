"""The ``fibersweep`` command line (typer). The only module that prints or exits.

Library errors map to exit codes here: bad input (:class:`InputError`, including
config errors) exits 2, a failed computation (:class:`FibersweepError`) exits 1.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated

import typer

from fibersweep.errors import FibersweepError, InputError

app = typer.Typer(
    name="fibersweep",
    help="Parameter sweeps of rigid fibers meeting a triangular pillar in a shallow channel.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)

ConfigArg = Annotated[Path, typer.Argument(help="YAML config file.", show_default=False)]
Verbose = Annotated[bool, typer.Option("--verbose", "-v", help="Log progress details.")]


@contextmanager
def _errors() -> Iterator[None]:
    """Turn library errors into a message on stderr and an exit code."""
    try:
        yield
    except InputError as exc:
        typer.secho(f"error: {exc}", err=True, fg=typer.colors.RED)
        raise typer.Exit(2) from None
    except FibersweepError as exc:
        typer.secho(f"failed: {exc}", err=True, fg=typer.colors.RED)
        raise typer.Exit(1) from None


def _setup_logging(verbose: bool) -> None:
    logging.basicConfig(
        level=logging.INFO if verbose else logging.WARNING,
        format="%(asctime)s %(name)s %(levelname)s: %(message)s",
    )


def _load(path: Path):
    from fibersweep.config import load_config

    return load_config(path)


@app.callback()
def main() -> None:
    """fibersweep: LBM flow once, many fiber runs, phase diagrams."""


# --------------------------------------------------------------- flow command (issue 2)


@app.command()
def flow(
    config: ConfigArg,
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
        cfg = _load(config)
        from fibersweep.flow.cache import get_flow_field

        t0 = time.perf_counter()
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


# --------------------------------------------------------------- simulate command (issue 3)


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
        str | None, typer.Option("--model", help="rigid or bead-spring [config fiber.model].")
    ] = None,
    reversible: Annotated[
        bool, typer.Option("--reversible", help="Also reverse the flow and report the return.")
    ] = False,
    seed: Annotated[int | None, typer.Option("--seed", help="Seed of random effects.")] = None,
    verbose: Verbose = False,
) -> None:
    """Run one fiber past the pillar and print its class, δ and contact data."""
    import math

    _setup_logging(verbose)
    with _errors():
        from fibersweep.errors import InputError
        from fibersweep.fiber.result import FiberStart
        from fibersweep.fiber.run import simulate as run_one
        from fibersweep.fiber.run import simulate_reversible
        from fibersweep.flow.cache import get_flow_field

        cfg = _load(config)
        fiber = cfg.fiber
        if model is not None:
            if model not in ("rigid", "bead-spring"):
                raise InputError(f"--model: expected rigid or bead-spring, got {model!r}")
            fiber = fiber.model_copy(update={"model": model})
        if plot is not None:
            rec = fiber.record.model_copy(
                update={"trajectories": True, "samples": max(fiber.record.samples, 2000)}
            )
            fiber = fiber.model_copy(update={"record": rec})
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
            f"({res.n_beads} beads), model {fiber.model}, pillar {fiber.contact.pillar}"
        )
        if res.status != "ok":
            typer.echo(f"status: failed ({res.reason})")
        typer.echo(f"class: {res.cls or '-'}")
        typer.echo(f"delta: {f(res.delta, '.4f')}")
        if res.contact:
            typer.echo(
                f"contact: yes, theta_c = {f(res.theta_c, '.2f')}°, y_c/h = {f(res.y_c, '.3f')}, "
                f"t_contact = {f(res.t_contact, '.3f')} s"
            )
        else:
            typer.echo("contact: no")
        typer.echo(
            f"t_pass: {f(res.t_pass, '.3f')} s; final x = {f(res.x_f, '.1f')} µm, "
            f"y = {f(res.y_f, '.1f')} µm, theta = {f(res.theta_f, '.1f')}°; "
            f"min clearance {f(res.min_clearance, '.3f')} µm"
        )
        typer.echo(f"steps: {res.n_steps} in {res.wall_time:.2f} s")
        if reversible:
            typer.echo(f"reversed flow: returns within {f(back, '.3g')} µm of the start")
        if plot is not None:
            from fibersweep.plots.chrono import chronophotograph

            typer.echo(f"wrote {chronophotograph(res, field.geometry, plot)}")
    if res.status != "ok":
        raise typer.Exit(1)


# --------------------------------------------------------------- sweep commands (issue 4/5)


def _fmt_s(s: float | None) -> str:
    if s is None:
        return "unknown"
    if s < 120:
        return f"{s:.0f} s"
    return f"{s / 60:.1f} min" if s < 7200 else f"{s / 3600:.1f} h"


def _with_run_overrides(cfg, **kw):
    """Config with ``run`` options from the command line, validated like the file."""
    from fibersweep.config import parse_config

    over = {k: v for k, v in kw.items() if v is not None}
    if not over:
        return cfg
    data = cfg.model_dump(mode="json")
    data["run"].update(over)
    return parse_config(data, source="command line")


@app.command()
def run(
    config: ConfigArg,
    workers: Annotated[
        int | None, typer.Option(help="Worker processes (default: run.workers).")
    ] = None,
    resume: Annotated[
        bool, typer.Option("--resume/--no-resume", help="Keep finished runs (default).")
    ] = True,
    retry_failed: Annotated[
        bool, typer.Option("--retry-failed", help="Re-run only the failed runs.")
    ] = False,
    dry_run: Annotated[
        bool, typer.Option("--dry-run", help="Show what is done and to do, and a time estimate.")
    ] = False,
    executor: Annotated[
        str | None, typer.Option(help="local (process pool) or dask (default: run.executor).")
    ] = None,
    scheduler: Annotated[
        str | None, typer.Option(help="Dask scheduler tcp://HOST:PORT (implies dask).")
    ] = None,
    output: Annotated[
        Path | None, typer.Option("--output", "-o", help="Output directory (default: run.output).")
    ] = None,
    verbose: Verbose = False,
) -> None:
    """Run a sweep: flow field (cached), fiber runs across workers, Parquet results."""
    _setup_logging(verbose)
    with _errors():
        cfg = _load(config)
        if scheduler and executor is None:
            executor = "dask"
        cfg = _with_run_overrides(
            cfg,
            workers=workers,
            executor=executor,
            scheduler=scheduler,
            output=None if output is None else str(output),
        )
        if dry_run:
            _dry_run(cfg, resume, retry_failed)
            return
        failed = _run(cfg, resume, retry_failed)
    if failed:
        raise typer.Exit(1)


def _print_plan(plan, workers: int) -> None:
    typer.echo(
        f"{plan.out}: {len(plan.tasks)} runs in the sweep; done {plan.done_ok} ok, "
        f"{plan.done_failed} failed; to do now {len(plan.todo)}"
        + (f"; {plan.kept_other} rows from earlier sweeps kept" if plan.kept_other else "")
    )
    if plan.fresh:
        typer.echo("  --no-resume: existing results will be moved to a previous-* folder")
    for note in plan.notes:
        typer.secho(f"  note: {note}", fg=typer.colors.YELLOW)


def _dry_run(cfg, resume: bool, retry_failed: bool) -> None:
    from dataclasses import replace

    from fibersweep.sweep.plan import plan_sweep
    from fibersweep.sweep.runner import estimate_run_s, flow_key_for

    key, cached = flow_key_for(cfg)
    plan = plan_sweep(cfg, key, resume=resume, retry_failed=retry_failed)
    _print_plan(plan, cfg.run.workers)
    per_run = plan.mean_run_s
    how = "mean of the finished runs"
    if per_run is None and cached and plan.todo:
        per_run = estimate_run_s(cfg, plan.todo)
        how = "timed on one run of this sweep"
    # same rule as SweepPlan.estimate_s: no more workers busy than runs to do
    est = None if per_run is None else replace(plan, mean_run_s=per_run).estimate_s(cfg.run.workers)
    typer.echo(
        f"  flow field: {'cached' if cached else 'NOT cached (it is computed first)'}; "
        f"estimate {_fmt_s(est)} on {cfg.run.workers} workers"
        + (f" ({per_run:.2f} s per run, {how})" if per_run is not None else "")
    )


def _run(cfg, resume: bool, retry_failed: bool) -> bool:
    """Run the sweep with a progress bar; True if any run of the table failed."""
    from collections import Counter

    from tqdm import tqdm

    from fibersweep.sweep.runner import run_sweep

    bar = None
    counts: Counter = Counter()
    short = {"Below": "B", "Above": "A", "Pole-vaulting": "PV", "Trapping": "T", "failed": "fail"}

    def on_plan(plan) -> None:
        nonlocal bar
        _print_plan(plan, cfg.run.workers)
        if not plan.todo:
            return
        import sys

        # On a terminal: a live bar; into a log file: a line every 10 s, not thousands.
        every = 0.2 if sys.stderr.isatty() else 10.0
        bar = tqdm(
            total=len(plan.todo), unit="run", dynamic_ncols=True, smoothing=0.1, mininterval=every
        )

    def progress(row) -> None:
        counts[row["class"] if row["status"] == "ok" else "failed"] += 1
        if bar is not None:
            shown = [k for k in short if counts[k]] + [k for k in counts if k not in short]
            bar.set_postfix_str(
                " ".join(f"{short.get(k, k or '?')}={counts[k]}" for k in shown), refresh=False
            )
            bar.update(1)

    from fibersweep.sweep.runner import flow_key_for

    key, cached = flow_key_for(cfg)
    typer.echo(
        f"flow field {key} ({cfg.flow.dx:g} µm grid): "
        + ("cached" if cached else f"not cached, computing it once into {cfg.run.cache_dir} ...")
    )
    try:
        summary = run_sweep(
            cfg, resume=resume, retry_failed=retry_failed, progress=progress, on_plan=on_plan
        )
    except KeyboardInterrupt:
        if bar is not None:
            bar.close()
        typer.secho(
            f"interrupted: {sum(counts.values())} runs of this call are saved in "
            f"{cfg.run.output}; run the same command again to resume",
            err=True,
            fg=typer.colors.YELLOW,
        )
        raise typer.Exit(130) from None
    if bar is not None:
        bar.close()
    if summary.ran:
        rate = summary.ran / summary.wall_s if summary.wall_s > 0 else 0.0
        typer.echo(
            f"ran {summary.ran} runs in {_fmt_s(summary.wall_s)} ({rate:.2f} runs/s) "
            f"-> {summary.out}"
        )
    else:
        typer.echo(f"nothing to run: every run of the sweep is in {summary.out}")
    typer.echo(
        "table: "
        + ", ".join(f"{k} {v}" for k, v in summary.table_counts.items())
        + f", failed {summary.failed}"
    )
    for line in summary.failures[:10]:
        typer.secho(f"  failed {line}", err=True, fg=typer.colors.RED)
    if summary.failed:
        typer.secho(
            f"{summary.failed} runs failed; re-run them with --retry-failed",
            err=True,
            fg=typer.colors.RED,
        )
    return summary.failed > 0


@app.command()
def classify(
    results: Annotated[Path, typer.Argument(help="Output directory of a sweep.")],
    head_blocked_speed: Annotated[
        float | None, typer.Option(help="Head blocked below this fraction of U_center.")
    ] = None,
    trap_time: Annotated[
        float | None, typer.Option(help="In contact and stopped this long [s] -> Trapping.")
    ] = None,
    trap_speed: Annotated[
        float | None, typer.Option(help="'Stopped': COM speed below this fraction of U_center.")
    ] = None,
    config: Annotated[
        Path | None, typer.Option("--config", "-c", help="Take thresholds from this config.")
    ] = None,
    verbose: Verbose = False,
) -> None:
    """Re-classify stored trajectories with new thresholds (no simulation)."""
    _setup_logging(verbose)
    with _errors():
        from fibersweep.sweep.reclassify import reclassify, thresholds_for

        base = _load(config).fiber.classify if config is not None else None
        th = thresholds_for(
            results,
            base,
            head_blocked_speed=head_blocked_speed,
            trap_time=trap_time,
            trap_speed=trap_speed,
        )
        res = reclassify(results, th)
    typer.echo(f"re-classified {res.n_runs} runs ({res.n_changed} changed) with {th}")
    typer.echo(res.counts.to_string(index=False))
    typer.echo(f"wrote {res.counts_path}")
    for w in res.warnings:
        typer.secho(f"warning: {w}", err=True, fg=typer.colors.YELLOW)


@app.command("plot-phase")
def plot_phase(
    results: Annotated[Path, typer.Argument(help="Output directory of a sweep.")],
    out: Annotated[
        Path | None, typer.Option("--out", "-o", help="Figure folder (default: RESULTS/figures).")
    ] = None,
    fmt: Annotated[str, typer.Option("--format", help="png, pdf or svg.")] = "png",
    verbose: Verbose = False,
) -> None:
    """Phase diagram, δ map, contact map and δ distribution of a sweep."""
    _setup_logging(verbose)
    with _errors():
        from fibersweep.plots.phase import plot_all

        paths = plot_all(results, out, fmt)
    for p in paths:
        typer.echo(f"wrote {p}")


# --------------------------------------------------------- discrepancy commands (issue 6)


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
    workers: Annotated[int | None, typer.Option(help="Worker processes [run.workers].")] = None,
    verbose: Verbose = False,
) -> None:
    """Measured-like fibers from the model with hidden effects and measurement noise.

    Starts are uniform in the range of CONFIG's sweep axes; the truth (effects,
    noise, true starts) goes to a separate JSON file.
    """
    import json

    _setup_logging(verbose)
    with _errors():
        cfg = _load(config)
        from fibersweep.discrepancy.schema import write_table
        from fibersweep.discrepancy.synth import parse_effects, synthesize
        from fibersweep.flow.cache import get_flow_field

        effects = parse_effects(effect)
        field, _ = get_flow_field(cfg.flow, cfg.run.cache_dir)
        table, tr = synthesize(
            field, cfg.fiber, _sweep_box(cfg), n, effects, seed=seed,
            workers=workers or cfg.run.workers,
        )  # fmt: skip
        write_table(table, output)
        tpath = truth or output.with_suffix(".truth.json")
        from fibersweep.discrepancy.report import _atomic_write

        _atomic_write(tpath, json.dumps(tr, indent=2))
    typer.echo(f"wrote {output} ({len(table)} fibers) and {tpath}")
    if tr["failed"]:
        typer.secho(f"  {len(tr['failed'])} failed runs left out (listed in the truth)",
                    fg=typer.colors.YELLOW)  # fmt: skip


@app.command()
def discrepancy(
    measured: Annotated[Path, typer.Argument(help="Measured fibers (.parquet or .csv).")],
    config: ConfigArg,
    output: Annotated[Path, typer.Option("--output", "-o", help="Report folder.")] = Path("report"),
    budget: Annotated[int | None, typer.Option(help="Most simulations in total.")] = None,
    seed: Annotated[int, typer.Option(help="Random seed.")] = 0,
    copies: Annotated[int, typer.Option(help="Jittered baseline copies per fiber.")] = 4,
    effects: Annotated[
        str | None, typer.Option(help="Comma-separated effects to consider [all].")
    ] = None,
    alpha: Annotated[float, typer.Option(help="Family-wise error rate.")] = 0.05,
    trajectories: Annotated[
        Path | None, typer.Option(help="Optional measured trajectories table.")
    ] = None,
    workers: Annotated[int | None, typer.Option(help="Worker processes [run.workers].")] = None,
    verbose: Verbose = False,
) -> None:
    """Where the model disagrees with MEASURED, which effect explains it, and the gap left."""
    _setup_logging(verbose)
    with _errors():
        cfg = _load(config)
        from fibersweep.discrepancy.report import write_report
        from fibersweep.discrepancy.schema import load_measured
        from fibersweep.discrepancy.workflow import DiscrepancySettings, run_discrepancy
        from fibersweep.flow.cache import get_flow_field

        data = load_measured(measured, trajectories)
        settings = DiscrepancySettings(
            copies=copies, budget=budget, seed=seed, alpha=alpha,
            workers=workers or cfg.run.workers,
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


if __name__ == "__main__":  # pragma: no cover
    app()
