"""The sweep commands: ``run``, ``classify``, ``plot-phase`` and ``check``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from fibersweep.analysis.classify import RULES
from fibersweep.api import SweepBar
from fibersweep.cli._app import (
    FIGURES,
    SWEEP,
    ConfigArg,
    Overrides,
    Verbose,
    Workers,
    _errors,
    _interruptible,
    _setup_logging,
    app,
    choices,
)
from fibersweep.errors import InputError, Terminated
from fibersweep.plots import FORMATS
from fibersweep.sweep.executors import EXECUTORS

#: Seconds above which making kernels ready means they were compiled, not loaded.
COMPILED_S = 5.0

#: Default of the classify thresholds: the sweep's own.
SWEEP_CLASSIFY = "the sweep's fiber.classify"

# Option choices, from the registries.
Rule = choices("Rule", RULES)
Executor = choices("Executor", EXECUTORS)
Format = choices("Format", FORMATS)


def _fmt_s(s: float | None) -> str:
    if s is None:
        return "unknown"
    if s < 120:
        return f"{s:.0f} s"
    return f"{s / 60:.1f} min" if s < 7200 else f"{s / 3600:.1f} h"


@app.command(rich_help_panel=SWEEP)
def run(
    config: ConfigArg,
    overrides: Overrides = None,
    workers: Workers = None,
    resume: Annotated[
        bool,
        typer.Option(
            "--resume/--no-resume", help="Keep finished runs; --no-resume moves them aside."
        ),
    ] = True,
    retry_failed: Annotated[
        bool, typer.Option("--retry-failed", help="Re-run only the failed runs.")
    ] = False,
    dry_run: Annotated[
        bool, typer.Option("--dry-run", help="Show what is done and to do, and a time estimate.")
    ] = False,
    executor: Annotated[
        Executor | None, typer.Option(help="Where runs execute.", show_default="run.executor")
    ] = None,
    scheduler: Annotated[
        str | None, typer.Option(help="Dask scheduler tcp://HOST:PORT (implies dask).")
    ] = None,
    output: Annotated[
        Path | None,
        typer.Option("--output", "-o", help="Output directory.", show_default="run.output"),
    ] = None,
    max_points: Annotated[
        int | None,
        typer.Option(help="Allow sweeps up to this many points.", show_default="run.max_points"),
    ] = None,
    verbose: Verbose = False,
) -> None:
    """Run a sweep: flow field (cached), fiber runs across workers, Parquet results."""
    from fibersweep import api

    _setup_logging(verbose)
    with _interruptible(), _errors():
        how = dict(
            output=output, workers=workers, scheduler=scheduler, resume=resume,
            retry_failed=retry_failed, max_points=max_points,
            executor=executor.value if executor is not None else None,
        )  # fmt: skip
        if dry_run:
            _print_estimate(api.estimate(config, *(overrides or []), **how))
            return
        shown = _Shown()
        try:
            res = api.run(config, *(overrides or []), progress=shown, **how)
        except KeyboardInterrupt as exc:
            if shown.config is None:  # stopped before the sweep started
                raise
            why = "terminated (SIGTERM)" if isinstance(exc, Terminated) else "interrupted"
            typer.secho(
                f"{why}: {shown.saved} runs of this call are saved in "
                f"{shown.config.run.output}; run the same command again to resume",
                err=True,
                fg=typer.colors.YELLOW,
            )
            raise typer.Exit(143 if isinstance(exc, Terminated) else 130) from None
        _print_run(res)
    if res.failed:
        raise typer.Exit(1)


class _Shown(SweepBar):
    """The sweep's bar, with the lines the command prints before and between its rounds."""

    def start(self, config, fields) -> None:
        super().start(config, fields)
        line, cached = _fields_line(fields)
        typer.echo(line if cached else f"{line}; computing into {config.run.cache_dir} ...")

    def plan(self, plan) -> None:
        _print_plan(plan)
        refine = self.config.sweep.refine
        if refine is not None and plan.todo:
            typer.echo(
                f"  the bar counts these {len(plan.todo)} runs; the refinement then adds up to "
                f"{refine.max_runs} more in up to {refine.rounds} rounds, each with its own bar"
            )
        super().plan(plan)

    def round(self, number: int, plan) -> None:
        self.close()
        typer.echo(
            f"refinement round {number}: {len(plan.todo)} runs to do "
            f"({len(plan.tasks)} points in the sweep so far)"
        )
        super().round(number, plan)


def _print_run(res) -> None:
    """What a sweep did (:class:`fibersweep.api.SweepRun`)."""
    if res.ran:
        typer.echo(
            f"ran {res.ran} runs in {_fmt_s(res.wall_s)} ({res.rate:.2f} runs/s) -> {res.path}"
        )
    else:
        typer.echo(f"nothing to run: every run of the sweep is in {res.path}")
    typer.echo(
        "table: " + ", ".join(f"{k} {v}" for k, v in res.counts.items()) + f", failed {res.failed}"
    )
    if res.refinement is not None:
        typer.echo(_refinement_line(res.refinement, res.config.sweep.refine))
    for message in res.warnings:
        typer.secho(f"warning: {message}", err=True, fg=typer.colors.YELLOW)
    for line in res.failures[:10]:
        typer.secho(f"  failed {line}", err=True, fg=typer.colors.RED)
    if res.failed:
        typer.secho(
            f"{res.failed} runs failed; re-run them with --retry-failed",
            err=True,
            fg=typer.colors.RED,
        )


def _print_plan(plan) -> None:
    typer.echo(
        f"{plan.out}: {len(plan.tasks)} runs in the sweep; done {plan.done_ok} ok, "
        f"{plan.done_failed} failed; to do now {len(plan.todo)}"
        + (f"; {plan.kept_other} rows from earlier sweeps kept" if plan.kept_other else "")
    )
    if len(plan.settings) > 1 or plan.columns:
        todo = {}
        for t in plan.todo:
            todo[t.settings] = todo.get(t.settings, 0) + 1
        keys = ", ".join(plan.columns)
        typer.echo(f"  {len(plan.settings)} setting combinations of {keys}:")
        shown = 12
        for st in plan.settings[:shown]:
            typer.echo(f"    {st.combination.label or '(base)'}: to do {todo.get(st.id, 0)}")
        if len(plan.settings) > shown:
            rest = sum(todo.get(st.id, 0) for st in plan.settings[shown:])
            typer.echo(f"    ... {len(plan.settings) - shown} more combinations: to do {rest}")
    if plan.fresh:
        typer.echo("  --no-resume: existing results will be moved to a previous-* folder")
    for note in plan.notes:
        typer.secho(f"  note: {note}", fg=typer.colors.YELLOW)


def _fields_line(fields) -> tuple[str, bool]:
    """One line on the sweep's flow fields (key -> (settings, cached)), and whether all
    are cached."""
    missing = [k for k, (_, cached) in fields.items() if not cached]
    if len(fields) == 1:
        key, (flow, cached) = next(iter(fields.items()))
        return f"flow field {key} ({flow.dx:g} µm grid): " + (
            "cached" if cached else "NOT cached (it is computed first)"
        ), cached
    return (
        f"{len(fields)} flow fields ({len(fields) - len(missing)} cached"
        + (f", {len(missing)} computed first, once each" if missing else "")
        + ")"
    ), not missing


def _print_estimate(est) -> None:
    """What a sweep would do and how long (:class:`fibersweep.api.SweepEstimate`)."""
    cfg, plan = est.config, est.plan
    _print_plan(plan)
    how = {
        "finished": "mean of the finished runs",
        "timed": _timed_on(est) + " of this sweep",
        "probe": _timed_on(est) + " on a probe field",
    }.get(est.timing, "")
    line, _ = _fields_line(est.fields)
    if est.probes:
        typer.echo(f"  {_probe_note(est)}")
    if est.seconds is not None and est.flow_s:
        how += f"; flow fields {_fmt_s(est.flow_s)} included"
    if est.free_workers < est.workers and est.seconds is not None:
        how += (f"; load average {est.load:.1f} on {est.cpus} cores: the workers share them, "
                f"counted as {est.free_workers}")  # fmt: skip
    typer.echo(
        f"  {line}; estimate {_fmt_s(est.seconds)} on {est.workers} "
        + ("worker" if est.workers == 1 else "workers")
        + (f" ({est.per_run_s:.2f} s per run, {how})" if est.per_run_s is not None else "")
        + (" for the runs known so far" if cfg.sweep.refine is not None else "")
    )
    if cfg.sweep.refine is not None:
        _dry_run_refinement(cfg, plan, est.round, est.refinement)


def _timed_on(est) -> str:
    """How many runs the estimate timed (in a pillar array, spread over the lengths)."""
    n = est.timed_runs
    return "timed on one run" if n == 1 else f"mean of {n} runs timed across the lengths"


def _dry_run_refinement(cfg, plan, rnd: int, info) -> None:
    """What is known of the refinement rounds: those the stored runs determine."""
    refine = cfg.sweep.refine
    head = (
        f"  refinement ({', '.join(refine.axes)}): up to {refine.max_runs} more runs in up to "
        f"{refine.rounds} rounds; "
    )
    if info is None:
        typer.echo(
            head + "the rounds are not yet known: each is chosen from the classes of the "
            "runs before it, once they have run"
        )
        return
    if plan.todo:
        typer.echo(
            head + f"round {rnd} is to do ({len(plan.todo)} runs above); later rounds are "
            "not yet known: they depend on its classes"
        )
        return
    done = _refinement_line(info, refine).removeprefix("refinement: ")
    typer.echo(head + "stored: " + done)


_STOPPED = {
    "located": "every boundary bracket is within tolerance",
    "stuck": "the others end at failed runs: --retry-failed re-runs them",
    "retry-failed": "--retry-failed runs no new point: a plain run continues the refinement",
    "interrupted": "interrupted: run the same command again to continue",
    "budget": "budget sweep.refine.max_runs spent",
    "rounds": "sweep.refine.rounds reached",
    "running": "more rounds to run",
    "unsaved": "results could not be written",
}


def _refinement_line(info: dict, refine) -> str:
    """One line on a refinement: rounds, runs, brackets located / open / stuck, why it stopped."""
    why = _STOPPED.get(info.get("stopped", ""), info.get("stopped", ""))
    line = (
        f"refinement: {info.get('rounds', 0)} rounds, {info.get('runs', 0)} of "
        f"{refine.max_runs} runs; boundary brackets: {info.get('located', 0)} located, "
        f"{info.get('open', 0)} open"
    )
    if info.get("stuck"):
        line += f", {info['stuck']} stuck (midpoint failed or not run)"
    return f"{line} ({why})"


def _probe_note(est) -> str:
    """A line on the fields not cached: the estimate of each solve, and the kernels that
    this dry run compiled."""
    from fibersweep.sweep.estimate import PROBE_STEPS

    notes = []
    for flow, e in est.probes:
        grids = " then ".join(f"{dx:g} µm ({cells / 1e6:.2g} M cells)" for dx, cells in e.grids)
        what = "unit cell" if flow.array is not None else "flow field"
        notes.append(
            f"{what} on {grids}: about {_fmt_s(e.flow_s)} "
            f"({e.mlups:.2g} MLUPS timed over {PROBE_STEPS} steps; typical step counts)"
        )
    note = notes[0] if len(notes) == 1 else f"{len(notes)} flow fields: {'; '.join(notes)}"
    # This dry run made every kernel the run needs ready: a first use compiled them (and
    # cached them on disk, so the run only loads them); say what that cost.
    ready = est.compile_s + est.warmup_s
    if ready > COMPILED_S:
        note += (
            f"; first use: this dry run compiled the kernels in {_fmt_s(ready)} (flow "
            f"{_fmt_s(est.compile_s)}, fiber {_fmt_s(est.warmup_s)}); cached now, the run "
            "loads them"
        )
    return note


@app.command(rich_help_panel=SWEEP)
def classify(
    results: Annotated[Path, typer.Argument(help="Output directory of a sweep.")],
    head_blocked_speed: Annotated[
        float | None,
        typer.Option(
            help="Head blocked below this fraction of U_center.", show_default=SWEEP_CLASSIFY
        ),
    ] = None,
    trap_time: Annotated[
        float | None,
        typer.Option(
            help="In contact and stopped this long [s] -> Trapping.", show_default=SWEEP_CLASSIFY
        ),
    ] = None,
    trap_speed: Annotated[
        float | None,
        typer.Option(
            help="'Stopped': COM speed below this fraction of U_center.",
            show_default=SWEEP_CLASSIFY,
        ),
    ] = None,
    rule: Annotated[
        Rule | None,
        typer.Option(
            help="Pole-vaulting rule: switch (default), head-speed (the source's), pivot, corner.",
            show_default=SWEEP_CLASSIFY,
        ),
    ] = None,
    pivot_fraction: Annotated[
        float | None,
        typer.Option(
            help="pivot rule: head travel below this x L while turning.",
            show_default=SWEEP_CLASSIFY,
        ),
    ] = None,
    config: Annotated[
        Path | None, typer.Option("--config", "-c", help="Take thresholds from this config.")
    ] = None,
    verbose: Verbose = False,
) -> None:
    """Re-classify stored trajectories with new thresholds or rule (no simulation).

    The runs table gets one class column per rule (class_head_speed, class_pivot,
    class_switch); 'class' is the chosen rule's. A pillar array's runs get their
    modes re-derived with the trap rule (--trap-time, --trap-speed).
    """
    from fibersweep import api

    _setup_logging(verbose)
    with _errors():
        res = api.classify(
            results, config, head_blocked_speed=head_blocked_speed, trap_time=trap_time,
            trap_speed=trap_speed, rule=rule.value if rule is not None else None,
            pivot_fraction=pivot_fraction,
        )  # fmt: skip
    th = res.thresholds
    if res.array:  # a pillar array: modes, of which only the trap rule is here
        typer.echo(
            f"re-derived the modes of {res.n_runs} pillar-array runs ({res.n_changed} changed) "
            f"with the trap rule trap_time = {th.trap_time:g} s, trap_speed = "
            f"{th.trap_speed:g} U_center (the other mode thresholds are sort-report's "
            "--zigzag-max and --displacement-min)"
        )
        if res.beyond_simulated:
            typer.echo(
                f"note: runs stopped by their own trap rule (trap_time = "
                f"{res.simulated_trap_time:g} s) end there, so a trap_time longer than that "
                "cannot tell whether they would have moved on; run them again with "
                "fiber.classify.trap_time to know"
            )
    else:
        typer.echo(f"re-classified {res.n_runs} runs ({res.n_changed} changed) with {th}")
    typer.echo(res.counts.to_string(index=False))
    typer.echo(f"wrote {res.counts_path}")
    for w in res.warnings:
        typer.secho(f"warning: {w}", err=True, fg=typer.colors.YELLOW)


def _warn_mixed_rules(runs, results: Path) -> None:
    """Warn on stderr when the class column of ``results`` mixes pole-vaulting rules."""
    from fibersweep.sweep.rules import mixed_rules_message

    message = mixed_rules_message(runs, results)
    if message:
        typer.secho(f"warning: {message}", err=True, fg=typer.colors.YELLOW)


@app.command("plot-phase", rich_help_panel=FIGURES)
def plot_phase(
    results: Annotated[Path, typer.Argument(help="Output directory of a sweep.")],
    out: Annotated[
        Path | None,
        typer.Option(
            "--output", "-o", "--out", help="Figure folder.", show_default="RESULTS/figures"
        ),
    ] = None,
    fmt: Annotated[Format, typer.Option("--format", help="Figure format.")] = "png",
    col: Annotated[
        str | None,
        typer.Option(
            "--col",
            help="Panel columns by this column, e.g. a swept key fiber.effects.friction.",
            show_default="the first swept key that varies, else length",
        ),
    ] = None,
    row: Annotated[
        str | None,
        typer.Option(
            "--row", help="Panel rows by this column.", show_default="the next key that varies"
        ),
    ] = None,
    verbose: Verbose = False,
) -> None:
    """Phase diagram, δ map, contact map and δ distribution of a sweep past one pillar.

    A pillar array's runs have modes, not the channel's classes: exit 2 naming
    sort-report, plot-fractions and explore.

    A folder of several settings gets one panel per value of the swept keys that
    vary (--col, --row), and one file per value of any further one.
    """
    _setup_logging(verbose)
    with _errors():
        from fibersweep.plots.phase import plot_all
        from fibersweep.sweep.manifest import read_manifest
        from fibersweep.sweep.store import read_runs

        runs = read_runs(results)
        if runs.empty:
            raise InputError(f"{results}: no runs to plot (expected {results}/runs/part-*.parquet)")
        if "mode" in runs and runs["mode"].notna().any():
            raise InputError(
                f"plot-phase: {results} holds pillar-array runs; the phase diagram shows the "
                "channel's classes (Below, Above, Pole-vaulting, Trapping) past one pillar, "
                "which array runs do not have. For an array: fibersweep sort-report RESULTS "
                "(f and migration against length, critical lengths, outlets), fibersweep "
                "plot-fractions RESULTS --by length (modes against a setting), fibersweep "
                "explore RESULTS"
            )
        man = read_manifest(results) or {}
        sep = man.get("separatrix")
        combos = man.get("combinations") or {}
        if len({e.get("flow_key") for e in combos.values()}) > 1:  # one per flow field
            sep = {sid: e.get("separatrix") for sid, e in combos.items()}
        paths = plot_all(
            runs, out or results / "figures", Format(fmt).value, separatrix=sep, col=col, row=row
        )
    _warn_mixed_rules(runs, results)
    for p in paths:
        typer.echo(f"wrote {p}")


@app.command(rich_help_panel=SWEEP)
def check(
    results: Annotated[Path, typer.Argument(help="Output directory of a sweep.")],
    verbose: Verbose = False,
) -> None:
    """Report the state of an output folder (reads every part; changes nothing).

    Exit code 0 when every part is readable and no run misses its data, 1 otherwise.
    """
    _setup_logging(verbose)
    with _errors():
        from fibersweep.sweep.check import check_folder

        report = check_folder(results)
    for line in report.lines():
        typer.echo(line)
    if not report.healthy:
        raise typer.Exit(1)
