"""The discrepancy commands: ``synth``, ``discrepancy`` and ``power``.

Effects are given the same way everywhere: ``--effect NAME[=VALUE]``, repeatable
(``synth`` needs the value; ``discrepancy`` takes names only, it fits the values).
Candidates from any setting: ``--candidate KEY=LO..HI`` or ``KEY=VALUE``,
repeatable, for ``discrepancy`` and ``power``, and the config's
``discrepancy.candidates`` (:mod:`fibersweep.discrepancy.declared`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from fibersweep.cli._app import (
    MEASURED,
    ConfigArg,
    Overrides,
    Verbose,
    Workers,
    _errors,
    _load,
    _setup_logging,
    app,
)


def _is_array(cfg) -> bool:
    """A pillar-array config (``flow.array``): the array measured table and observables."""
    from fibersweep.api.compare import is_array

    return is_array(cfg)


def _sweep_box(cfg) -> dict[str, tuple[float, float]]:
    from fibersweep.api.compare import sweep_box

    return sweep_box(cfg)


@app.command(rich_help_panel=MEASURED)
def synth(
    config: ConfigArg,
    overrides: Overrides = None,
    effect: Annotated[
        list[str] | None,
        typer.Option(
            "--effect", metavar="NAME=VALUE", help="Hidden effect NAME=VALUE (repeatable)."
        ),
    ] = None,
    n: Annotated[int, typer.Option("--n", help="Number of fibers.")] = 100,
    seed: Annotated[int, typer.Option(help="Random seed.")] = 0,
    output: Annotated[
        Path, typer.Option("--output", "-o", help="Measured table (.parquet or .csv).")
    ] = Path("measured.parquet"),
    truth: Annotated[
        Path | None, typer.Option(help="Truth file [OUTPUT with suffix .truth.json].")
    ] = None,
    tracks: Annotated[
        Path | None,
        typer.Option(help="Also write the fibers' trajectories here (.parquet or .csv)."),
    ] = None,
    fps: Annotated[float, typer.Option(help="Frame rate of the trajectories [1/s].")] = 100.0,
    workers: Workers = None,
    verbose: Verbose = False,
) -> None:
    """Measured-like fibers past one pillar or through a pillar array, from the model,
    with hidden effects and measurement noise.

    Starts are uniform in the range of CONFIG's sweep axes; the truth (effects,
    noise, true starts) goes to a separate JSON file. With --tracks, the
    trajectories too (channel frame, per-frame noise 1 µm and 1.5°), for
    ``discrepancy --trajectories``. On a pillar array (flow.array) the table is an
    array measured table: starts, fraction, trapped, mode (and bend for a
    flexible fiber), each fiber through fiber.array_rows rows.
    """
    import json

    _setup_logging(verbose)
    with _errors():
        cfg = _load(config, overrides)
        if _is_array(cfg):
            _synth_array(cfg, effect, n, seed, output, truth, tracks, workers)
            return
        from fibersweep.discrepancy.schema import write_table
        from fibersweep.discrepancy.synth import parse_effects, synthesize_with_tracks
        from fibersweep.errors import InputError
        from fibersweep.flow.cache import get_flow_field

        effects = parse_effects(effect)
        if not fps > 0:
            raise InputError(f"--fps: must be > 0, got {fps}")
        if tracks is not None and tracks.suffix.lower() not in (".parquet", ".csv"):
            raise InputError(f"--tracks {tracks}: unknown table format; use .parquet or .csv")
        field, _ = get_flow_field(cfg.flow, cfg.run.cache_dir)
        table, track_table, tr = synthesize_with_tracks(
            field, cfg.fiber, _sweep_box(cfg), n, effects, seed=seed,
            workers=workers or cfg.run.workers, executor=cfg.run.executor,
            scheduler=cfg.run.scheduler, fps=fps if tracks is not None else None,
        )  # fmt: skip
        write_table(table, output)
        if tracks is not None and track_table is not None:
            write_table(track_table, tracks)
        tpath = truth or output.with_suffix(".truth.json")
        from fibersweep.atomic import atomic_write

        atomic_write(tpath, json.dumps(tr, indent=2))
    typer.echo(f"wrote {output} ({len(table)} fibers) and {tpath}")
    if tracks is not None:
        typer.echo(f"wrote {tracks} (trajectories, {fps:g} frames/s)")
    if tr["failed"]:
        typer.secho(f"  {len(tr['failed'])} failed runs left out (listed in the truth)",
                    fg=typer.colors.YELLOW)  # fmt: skip


def _synth_array(cfg, effect, n: int, seed: int, output: Path, truth: Path | None,
                 tracks: Path | None, workers: int | None) -> None:  # fmt: skip
    """``synth`` on a pillar array (:func:`fibersweep.discrepancy.array_synth.synthesize_array`)."""
    import json

    from fibersweep.api.compare import refuse_array
    from fibersweep.atomic import atomic_write
    from fibersweep.discrepancy.array_synth import synthesize_array
    from fibersweep.discrepancy.schema import write_table
    from fibersweep.discrepancy.synth import parse_effects
    from fibersweep.flow.cache import get_flow_field

    if tracks is not None:
        refuse_array(cfg, "synth --tracks", "writing trajectories in the channel frame")
    effects = parse_effects(effect)
    field, _ = get_flow_field(cfg.flow, cfg.run.cache_dir)
    table, tr = synthesize_array(
        field, cfg.fiber, _sweep_box(cfg), n, effects, seed=seed,
        workers=workers or cfg.run.workers, executor=cfg.run.executor,
        scheduler=cfg.run.scheduler,
    )  # fmt: skip
    write_table(table, output)
    tpath = truth or output.with_suffix(".truth.json")
    atomic_write(tpath, json.dumps(tr, indent=2))
    typer.echo(f"wrote {output} ({len(table)} fibers through {cfg.fiber.array_rows} rows; "
               "theta0 [deg], y0 [fraction of period_y], length [µm]) and "
               f"{tpath}")  # fmt: skip
    if tr["failed"]:
        typer.secho(f"  {len(tr['failed'])} failed runs left out (listed in the truth)",
                    fg=typer.colors.YELLOW)  # fmt: skip


def _effect_names(effect: list[str] | None) -> tuple[str, ...] | None:
    """Library subset from repeatable --effect NAME."""
    from fibersweep.errors import InputError

    names = []
    for item in effect or []:
        name, sep, _ = item.partition("=")
        if sep:
            raise InputError(
                f"--effect {item}: discrepancy fits the value; give the name only ({name})"
            )
        names.append(name.strip())
    return tuple(names) or None


CandidateOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--candidate",
        metavar="KEY=LO..HI|KEY=VALUE",
        help="A setting as a candidate explanation, repeatable: KEY=LO..HI (fitted, log "
        "scale over decades), KEY=VALUE (an alternative), or a switch with its parameter "
        "(fiber.model=bead-spring,fiber.young_modulus=1e4..3e7). The config's "
        "discrepancy.candidates are declared as well.",
    ),
]


def _declared(cfg, candidate: list[str] | None) -> tuple:
    """Declared candidates: the config's ``discrepancy.candidates``, then ``--candidate``."""
    from fibersweep.api.compare import declared_candidates

    return declared_candidates(cfg, candidate)


def _plan_lines(n: int, settings, starts=None) -> list[str]:
    """The plan before it runs: runs in all, what a costly (flexible) candidate adds, and
    (with the measured ``starts``) the follow-up stages and whether the budget holds them."""
    from fibersweep.discrepancy.settings import plan_budget, switch_cost

    plan = plan_budget(n, settings, settings.candidates_of())
    total = plan.total(n)
    lines = [f"plan: at most {total} simulations for {n} fibers"]
    extra = 0.0
    for c in settings.declared:
        model, f = switch_cost(c.switch)
        if f == 1.0:
            continue
        runs = plan.runs_of(n, c)
        extra += (f - 1.0) * runs
        lines.append(f"  {c.name} ({model}): up to {runs} of them, each about {f:g}x a rigid run")
    if extra:
        lines.append(
            f"  time about {(total + extra) / total:.2f}x that of the same plan on rigid runs"
        )
    if starts is not None:
        lines += _followup_lines(starts, settings, plan, total)
    return lines


def _followup_lines(starts, settings, plan, total: int) -> list[str]:
    """The stages after the verdict, their runs, and what the budget leaves them."""
    from fibersweep.discrepancy.followup import followup_costs

    c = followup_costs(starts, settings, plan, settings.candidates_of())
    parts = []
    if c.power:
        parts.append(f"power analysis {c.power} (+ up to {c.power_more} re-reads while the "
                     "budget lasts)")  # fmt: skip
    if c.next:
        parts.append(f"what to measure next up to {c.next}")
    if not parts:
        return []
    lines = ["  after the verdict, if it calls for them: " + ", ".join(parts)]
    if settings.budget is not None:
        left = settings.budget - total
        need = min(x for x in (c.power, c.next) if x)
        fits = ("each fits" if max(c.power, c.next) <= left else
                "one that does not fit in what the analysis leaves is skipped, and the report "
                "says so")  # fmt: skip
        lines.append(f"  budget {settings.budget}: {left} runs left after the analysis at its "
                     f"most (the smallest follow-up needs {need}); {fits}")  # fmt: skip
    return lines


def _print_discrepancy_plan(plan) -> None:
    """The plan before it runs (:class:`fibersweep.api.DiscrepancyPlan`)."""
    for line in [*_plan_lines(plan.fibers, plan.settings, plan.starts), *plan.fields]:
        typer.echo(line)
    if plan.followup is not None:
        typer.echo(
            f"  then {2 * plan.settings.settle_copies * plan.followup} more (beyond any "
            f"--budget) for the {plan.followup} follow-up fibers, if the verdict leaves two "
            "hypotheses"
        )


@app.command(rich_help_panel=MEASURED)
def discrepancy(
    measured: Annotated[Path, typer.Argument(help="Measured fibers (.parquet or .csv).")],
    config: ConfigArg,
    overrides: Overrides = None,
    output: Annotated[Path, typer.Option("--output", "-o", help="Report folder.")] = Path("report"),
    budget: Annotated[int | None, typer.Option(help="Most simulations in total.")] = None,
    seed: Annotated[int, typer.Option(help="Random seed.")] = 0,
    copies: Annotated[int, typer.Option(help="Jittered baseline copies per fiber.")] = 8,
    effect: Annotated[
        list[str] | None,
        typer.Option(
            "--effect",
            metavar="NAME",
            help="Library effect to consider, repeatable (default: all).",
        ),
    ] = None,
    candidate: CandidateOpt = None,
    alpha: Annotated[float, typer.Option(help="Family-wise error rate.")] = 0.05,
    pairs: Annotated[
        int, typer.Option(help="Pairs of effects tried (0: single effects only).")
    ] = 3,
    power: Annotated[
        bool,
        typer.Option(help="Power analysis when the verdict is no gap or unexplained."),
    ] = True,
    next_: Annotated[
        bool,
        typer.Option(
            "--next/--no-next", help="Propose starts that separate two candidates when undecided."
        ),
    ] = True,
    trajectories: Annotated[
        Path | None,
        typer.Option(
            help="Measured tracks (fiber_id, t [s], x, y [µm, the model's channel frame], "
            "theta [deg]) of every fiber: adds y_out, theta_out, t_transit (docs/trajectories.md)."
        ),
    ] = None,
    followup: Annotated[
        Path | None,
        typer.Option(
            help="Fibers measured after a first analysis of MEASURED (same schema), e.g. at "
            "the starts its 'what to measure next' gave: they test the verdict's two "
            "hypotheses against each other (docs/discrepancy.md)."
        ),
    ] = None,
    ignore_extra_columns: Annotated[
        bool, typer.Option(help="Ignore columns of MEASURED the schema does not know.")
    ] = False,
    workers: Workers = None,
    verbose: Verbose = False,
) -> None:
    """Where the model disagrees with fibers MEASURED past one pillar or through a pillar
    array, which effects explain it, and the gap left.

    On a pillar array (flow.array) MEASURED is an array measured table (starts,
    fraction, trapped, optional mode and bend); fabrication settings are candidates
    as alternatives (--candidate flow.array.shift=0.125), each value's unit-cell
    field solved once and cached.

    With --followup, MEASURED is analysed as without it (same seed, same
    verdict), then the two hypotheses the verdict leaves are tested on the
    follow-up fibers; an ambiguous verdict between them becomes named when those
    fibers reject one and fit the other.
    """
    from fibersweep import api

    _setup_logging(verbose)
    with _errors():
        rep = api.discrepancy(
            measured, config, *(overrides or []), output=output, budget=budget, seed=seed,
            copies=copies, effects=_effect_names(effect), candidates=candidate or (),
            alpha=alpha, pairs=pairs, power=power, propose_next=next_,
            trajectories=trajectories, followup=followup,
            ignore_extra_columns=ignore_extra_columns, workers=workers, progress=True,
            on_plan=_print_discrepancy_plan,
        )  # fmt: skip
    s = rep.summary
    if s.get("settle"):
        first = s["settle"]["verdict_first"]
        typer.echo(f"verdict on MEASURED alone: {first['kind']}: {first['text']}")
        typer.echo(f"follow-up: {s['settle']['text']}")
    elif s.get("settle_skipped"):
        typer.echo(f"follow-up not tested: {s['settle_skipped']}")
    typer.echo(f"verdict: {s['verdict']['kind']}: {s['verdict']['text']}")
    for stage, why in s.get("stages_skipped", {}).items():
        if why.startswith("skipped: budget"):  # the others are said in the report
            typer.echo(f"not run: {stage}, {why}")
    typer.echo(f"simulations: {s['simulations']} in {s['seconds']:.0f} s"
               + (f" (budget {budget})" if budget is not None else ""))  # fmt: skip
    typer.echo(f"wrote {output / 'report.md'} and {output / 'summary.json'}")
    for c in s["updated_configs"]:
        typer.echo(f"wrote {output / c}")


@app.command("power", rich_help_panel=MEASURED)
def power_cmd(
    config: ConfigArg,
    overrides: Overrides = None,
    n: Annotated[int, typer.Option("--n", help="Fibers the detection limits are for.")] = 100,
    measured: Annotated[
        Path | None,
        typer.Option(help="Use these measured starts (default: uniform in the sweep box)."),
    ] = None,
    simulate: Annotated[
        int, typer.Option(help="Fibers simulated (limits are scaled from them to N).")
    ] = 40,
    effect: Annotated[
        list[str] | None,
        typer.Option(
            "--effect",
            metavar="NAME",
            help="Library effect to analyse, repeatable (default: all of them, or none "
            "when --candidate is given).",
        ),
    ] = None,
    candidate: CandidateOpt = None,
    alpha: Annotated[float, typer.Option(help="Family-wise error rate.")] = 0.05,
    boot: Annotated[
        int,
        typer.Option(
            help="Bootstrap resamples of the simulated starts for each limit's 95 % interval "
            "(no new runs; 0: none)."
        ),
    ] = 30,
    seed: Annotated[int, typer.Option(help="Random seed.")] = 0,
    output: Annotated[Path, typer.Option("--output", "-o", help="Where power.json goes.")] = Path(
        "power"
    ),
    workers: Workers = None,
    verbose: Verbose = False,
) -> None:
    """Smallest magnitude of each candidate the discrepancy workflow would detect.

    By simulation at CONFIG's model, for N fibers with starts uniform in the sweep
    box (or MEASURED's starts), with the look-alike effects these observables
    cannot separate. The candidates: every library effect by default; with
    --candidate only the declared ones (each limit in its setting's unit), plus
    the library effects that --effect names. Unlike `discrepancy`, where a declared
    candidate is added to the library, the question here is the power for what
    was declared, and each candidate costs its own runs.
    """
    import json

    import numpy as np

    _setup_logging(verbose)
    with _errors():
        cfg = _load(config, overrides)
        from fibersweep.api.compare import array_settings_parts, load_measured_for
        from fibersweep.atomic import atomic_write
        from fibersweep.discrepancy.candidates import get_candidates
        from fibersweep.discrepancy.copies import CopyMaker, NoiseModel
        from fibersweep.discrepancy.detection import limit_in_unit
        from fibersweep.discrepancy.observables import scored
        from fibersweep.discrepancy.power import analyse_power
        from fibersweep.discrepancy.simulate import Simulator
        from fibersweep.errors import InputError
        from fibersweep.flow.cache import get_flow_field

        if n < 8 or simulate < 8:
            raise InputError(f"--n and --simulate must be >= 8, got {n} and {simulate}")
        declared = _declared(cfg, candidate)
        names = _effect_names(effect)
        array = _is_array(cfg)
        noise, library = NoiseModel(), names
        if array:  # the array's noise; only the library effects that act in an array
            parts = array_settings_parts(cfg, names, declared)
            noise, library = parts["noise"], parts["effects"]
        # declared candidates alone: the library only when --effect names some of it
        cands = [*(get_candidates(library) if names or not declared else []), *declared]
        rng = np.random.default_rng([seed, 17])
        field, _ = get_flow_field(cfg.flow, cfg.run.cache_dir)
        if measured is not None:
            data = load_measured_for(cfg, measured)
            starts, obs = data.starts, tuple(data.observed)
        else:
            box = _sweep_box(cfg)
            k = min(n, simulate)
            starts = np.column_stack([rng.uniform(*box[c], k) for c in ("theta0", "y0", "length")])
            obs = scored()
            if array:
                from fibersweep.discrepancy.array_starts import redraw_clear

                starts = redraw_clear(field, cfg.fiber, starts, box, rng, "power")
                obs = tuple(o for o in scored(geometry="array")
                            if o != "bend" or cfg.fiber.model != "rigid")  # fmt: skip
        if array:
            from fibersweep.discrepancy.array_workflow import field_plan

            for line in field_plan(declared, cfg.fiber, cfg.flow, cfg.run.cache_dir, field.meta):
                typer.echo(line)
        # the bar's length comes from the analysis (discrepancy.power.planned_runs)
        with Simulator(
            field, cfg.fiber, workers=workers or cfg.run.workers, executor=cfg.run.executor,
            scheduler=cfg.run.scheduler, tracks=False, candidates=cands, flow=cfg.flow,
            cache_dir=cfg.run.cache_dir,
        ) as sim:  # fmt: skip
            maker = CopyMaker(starts, noise, seed, sim)
            pw = analyse_power(maker, cands, n, obs, rng, n_sim=simulate, alpha=alpha,
                               n_boot=boot)  # fmt: skip
        rows = []
        by_name = {c.name: c for c in cands}
        for e in pw.effects:
            real = float(np.copysign(by_name[e.name].realistic, e.probe))
            rows.append(
                {
                    "effect": e.name, "probe": e.probe, "limit": e.limit, "gamma": e.gamma,
                    "read_at": e.read_at,
                    "limit_ci": list(e.limit_ci) if e.limit_ci is not None else None,
                    "dispersion_limit": e.dispersion_limit,
                    "realistic": real, "fibers_for_realistic": pw.fibers_to_detect(e.name, real),
                    **limit_in_unit(by_name[e.name], e),
                }
            )  # fmt: skip
        out = {
            "n": n, "n_simulated": pw.n_sim, "alpha": alpha, "power": pw.power,
            "effects": rows, "simulations": pw.simulations,
            "lookalikes": [{"a": a, "b": b, "cosine": c} for a, b, c in pw.lookalikes],
        }  # fmt: skip
        output.mkdir(parents=True, exist_ok=True)
        atomic_write(output / "power.json", json.dumps(out, indent=2))
    typer.echo(f"detection limits at N = {n} (power {pw.power:g}, alpha {alpha:g}):")
    for r in rows:
        if "setting" in r:
            need = r["fibers_for_realistic"]
            probe = by_name[r["effect"]].show(r["realistic"])
            more = f" ({probe}: detected with {need} fibers)" if need else ""
            typer.echo(f"  {r['effect']}: {r['setting']}{more}")
            continue
        lim = f"from {r['limit']:.3g}" if r["limit"] is not None else "not within its range"
        if r["limit_ci"] is not None:
            lo, hi = (f"{x:.3g}" if x is not None else "out of range" for x in r["limit_ci"])
            lim += f" [{lo}, {hi}]"
        if r["dispersion_limit"] is not None:
            lim += f"; dispersion test from {r['dispersion_limit']:.3g}"
        if r["read_at"] is not None:
            lim += f"; read at {r['read_at']:.3g}"
        need = r["fibers_for_realistic"]
        typer.echo(
            f"  {r['effect']:>13} {'+' if r['probe'] > 0 else '-'}  {lim:>41}"
            f"   (realistic {r['realistic']:g}: {need if need else '> 100000'} fibers)"
        )
    for a, b, c in pw.lookalikes:
        typer.echo(f"  look-alikes: {a} ~ {b} (|cos| {c:.2f})")
    typer.echo(f"wrote {output / 'power.json'} ({pw.simulations} simulations)")
