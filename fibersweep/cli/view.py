"""Views of a results folder beyond the phase diagram.

``plot-fractions`` (class fractions against a setting), ``plot-delta`` (δ against
a setting), ``plot-tracks`` (trajectories of a chosen subset), ``animate`` (one
run) and ``explore`` (one self-contained HTML page). On a pillar array's results
each answers in the array's terms (modes, displacement against rows crossed, f
against length), except ``plot-delta``, whose δ an array run does not have: it
exits 2 naming the commands that answer the question.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Annotated

import typer

from fibersweep.cli._app import FIGURES, Verbose, _errors, _setup_logging, app, choices
from fibersweep.errors import InputError
from fibersweep.plots import FORMATS

Results = Annotated[Path, typer.Argument(help="Output directory of a sweep.", show_default=False)]
Where = Annotated[
    str | None,
    typer.Option(
        "--where",
        help="Only runs for which this holds: a pandas query over the runs table, e.g. "
        "'y0 > 0.3 and class == \"Trapping\"' (columns as the table names them).",
    ),
]
Format = choices("Format", FORMATS)

#: Most trajectory points written into an explorer page (about 7 numbers each).
MAX_PAGE_POINTS = 1_500_000


def _runs(results: Path, where: str | None = None):
    """The runs table of ``results`` (only those ``where`` selects); InputError if none."""
    from fibersweep.plots.subset import select_runs
    from fibersweep.sweep.store import read_runs

    runs = read_runs(results)
    if runs.empty:
        raise InputError(f"{results}: no runs (expected {results}/runs/part-*.parquet)")
    return select_runs(runs, where)


def _geometries(results: Path, runs) -> dict:
    """Geometry of each settings id of ``runs``, from the folder's manifest."""
    from fibersweep.config.flow import FlowSettings
    from fibersweep.sweep.manifest import read_manifest

    man = read_manifest(results) or {}
    combos = man.get("combinations") or {}
    default = (man.get("config") or {}).get("flow")
    out = {}
    for sid in runs["settings"].astype(str).unique():
        flow = (combos.get(sid) or {}).get("flow") or default
        if flow is None:
            raise InputError(f"{results}: the manifest does not record the flow of settings {sid}")
        out[sid] = FlowSettings.model_validate(flow).geometry.to_geometry()
    return out


def is_array(runs) -> bool:
    """Whether ``runs`` are pillar-array runs (their outcome is a mode, not a class)."""
    return "mode" in runs and bool(runs["mode"].notna().any())


def _array_runs(results: Path, where: str | None):
    """Array runs that ``where`` selects, with their trajectories, settings and config
    (:func:`fibersweep.results.load_array_results`)."""
    from fibersweep.plots.subset import select_runs
    from fibersweep.results import load_array_results

    runs, settings, cfg = load_array_results(results)
    plain = runs[[c for c in runs.columns if not c.startswith("traj_")]]
    ids = set(select_runs(plain, where)["id"])
    return runs[runs["id"].isin(ids)].reset_index(drop=True), settings, cfg


def _cell_arrays(results: Path, runs) -> dict:
    """The pillar array of each settings id of ``runs``, from the folder's manifest."""
    from fibersweep.config.array import ArraySettings
    from fibersweep.sweep.manifest import read_manifest

    man = read_manifest(results) or {}
    combos = man.get("combinations") or {}
    default = (man.get("config") or {}).get("flow") or {}
    out = {}
    for sid in runs["settings"].astype(str).unique():
        flow = (combos.get(sid) or {}).get("flow") or default
        out[sid] = ArraySettings.model_validate(flow["array"]).to_array()
    return out


def _arrays(settings: list[dict]) -> list:
    from fibersweep.config.array import ArraySettings

    return [ArraySettings.model_validate(s["array"]).to_array() for s in settings]


def _safe(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.=+-]", "_", name)


def _save(fig, path: Path) -> Path:
    from fibersweep.plots.style import save_figure

    return save_figure(fig, path)


@app.command("plot-fractions", rich_help_panel=FIGURES)
def plot_fractions(
    results: Results,
    by: Annotated[
        str, typer.Option("--by", help="Setting of the horizontal axis: length, a swept key...")
    ] = "length",
    level: Annotated[
        float, typer.Option("--level", help="Confidence level of the Wilson intervals.")
    ] = 0.95,
    where: Where = None,
    out: Annotated[
        Path | None,
        typer.Option("--output", "-o", help="Figure file.", show_default="RESULTS/figures/…"),
    ] = None,
    verbose: Verbose = False,
) -> None:
    """Fraction of runs in each class (a pillar array: each mode) against one setting,
    with binomial (Wilson) intervals."""
    _setup_logging(verbose)
    with _errors():
        from fibersweep.plots.fractions import class_fractions, fractions_figure, pooled_keys
        from fibersweep.plots.style import paper_style

        if not 0.0 < level < 1.0:
            raise InputError(f"--level {level}: expected a number between 0 and 1")
        runs = _runs(results, where)
        with paper_style():
            path = _save(
                fractions_figure(runs, by, level),
                out or results / "figures" / f"fractions-{_safe(by)}.png",
            )
        facets = pooled_keys(runs, by)  # an array's other settings: one panel each
        groups = list(runs.groupby(facets, sort=True)) if facets else [((), runs)]
        tables = [(k, class_fractions(g, by, level)) for k, g in groups]
    for k, table in tables:
        if facets:
            k = k if isinstance(k, tuple) else (k,)
            typer.echo(", ".join(f"{f} = {v}" for f, v in zip(facets, k, strict=True)) + ":")
        for r in table.itertuples(index=False):
            typer.echo(
                f"{'  ' if facets else ''}{by} = {r[0]}: {r[1]} {r.k}/{r.n} = {r.fraction:.2f} "
                f"[{r.lo:.2f}, {r.hi:.2f}]"
            )
    typer.echo(f"wrote {path}")


@app.command("plot-delta", rich_help_panel=FIGURES)
def plot_delta(
    results: Results,
    by: Annotated[str, typer.Option("--by", help="Setting of the horizontal axis.")] = "length",
    where: Where = None,
    out: Annotated[
        Path | None,
        typer.Option("--output", "-o", help="Figure file.", show_default="RESULTS/figures/…"),
    ] = None,
    verbose: Verbose = False,
) -> None:
    """Lateral displacement δ past one pillar against one setting: every run, median,
    quartiles, 5–95 %.

    A pillar array's runs have no δ (their displacement is f: sort-report); exit 2.
    """
    _setup_logging(verbose)
    with _errors():
        from fibersweep.plots.fractions import delta_by_figure, delta_spread
        from fibersweep.plots.style import paper_style

        runs = _runs(results, where)
        if is_array(runs):
            raise InputError(
                f"plot-delta: {results} holds pillar-array runs, which have no δ (the lateral "
                "displacement past the channel's one pillar); their displacement is f, a "
                "fraction of the array's tilt: fibersweep sort-report RESULTS draws f and the "
                "migration angle against length, fibersweep plot-tracks RESULTS the "
                "displacement against rows crossed"
            )
        with paper_style():
            path = _save(
                delta_by_figure(runs, by), out or results / "figures" / f"delta-{_safe(by)}.png"
            )
        sp = delta_spread(runs, by)
    for r in sp.itertuples(index=False):
        typer.echo(
            f"{by} = {r[0]}: n = {r.n}, median δ = {r.median:.4f}, "
            f"quartiles [{r.q25:.4f}, {r.q75:.4f}], sd {r.sd:.4f} (h_obs)"
        )
    typer.echo(f"wrote {path}")


@app.command("plot-tracks", rich_help_panel=FIGURES)
def plot_tracks(
    results: Results,
    where: Where = None,
    out: Annotated[
        Path | None,
        typer.Option(
            "--output", "-o", help="Figure file.", show_default="RESULTS/figures/tracks.png"
        ),
    ] = None,
    verbose: Verbose = False,
) -> None:
    """Paths of the runs --where selects (all by default): past one pillar by class, through
    a pillar array as displacement against rows crossed by mode.

    A pillar array's runs: their lateral displacement against the rows crossed, one
    panel per setting and length, by mode, with the array's tilt.
    """
    _setup_logging(verbose)
    with _errors():
        from fibersweep.plots.style import paper_style
        from fibersweep.plots.tracks import overlay_figure
        from fibersweep.sweep.store import read_trajectories

        runs = _runs(results, where)
        if is_array(runs):
            from fibersweep.plots.array import overlay_figure as rows_figure
            from fibersweep.plots.labels import describe

            aruns, settings, _ = _array_runs(results, where)
            arrays = _arrays(settings)
            periods = {i: a.period_x for i, a in enumerate(arrays)}
            shifts = {i: a.lateral_shift for i, a in enumerate(arrays)}
            with paper_style():
                fig = rows_figure(aruns, periods, shifts=shifts, labels=describe(settings),
                                  title=where or "")  # fmt: skip
                path = _save(fig, out or results / "figures" / "tracks.png")
            typer.echo(f"wrote {path} ({len(aruns)} runs)")
            return
        samples = read_trajectories(results, runs["id"].tolist())
        with paper_style():
            fig = overlay_figure(runs, samples, _geometries(results, runs), title=where or "")
            path = _save(fig, out or results / "figures" / "tracks.png")
    typer.echo(f"wrote {path}")


@app.command(rich_help_panel=FIGURES)
def animate(
    results: Results,
    run_id: Annotated[
        str | None,
        typer.Argument(help="Id of the run (or a unique start of it).", show_default=False),
    ] = None,
    where: Where = None,
    out: Annotated[
        Path | None,
        typer.Option(
            "--output",
            "-o",
            help=".gif (Pillow, always there) or .mp4 (needs ffmpeg).",
            show_default="RESULTS/figures/run-ID.gif",
        ),
    ] = None,
    frames: Annotated[int, typer.Option("--frames", min=2, help="Frames.")] = 120,
    fps: Annotated[int, typer.Option("--fps", min=1, help="Frames per second.")] = 20,
    verbose: Verbose = False,
) -> None:
    """Animate one run of a sweep: the fiber moving past the pillar, or through the rows.

    The run is RUN_ID, or the first run --where selects. A pillar array's run is
    followed through the rows. A flexible fiber is drawn through all its beads
    (stored with fiber.record.all_beads). A .gif is written with matplotlib's
    PillowWriter (Pillow comes with matplotlib); an .mp4 needs ffmpeg.
    """
    _setup_logging(verbose)
    with _errors():
        from fibersweep.plots.style import paper_style
        from fibersweep.plots.tracks import animate_run
        from fibersweep.sweep.store import read_trajectories

        if (run_id is None) == (where is None):
            raise InputError("name the run: a RUN_ID or --where (one of them)")
        runs = _runs(results, where)
        if run_id is not None:
            runs = runs[runs["id"].astype(str).str.startswith(run_id)]
            if len(runs) != 1:
                what = "no such run" if runs.empty else f"{len(runs)} runs match"
                raise InputError(f"run {run_id!r}: {what}")
        elif len(runs) > 1:
            typer.echo(f"{len(runs)} runs match --where; animating the first, {runs['id'].iloc[0]}")
        hit = runs.iloc[:1]
        run = hit.iloc[0]
        if is_array(runs):
            from fibersweep.plots.array_chrono import animate_array_run
            from fibersweep.plots.labels import describe

            aruns, settings, cfg = _array_runs(results, None)
            arun = aruns[aruns["id"] == run["id"]].iloc[0]
            array = _arrays(settings)[int(arun["setting"])]
            with paper_style():
                path = animate_array_run(
                    arun.to_dict(), array, cfg["fiber"]["bead_radius"],
                    out or results / "figures" / f"run-{run['id']}.gif", frames=frames, fps=fps,
                    label=describe(settings)[int(arun["setting"])],
                )  # fmt: skip
            typer.echo(f"wrote {path}")
            return
        samples = read_trajectories(results, [run["id"]])
        geometry = _geometries(results, hit)[str(run["settings"])]
        with paper_style():
            path = animate_run(
                run, samples, geometry, out or results / "figures" / f"run-{run['id']}.gif",
                frames=frames, fps=fps,
            )  # fmt: skip
    typer.echo(f"wrote {path}")


@app.command(rich_help_panel=FIGURES)
def explore(
    results: Results,
    out: Annotated[
        Path | None,
        typer.Option("--output", "-o", help="HTML file.", show_default="RESULTS/explore.html"),
    ] = None,
    samples: Annotated[
        int, typer.Option("--samples", min=2, help="Trajectory points kept per run.")
    ] = 150,
    verbose: Verbose = False,
) -> None:
    """Write one self-contained HTML page to explore a sweep in a browser (works offline).

    Hover a run of the phase diagram for its settings and outcome, filter by any
    column, click a run to see its trajectory. A pillar array's runs are shown as
    f against length by mode, a clicked run's path through the rows over its pillars.
    """
    _setup_logging(verbose)
    with _errors():
        from fibersweep.plots.explore import explorer_html
        from fibersweep.sweep.manifest import read_manifest
        from fibersweep.sweep.store import read_trajectories

        runs = _runs(results)
        traj = read_trajectories(results)
        n_tracks = max(1, traj["id"].nunique()) if len(traj) else 1
        if samples * n_tracks > MAX_PAGE_POINTS:  # keep the page a size a browser opens
            samples = max(10, MAX_PAGE_POINTS // n_tracks)
            typer.echo(f"{n_tracks} trajectories: keeping {samples} points of each (--samples)")
        sep = (read_manifest(results) or {}).get("separatrix")
        arrays = geometries = None
        if is_array(runs):
            arrays, geometries = _cell_arrays(results, runs), {}
        else:
            geometries = _geometries(results, runs)
        html = explorer_html(
            runs, traj, geometries, title=str(results), separatrix=sep,
            samples_per_run=samples, arrays=arrays,
        )  # fmt: skip
        from fibersweep.atomic import atomic_write

        path = atomic_write(out or results / "explore.html", html)
    typer.echo(f"wrote {path} ({path.stat().st_size / 1e6:.1f} MB, {len(runs)} runs)")
