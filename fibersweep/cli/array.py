"""Pillar-array command ``sort-report`` (and ``run-array``, removed: use ``fibersweep run``)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from fibersweep.cli._app import (
    ARRAYS,
    ConfigArg,
    Overrides,
    Verbose,
    _errors,
    _setup_logging,
    app,
)
from fibersweep.config.fiber import ARRAY_ROWS
from fibersweep.errors import InputError


@app.command("run-array", hidden=True)
def run_array(
    config: ConfigArg,
    overrides: Overrides = None,
    verbose: Verbose = False,
) -> None:
    """Removed: a pillar-array sweep is ``fibersweep run CONFIG`` with ``flow.array`` set."""
    _setup_logging(verbose)
    with _errors():
        raise InputError(
            "run-array: removed; use fibersweep run CONFIG (a pillar array is the flow.array "
            "section of the standard config: see configs/array.yaml and docs/arrays.md)"
        )


@app.command("sort-report", rich_help_panel=ARRAYS)
def sort_report(
    results: Annotated[Path, typer.Argument(help="Output folder of an array sweep.")],
    rows: Annotated[
        int | None, typer.Option(help="Rows of the device [default: fiber.array_rows].")
    ] = None,
    outlets: Annotated[
        str,
        typer.Option(
            help="Outlet edges, comma separated, each a fraction of the full displacement "
            "strictly between 0 and 1 (0: straight on, 1: the tilt at every row)."
        ),
    ] = "0.5",
    target_length: Annotated[
        float | None,
        typer.Option(
            "--target-length",
            help="Critical length wanted [µm]: which value of the swept array setting gives "
            "it, and what to run to be sure.",
        ),
    ] = None,
    separate: Annotated[
        str | None,
        typer.Option(
            help="Two lengths to separate, L1,L2 [µm]: the setting whose critical length "
            "lies halfway between them."
        ),
    ] = None,
    setting: Annotated[
        str | None,
        typer.Option(
            help="The swept setting to read the critical length against.",
            show_default="the first swept array setting",
        ),
    ] = None,
    figures: Annotated[bool, typer.Option(help="Write the figures (RESULTS/figures/).")] = True,
    zigzag_max: Annotated[float, typer.Option(help="Mode rule: |f| below this is zigzag.")] = 0.25,
    displacement_min: Annotated[float, typer.Option(help="f above this is displacement.")] = 0.75,
    verbose: Verbose = False,
) -> None:
    """A sorter designer's page: critical lengths, outlets, and the array setting to choose.

    Per setting and fiber length: the displacement fraction f and migration angle
    over the runs that were not trapped, the trapped share and the modes; the
    critical lengths (mean f = 1/2) with their error; recovery and purity per
    outlet of a device of ROWS rows, with the trapped share beside them. With a
    swept array setting (shift, a period, the pillar size or shape): the critical
    length against it, and with --target-length or --separate, the value that
    gives it and the runs to add to be sure. Tables go to RESULTS/*.csv, figures
    to RESULTS/figures/.
    """
    _setup_logging(verbose)
    with _errors():
        from fibersweep.analysis.modes import ModeSettings
        from fibersweep.results import load_array_results
        from fibersweep.sorting import report as sr

        try:
            edges = [float(e) for e in outlets.split(",") if e.strip()]
        except ValueError:
            raise InputError(f"--outlets: not a list of numbers: {outlets!r}") from None
        edges = sr.check_edges(edges)
        target = _target(target_length, separate)
        runs, settings, cfg = load_array_results(results)
        modes = ModeSettings(zigzag_max=zigzag_max, displacement_min=displacement_min)
        runs = sr.relabel(runs, settings, modes, cfg["fiber"]["classify"]["trap_speed"])
        key = _design_key(settings, setting, target)
        n_rows = rows or cfg["fiber"].get("array_rows", ARRAY_ROWS)
        table = sr.migration_table(runs, settings)
        crit = sr.critical_table(table)
        bead = 2.0 * cfg["fiber"]["bead_radius"]
        _echo_migration(runs, table, crit, settings, bead)
        _warn_short(settings, int(cfg["fiber"].get("array_rows", ARRAY_ROWS)))
        out = sr.outlet_table(runs, settings, n_rows, edges)
        _echo_outlets(out, settings, n_rows)
        written = [results / "migration.csv", results / "outlets.csv"]
        table.to_csv(written[0], index=False)
        out.to_csv(written[1], index=False)
        curve = ans = None
        if key is not None:
            curve, ans = _design(crit, table, settings, key, target, bead, separate)
            curve.to_csv(results / "critical.csv", index=False)
            written.append(results / "critical.csv")
        typer.echo("tables: " + ", ".join(str(w) for w in written))
        if figures:
            _figures(results, runs, table, crit, out, settings, cfg, key, curve, ans, target)


def _target(target_length: float | None, separate: str | None) -> float | None:
    """The critical length asked for (--target-length, or halfway between --separate's)."""
    if target_length is not None and separate is not None:
        raise InputError("--target-length and --separate: give one of them")
    if separate is not None:
        try:
            pair = [float(v) for v in separate.split(",")]
        except ValueError:
            pair = []
        if (
            len(pair) != 2
            or not all(math.isfinite(v) and v > 0 for v in pair)
            or pair[0] == pair[1]
        ):
            raise InputError(f"--separate {separate!r}: expected two different lengths L1,L2 [µm]")
        return 0.5 * (pair[0] + pair[1])
    if target_length is not None and not (math.isfinite(target_length) and target_length > 0):
        raise InputError(f"--target-length {target_length}: expected a length > 0 [µm]")
    return target_length


def _design_key(settings: list[dict], setting: str | None, target: float | None) -> str | None:
    from fibersweep.sorting.design import design_key

    key = design_key(settings, setting)
    if key is None and target is not None:
        raise InputError(
            "--target-length/--separate: these results sweep no array setting, so there is "
            "nothing to choose; sweep one, e.g. 'sweep.flow.array.shift=[0.05, 0.1, 0.15, 0.2]' "
            "(docs/arrays.md, 'Design: a target critical length')"
        )
    return key


_ABBREV = {"zigzag": "Z", "displacement": "D", "wrap-and-jump": "WJ", "trapped": "T", "mixed": "M"}


def _echo_migration(runs, table, crit, settings: list[dict], bead: float) -> None:
    """Per setting: the f summary per length, its critical lengths and lengths to add."""
    import pandas as pd

    from fibersweep.sorting.report import refine_lengths

    pd.set_option("display.width", 160)
    typer.echo(
        "f: displacement per row / ε λy (1 follows the tilt, 0 the flow), mean ± standard "
        "error over the runs that were not trapped; trapped: their share (not in f or the "
        "angle); modes: Z zigzag, D displacement, WJ wrap-and-jump, M mixed, T trapped"
    )
    add = refine_lengths(table)
    for s, g in table.groupby("setting"):
        meta = settings[int(s)]
        tilt = math.degrees(math.atan(meta["array"]["shift"]))
        typer.echo(f"\n{_name(meta)} (tilt {tilt:.2f}°):")
        rows = []
        for r in g.itertuples():
            sub = runs[(runs["setting"] == s) & (runs["length"] == r.length)]
            counts = sub["mode"].value_counts()
            rows.append(
                {
                    "L [µm]": f"{r.length:g}",
                    "runs": r.runs,
                    "trapped": f"{r.trapped:.2f}",
                    "f": _pm(r.fraction_mean, r.fraction_se, 2),
                    "angle [deg]": _pm(r.angle_mean, r.angle_std, 2),
                    "modes": " ".join(f"{counts[m]} {_ABBREV[m]}" for m in _ABBREV if m in counts),
                }
            )
        typer.echo(pd.DataFrame(rows).to_string(index=False))
        c = crit[crit["setting"] == s]
        if c.empty:
            f = g["fraction_mean"].to_numpy(float)
            side = "below" if (f[~np.isnan(f)] < 0.5).all() else "above"
            typer.echo(
                f"critical length: none in {g['length'].min():g} to {g['length'].max():g} "
                f"µm (mean f {side} 1/2 at every length)"
            )
        for r in c.itertuples():
            located = " (located to one bead)" if r.hi - r.lo <= bead * (1 + 1e-9) else ""
            typer.echo(
                f"critical length ({'f rises' if r.rising else 'f falls'} through 1/2): "
                f"{_pm(r.critical, r.se, 1)} µm, between the simulated {r.lo:g} and {r.hi:g} "
                f"µm{located}"
            )
        new = [L for L in add.get(int(s), []) if _bisects(L, c, bead)]
        if new:
            typer.echo(
                f"to narrow it: add {', '.join(f'{L:g}' for L in new)} to sweep.length and run "
                "the same config into this folder (only the new lengths run), or let the sweep "
                "do it: 'sweep.refine={axes: [length], tolerance: {length: "
                f"{bead:g}}}, max_runs: 200}}'"
            )


#: Zigzag periods (1/ε rows each) a run should cross for its f to tell the modes apart.
MIN_PERIODS = 2.0


def _warn_short(settings: list[dict], rows: int) -> None:
    """Say where the runs crossed too few rows for f to separate zigzag from displacement.

    A zigzagging fiber follows the tilt for 1/ε rows, then jumps back one column: its f
    averages to 0 only over whole periods of 1/ε rows; over one period it can read
    anything between 0 and 1.
    """
    for meta in settings:
        eps = meta["array"]["shift"]
        if eps > 0 and rows * eps < MIN_PERIODS:
            typer.secho(
                f"note: {_name(meta)}: {rows} rows are {rows * eps:.1f} zigzag periods (1/ε = "
                f"{1 / eps:.0f} rows), too few for f to tell zigzag from displacement; run at "
                f"least {math.ceil(MIN_PERIODS / eps)} rows (fiber.array_rows)",
                fg=typer.colors.YELLOW,
            )


def _name(meta: dict) -> str:
    from fibersweep.sorting.report import setting_name

    return setting_name(meta)


def _bisects(L: float, crit, bead: float) -> bool:
    """Whether the midpoint L halves a bracket wider than one bead."""
    return any(r.lo < L < r.hi and r.hi - r.lo > bead * (1 + 1e-9) for r in crit.itertuples())


def _pm(v: float, e: float, digits: int) -> str:
    if not math.isfinite(v):
        return "-"
    return f"{v:.{digits}f}" + (f" ± {e:.{digits}f}" if math.isfinite(e) else "")


def _echo_outlets(out, settings: list[dict], n_rows: int) -> None:
    """Recovery and purity per outlet and length, the trapped share beside them."""
    import pandas as pd

    outs = sorted(out["outlet"].unique())
    for s, g in out.groupby("setting"):
        meta = settings[int(s)]
        full = n_rows * meta["array"]["shift"] * meta["array"]["period_y"]
        typer.echo(
            f"\noutlets of a {n_rows}-row device, {_name(meta)} (full displacement "
            f"{full:.0f} µm): recovery and purity per outlet; each length's recoveries and its "
            "trapped share add up to 1"
        )
        rows = []
        empty = set()
        for L, gl in g.groupby("length"):
            row = {"L [µm]": f"{L:g}"}
            for k in outs:
                r = gl[gl["outlet"] == k].iloc[0]
                lo, hi = r["from"], r["to"]
                name = (
                    f"f<{hi:g}"
                    if not math.isfinite(lo)
                    else f"f>={lo:g}"
                    if not math.isfinite(hi)
                    else f"{lo:g}<=f<{hi:g}"
                )
                row[f"{k}: {name} rec"] = f"{r['recovery']:.2f}"
                row[f"{k}: pur"] = "-" if not math.isfinite(r["purity"]) else f"{r['purity']:.2f}"
                if not math.isfinite(r["purity"]):
                    empty.add(k)
            row["trapped"] = f"{gl['trapped'].iloc[0]:.2f}"
            rows.append(row)
        typer.echo(pd.DataFrame(rows).to_string(index=False))
        for k in sorted(empty):
            typer.echo(f"  outlet {k}: no fiber leaves there (purity -)")


def _design(crit, table, settings, key: str, target, bead: float, separate):
    """Critical length against the swept setting; the answer for a target. Printed."""
    from fibersweep.sorting import design as sd

    curve = sd.critical_curve(crit, table, settings, key)
    name = key.rsplit(".", 1)[-1]
    typer.echo(
        f"\ncritical length against {name} (first length where f rises through 1/2; "
        "where it never rises, where it falls):"
    )
    for grp, g in curve.groupby("group", sort=False):
        if grp:
            typer.echo(f"  {grp}:")
        for r in g.itertuples():
            if math.isfinite(r.critical):
                txt = f"{_pm(r.critical, r.se, 1)} µm (between {r.lo:g} and {r.hi:g})"
                txt += "" if r.rising else ", f falls through 1/2"
            elif math.isfinite(r.lo):
                txt = f"above {r.lo:g} µm (f < 1/2 at every length)"
            else:
                txt = f"below {r.hi:g} µm (f > 1/2 at every length)"
            val = f"{r.value:g}" if isinstance(r.value, int | float) else r.value
            typer.echo(f"    {name} = {val}: {txt}")
    ans = None
    if target is not None:
        what = (
            f"to separate {separate.replace(',', ' and ')} µm, a critical length halfway: "
            f"{target:g} µm"
            if separate
            else f"target critical length {target:g} µm"
        )
        typer.echo(f"\n{what}:")
        for grp, g in curve.groupby("group", sort=False):
            ans = sd.answer(g, key, target, settings[int(g["setting"].iloc[0])]["flow"], bead)
            typer.echo(("  " + grp + ": " if grp else "  ") + ans.text)
            if ans.add:
                typer.echo("  to be sure, run:")
                for line in ans.add:
                    typer.echo(f"    {line}")
            if (
                isinstance(ans.value, float)
                and not np.isclose(curve["value"].to_numpy(float), _lattice_pick(ans)).any()
            ):
                values = sorted({*curve["value"], _lattice_pick(ans)})
                typer.echo(
                    f"  the check: add {_lattice_pick(ans):g} to the swept values, e.g. "
                    f"'sweep.{key}=[{', '.join(f'{v:g}' for v in values)}]', and run the same "
                    "sweep into this folder (only the new runs run); sort-report then reads "
                    "its critical length"
                )
    return curve, ans


def _lattice_pick(ans) -> float:
    lo, hi = ans.lattice
    cands = [v for v in (lo, hi) if math.isfinite(v)]
    return min(cands, key=lambda v: abs(v - ans.value)) if cands else ans.value


def _slug(values: dict) -> str:
    """File-name part of a setting combination: 'shift=0.1_young_modulus=1e+04'."""
    import re

    parts = [
        f"{k.rsplit('.', 1)[-1]}={v:g}"
        if isinstance(v, int | float)
        else f"{k.rsplit('.', 1)[-1]}={v}"
        for k, v in values.items()
    ]
    return re.sub(r"[^A-Za-z0-9_.=+-]", "_", "_".join(parts))


#: Most settings drawn in one chronophotograph (one panel each).
MAX_PANELS = 6


def _pick(sub, mode: str) -> dict | None:
    """A run that shows ``mode``: at the length where it is most common, f nearest its median."""
    m = sub[sub["mode"] == mode]
    if m.empty:
        return None
    L = m["length"].value_counts().sort_index().idxmax()
    g = m[m["length"] == L]
    if mode == "wrap-and-jump" and "wraps" in g:
        return g.sort_values("wraps", ascending=False).iloc[0].to_dict()
    f = g["fraction"].to_numpy(float)
    return (
        g.iloc[int(np.nanargmin(np.abs(f - np.nanmedian(f))))].to_dict()
        if np.isfinite(f).any()
        else g.iloc[0].to_dict()
    )


def _figures(
    results: Path, runs, table, crit, out, settings: list[dict], cfg: dict, key, curve, ans, target
) -> None:
    from fibersweep.analysis.modes import MODES
    from fibersweep.config.flow import FlowSettings
    from fibersweep.flow.cache import get_flow_field
    from fibersweep.plots import array as pa
    from fibersweep.plots import array_design as pd_
    from fibersweep.plots.shapes import ShapeNotStored
    from fibersweep.plots.style import paper_style, save_figure

    fig_dir = results / "figures"
    written, notes = [], []
    with paper_style():
        arrays, shifts, periods, drawn = {}, {}, {}, set()
        for i, s in enumerate(settings):
            # the sweep's cell field, from the cache (solved again if it was removed)
            flow = FlowSettings.model_validate(s["flow"])
            field, _ = get_flow_field(flow, cfg["run"]["cache_dir"])
            arrays[i] = field.array
            shifts[i] = field.array.lateral_shift
            periods[i] = field.array.period_x
            if s["flow_key"] in drawn:  # settings that share a flow share its figure
                continue
            drawn.add(s["flow_key"])
            flow_values = {k: v for k, v in s["values"].items() if k.startswith("flow.")}
            name = f"cell-flow-{_slug(flow_values)}.png" if flow_values else "cell-flow.png"
            written.append(save_figure(pa.cell_flow_figure(field), fig_dir / name, dpi=110))
        tilts = {i: math.degrees(math.atan(s["array"]["shift"])) for i, s in enumerate(settings)}
        labels = {i: s["label"] for i, s in enumerate(settings)}
        written.append(
            save_figure(pd_.migration_figure(table, tilts, labels, crit), fig_dir / "migration.png")
        )
        written.append(save_figure(pd_.outlets_figure(out, labels), fig_dir / "outlets.png"))
        written.append(
            save_figure(
                pa.overlay_figure(runs, periods, shifts=shifts),
                fig_dir / "sort-tracks.png",
                dpi=130,
            )
        )
        shown = list(range(len(settings)))
        if len(shown) > MAX_PANELS:
            shown = [
                shown[round(k * (len(shown) - 1) / (MAX_PANELS - 1))] for k in range(MAX_PANELS)
            ]
            notes.append(f"chronophotographs show {MAX_PANELS} of the {len(settings)} settings")
        for mode in MODES:
            picks = [(i, _pick(runs[runs["setting"] == i], mode)) for i in shown]
            picks = [(i, p) for i, p in picks if p is not None]
            if not picks:
                continue
            try:
                fig = pa.chrono_figure(
                    None,
                    [p for _, p in picks],
                    cfg["fiber"]["bead_radius"],
                    arrays=[arrays[i] for i, _ in picks],
                )
            except ShapeNotStored as exc:
                notes.append(f"no chronophotograph of the {mode} runs: {exc}")
                continue
            written.append(save_figure(fig, fig_dir / f"chrono-{mode}.png", dpi=130))
        if curve is not None:
            from fibersweep.config import setting_column

            unit = setting_column(key)[1]
            fig = pd_.critical_figure(curve, key, unit, ans, target)
            written.append(save_figure(fig, fig_dir / f"critical-{key.rsplit('.', 1)[-1]}.png"))
    for w in written:
        typer.echo(f"figure: {w}")
    for n in notes:
        typer.secho(f"note: {n}", fg=typer.colors.YELLOW)
