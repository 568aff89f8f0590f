"""The sweep commands: ``run``, ``classify``, ``plot-phase`` and ``check``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from fibersweep.analysis.classify import RULES
from fibersweep.cli._app import (
    FIGURES,
    SWEEP,
    ConfigArg,
    Overrides,
    Verbose,
    Workers,
    _errors,
    _interruptible,
    _load,
    _setup_logging,
    app,
    choices,
    flow_progress,
)
from fibersweep.errors import InputError, Terminated
from fibersweep.plots import FORMATS
from fibersweep.sweep.executors import EXECUTORS
from fibersweep.sweep.starts import PHYSICS

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


def _with_run_overrides(cfg, **kw):
    """Config with ``run`` options from the command line, validated like the file."""
    from fibersweep.config import parse_config

    over = {k: v for k, v in kw.items() if v is not None}
    if not over:
        return cfg
    data = cfg.model_dump(mode="json")
    data["run"].update(over)
    return parse_config(data, source="command line", physics=PHYSICS)


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
    _setup_logging(verbose)
    with _interruptible(), _errors():
        cfg = _load(config, overrides, max_points=max_points)
        if scheduler and executor is None:
            executor = Executor("dask")
        cfg = _with_run_overrides(
            cfg,
            workers=workers,
            executor=executor.value if executor is not None else None,
            scheduler=scheduler,
            output=None if output is None else str(output),
        )
        if dry_run:
            _dry_run(cfg, resume, retry_failed)
            return
        with flow_progress():  # a bar over the solver's steps if a field is computed
            failed = _run(cfg, resume, retry_failed, overrides or [])
    if failed:
        raise typer.Exit(1)


def _print_plan(plan, workers: int) -> None:
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


def _fields_line(cfg) -> tuple[str, bool]:
    """One line on the sweep's flow fields, and whether all are cached."""
    from fibersweep.sweep.fields import flow_keys_for

    fields = flow_keys_for(cfg)
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


def _dry_run(cfg, resume: bool, retry_failed: bool) -> None:
    from dataclasses import replace

    from fibersweep.sweep.estimate import busy_cores, estimate_run_s, free_workers
    from fibersweep.sweep.fields import flow_keys_for
    from fibersweep.sweep.plan import plan_sweep

    load, cpus = busy_cores()  # before the probes below add to it
    plan = plan_sweep(cfg, None, resume=resume, retry_failed=retry_failed)
    extra, rnd, info = [], 0, None
    if cfg.sweep.refine is not None and not plan.fresh:
        from fibersweep.sweep.refine import stored_rounds
        from fibersweep.sweep.store import read_runs

        stored = read_runs(plan.out)
        extra, rnd, info = stored_rounds(cfg.sweep.refine, plan.settings, plan.tasks, stored)
        if extra:
            plan = plan_sweep(cfg, None, retry_failed=retry_failed, extra=extra)
    _print_plan(plan, cfg.run.workers)
    per_run = plan.mean_run_s
    how = "mean of the finished runs"
    line, _ = _fields_line(cfg)
    fields = flow_keys_for(cfg)
    flow_s = 0.0
    if plan.todo:
        task = plan.todo[len(plan.todo) // 2]
        cached = fields[task.flow_key][1]
        missing = [flow for flow, is_cached in fields.values() if not is_cached]
        if per_run is None and cached:
            per_run = estimate_run_s(cfg, plan.todo)
            how = _timed_on(cfg, plan.todo) + " of this sweep"
        if missing:
            flow_s, per_run_timed, note = _estimate_fields(cfg, plan.todo, missing)
            typer.echo(f"  {note}")
            if per_run is None:
                per_run, how = per_run_timed, _timed_on(cfg, plan.todo) + " on a probe field"
    # same rule as SweepPlan.estimate_s: no more workers busy than runs to do; on a busy
    # machine only as many as the free cores hold
    remote = cfg.run.scheduler is not None  # a cluster's workers: this machine's load is not theirs
    free = cfg.run.workers if remote else free_workers(cfg.run.workers, load, cpus)
    est = None if per_run is None else replace(plan, mean_run_s=per_run).estimate_s(free)
    if est is not None and flow_s:
        est += flow_s
        how += f"; flow fields {_fmt_s(flow_s)} included"
    if free < cfg.run.workers and est is not None:
        how += (f"; load average {load:.1f} on {cpus} cores: the workers share them, "
                f"counted as {free}")  # fmt: skip
    typer.echo(
        f"  {line}; estimate {_fmt_s(est)} on {cfg.run.workers} "
        + ("worker" if cfg.run.workers == 1 else "workers")
        + (f" ({per_run:.2f} s per run, {how})" if per_run is not None else "")
        + (" for the runs known so far" if cfg.sweep.refine is not None else "")
    )
    if cfg.sweep.refine is not None:
        _dry_run_refinement(cfg, plan, extra, rnd, info)


def _timed_on(cfg, todo) -> str:
    """How many runs the estimate timed (in a pillar array, spread over the lengths)."""
    from fibersweep.sweep.estimate import sample_tasks

    if cfg.flow.array is None:
        return "timed on one run"
    n = len(sample_tasks(todo))
    return "timed on one run" if n == 1 else f"mean of {n} runs timed across the lengths"


def _dry_run_refinement(cfg, plan, extra, rnd: int, info) -> None:
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


def _estimate_fields(cfg, todo, missing) -> tuple[float, float, str]:
    """Seconds for the fields not cached, seconds per run, and a line on how.

    The runs are timed on the probe field of the first field not cached: its middle
    run, or in a pillar array runs spread across the lengths (their cost depends on it).
    """
    from fibersweep.fiber.result import FiberStart
    from fibersweep.sweep.estimate import PROBE_STEPS, estimate_uncached, sample_tasks
    from fibersweep.sweep.plan import sweep_settings

    task = todo[len(todo) // 2]
    sub = next((s.config for s in sweep_settings(cfg) if s.id == task.settings), cfg)
    picks = sample_tasks(todo) if cfg.flow.array is not None else [task]
    start = [FiberStart(theta0=t.theta0, y0=t.y0, length=t.length) for t in picks]
    total = 0.0
    per_run = None
    notes = []
    compile_s = warmup_s = 0.0
    for flow in missing:
        e = estimate_uncached(flow, sub.fiber, start)
        total += e.flow_s
        per_run = e.run_s if per_run is None else per_run
        compile_s = max(compile_s, e.compile_s)
        warmup_s = max(warmup_s, e.warmup_s)
        grids = " then ".join(f"{dx:g} µm ({cells / 1e6:.2g} M cells)" for dx, cells in e.grids)
        what = "unit cell" if flow.array is not None else "flow field"
        notes.append(
            f"{what} on {grids}: about {_fmt_s(e.flow_s)} "
            f"({e.mlups:.2g} MLUPS timed over {PROBE_STEPS} steps; typical step counts)"
        )
        start = start[:1]  # the runs are timed once, on the first probe field
    note = notes[0] if len(notes) == 1 else f"{len(notes)} flow fields: {'; '.join(notes)}"
    # This dry run made every kernel the run needs ready: a first use compiled them (and
    # cached them on disk, so the run only loads them); say what that cost.
    ready = compile_s + warmup_s
    if ready > COMPILED_S:
        note += (
            f"; first use: this dry run compiled the kernels in {_fmt_s(ready)} (flow "
            f"{_fmt_s(compile_s)}, fiber {_fmt_s(warmup_s)}); cached now, the run loads them"
        )
    return total, per_run, note


def _run(cfg, resume: bool, retry_failed: bool, overrides: list[str] | None = None) -> bool:
    """Run the sweep with a progress bar; True if any run of the table failed."""
    from collections import Counter

    from fibersweep.progressbar import WarmingBar
    from fibersweep.sweep.runner import run_sweep

    bar = None
    counts: Counter = Counter()
    short = {"Below": "B", "Above": "A", "Pole-vaulting": "PV", "Trapping": "T", "failed": "fail",
             "zigzag": "Z", "displacement": "D", "wrap-and-jump": "WJ", "trapped": "T",
             "mixed": "M"}  # fmt: skip

    def new_bar(n: int):
        # On a terminal: a live bar; into a log file: a line every 10 s, not thousands. The
        # first run of each worker includes its start-up (kernels compiled on first use):
        # the rate and the estimate start after them.
        return WarmingBar(
            n,
            warm=min(cfg.run.workers, n),
            note="workers starting (the first runs also compile the kernels)",
            unit="run",
            smoothing=0.1,
        )

    def on_plan(plan) -> None:
        nonlocal bar
        _print_plan(plan, cfg.run.workers)
        if cfg.sweep.refine is not None and plan.todo:
            typer.echo(
                f"  the bar counts these {len(plan.todo)} runs; the refinement then adds up to "
                f"{cfg.sweep.refine.max_runs} more in up to {cfg.sweep.refine.rounds} rounds, "
                "each with its own bar"
            )
        if not plan.todo:
            return
        bar = new_bar(len(plan.todo))

    def progress(row) -> None:
        label = row.get("mode") or row["class"]  # a pillar array's runs: the mode
        counts[label if row["status"] == "ok" else "failed"] += 1
        if bar is not None:
            shown = [k for k in short if counts[k]] + [k for k in counts if k not in short]
            bar.set_postfix_str(
                " ".join(f"{short.get(k, k or '?')}={counts[k]}" for k in shown), refresh=False
            )
            bar.update(1)

    def on_round(rnd: int, plan) -> None:
        nonlocal bar
        if bar is not None:
            bar.close()
            bar = None
        typer.echo(
            f"refinement round {rnd}: {len(plan.todo)} runs to do "
            f"({len(plan.tasks)} points in the sweep so far)"
        )
        if plan.todo:
            bar = new_bar(len(plan.todo))

    line, cached = _fields_line(cfg)
    typer.echo(line if cached else f"{line}; computing into {cfg.run.cache_dir} ...")
    try:
        summary = run_sweep(
            cfg, resume=resume, retry_failed=retry_failed, progress=progress, on_plan=on_plan,
            overrides=overrides, on_round=on_round,
        )  # fmt: skip
    except KeyboardInterrupt as exc:
        if bar is not None:
            bar.close()
        why = "terminated (SIGTERM)" if isinstance(exc, Terminated) else "interrupted"
        typer.secho(
            f"{why}: {sum(counts.values())} runs of this call are saved in "
            f"{cfg.run.output}; run the same command again to resume",
            err=True,
            fg=typer.colors.YELLOW,
        )
        raise typer.Exit(143 if isinstance(exc, Terminated) else 130) from None
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
    if summary.refinement is not None:
        typer.echo(_refinement_line(summary.refinement, cfg.sweep.refine))
    if summary.ran:  # rows added under this config's rule to a folder labelled by another
        from fibersweep.sweep.store import read_runs

        _warn_mixed_rules(read_runs(summary.out), summary.out)
    for line in summary.failures[:10]:
        typer.secho(f"  failed {line}", err=True, fg=typer.colors.RED)
    if summary.failed:
        typer.secho(
            f"{summary.failed} runs failed; re-run them with --retry-failed",
            err=True,
            fg=typer.colors.RED,
        )
    return summary.failed > 0


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
    _setup_logging(verbose)
    with _errors():
        from fibersweep.sweep.manifest import read_manifest
        from fibersweep.sweep.reclassify import reclassify, thresholds_for

        base = _load(config).fiber.classify if config is not None else None
        man = read_manifest(results) or {}
        run_cfg = man.get("config") or {}
        array = (run_cfg.get("flow") or {}).get("array") is not None
        channel_only = {"--rule": rule, "--pivot-fraction": pivot_fraction,
                        "--head-blocked-speed": head_blocked_speed}  # fmt: skip
        given = [k for k, v in channel_only.items() if v is not None]
        if array and given:
            raise InputError(
                f"{', '.join(given)}: pillar-array runs have modes, not a channel's classes; "
                "classify re-derives their trap rule (--trap-time, --trap-speed), and "
                "sort-report's --zigzag-max and --displacement-min set the other modes"
            )
        th = thresholds_for(
            results,
            base,
            head_blocked_speed=head_blocked_speed,
            trap_time=trap_time,
            trap_speed=trap_speed,
            rule=rule.value if rule is not None else None,
            pivot_fraction=pivot_fraction,
        )
        res = reclassify(results, th)
    if "mode" in res.counts.columns:  # a pillar array: modes, of which only the trap rule is here
        typer.echo(
            f"re-derived the modes of {res.n_runs} pillar-array runs ({res.n_changed} changed) "
            f"with the trap rule trap_time = {th.trap_time:g} s, trap_speed = "
            f"{th.trap_speed:g} U_center (the other mode thresholds are sort-report's "
            "--zigzag-max and --displacement-min)"
        )
        # the thresholds the runs were simulated with (a re-labelling rewrites the config's)
        simulated = man.get("simulated_classify") or (run_cfg.get("fiber") or {}).get("classify")
        ran = (simulated or {}).get("trap_time")
        counts = res.counts
        trapped = int(counts.loc[counts["mode"] == "trapped", "runs"].sum())
        if ran is not None and th.trap_time > float(ran) and trapped:
            typer.echo(
                f"note: runs stopped by their own trap rule (trap_time = {float(ran):g} s) "
                f"end there, so a trap_time longer than that cannot tell whether they would "
                "have moved on; run them again with fiber.classify.trap_time to know"
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
