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
    measured: Annotated[
        Path | None,
        typer.Option(
            "--measured",
            help="Array measured table (Parquet or CSV, one row per fiber: length [µm], "
            "fraction, trapped): its f(L) and critical length beside the model's.",
        ),
    ] = None,
    edges: Annotated[
        str | None,
        typer.Option(
            help="Length bin edges of the measured fibers [µm], comma separated.",
            show_default="one bin per simulated length",
        ),
    ] = None,
    verbose: Verbose = False,
) -> None:
    """A sorter designer's page: critical lengths, outlets, and the array setting to choose.

    Per setting and fiber length: the displacement fraction f and migration angle
    over the runs that were not trapped, the trapped share and the modes; the
    critical lengths (mean f = 1/2) with their 95 % interval (the runs' scatter and
    the interpolation between simulated lengths) and the lengths that decide them on
    few moving runs; recovery and purity per outlet of a device of ROWS rows, with
    the trapped share beside them. With a swept array setting (shift, a period, the
    pillar size or shape): the critical length against it, and with --target-length
    or --separate, the value that gives it, its interval and the runs to add to be
    sure. Settings outside the validated range are warned about first. With
    --measured TABLE (fibers measured through the fabricated array): per length bin
    the measured f with its 95 % Wilson interval and trapped share beside the model's,
    the measured critical length with its interval beside the model's, and the
    measured points on migration.png. Tables go to RESULTS/*.csv, figures to
    RESULTS/figures/.
    """
    from fibersweep import api

    _setup_logging(verbose)
    with _errors():
        rep = api.sort_report(
            results, rows=rows, outlets=outlets, target_length=target_length,
            separate=separate, setting=setting, figures=figures, zigzag_max=zigzag_max,
            displacement_min=displacement_min, measured=measured, edges=edges,
        )  # fmt: skip
    for message in rep.warnings:  # outside the validated range: before the numbers
        typer.secho(f"warning: {message}", fg=typer.colors.YELLOW)
    _echo_migration(rep)
    if rep.measured is not None:
        _echo_measured(rep, measured)
    _echo_outlets(rep.outlets, rep.settings, rep.rows)
    if rep.curve is not None:
        _echo_design(rep)
    typer.echo("tables: " + ", ".join(str(w) for w in rep.tables))
    for w in rep.figures:
        typer.echo(f"figure: {w}")
    for n in rep.notes:
        typer.secho(f"note: {n}", fg=typer.colors.YELLOW)


_ABBREV = {"zigzag": "Z", "displacement": "D", "wrap-and-jump": "WJ", "trapped": "T", "mixed": "M"}


def _echo_migration(rep) -> None:
    """Per setting: the f summary per length, its critical lengths and lengths to add."""
    import pandas as pd

    from fibersweep.sorting.report import located

    runs, table, crit, bead = rep.runs, rep.migration, rep.critical, rep.bead
    pd.set_option("display.width", 160)
    typer.echo(
        "f: displacement per row / ε λy (1 follows the tilt, 0 the flow), mean ± standard "
        "error over the runs that were not trapped; trapped: their share (not in f or the "
        "angle); modes: Z zigzag, D displacement, WJ wrap-and-jump, M mixed, T trapped"
    )
    for s, g in table.groupby("setting"):
        meta = rep.settings[int(s)]
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
            one_bead = " (located to one bead)" if located(r.lo, r.hi, bead) else ""
            typer.echo(
                f"critical length ({'f rises' if r.rising else 'f falls'} through 1/2): "
                f"{_interval(r)}, between the simulated {r.lo:g} and {r.hi:g} µm{one_bead}"
            )
        for line in rep.caveats.get(int(s), []):
            typer.secho(f"  caveat: {line}", fg=typer.colors.YELLOW)
        new = rep.narrowing.get(int(s), [])
        if new:
            typer.echo(
                f"to narrow it: add {', '.join(f'{L:g}' for L in new)} to sweep.length and run "
                "the same config into this folder (only the new lengths run), or let the sweep "
                "do it: 'sweep.refine={axes: [length], tolerance: {length: "
                f"{bead:g}}}, max_runs: 200}}'"
            )


def _echo_measured(rep, path: Path) -> None:
    """The measured f and trapped share per length bin beside the model's, the critical
    length of each, and the trapped share over all fibers."""
    import pandas as pd

    from fibersweep.sorting.interval import level_text
    from fibersweep.sorting.report import critical_text

    m = rep.measured
    lev = level_text()
    bins = "the given --edges" if m.given_edges else "one per simulated length"
    out = (
        f", {m.outside} outside {m.edges[0]:g} to {m.edges[-1]:g} µm left out" if m.outside else ""
    )
    typer.echo(
        f"\nmeasured beside the model ({path}: {m.fibers} fibers, "
        f"{m.binned if m.outside else 'all'} in "
        f"{len(m.bins)} length bins, {bins}{out}): f over the fibers that were not trapped "
        f"and the trapped share of all, each with its {lev} Wilson interval; model: the "
        "runs of the simulated lengths in the bin"
    )
    many = len(rep.settings) > 1
    rows = []
    for b in m.bins.to_dict("records"):
        row = {
            "L bin [µm]": f"{b['from']:g} to {b['to']:g}",
            "fibers": b["fibers"],
            "L mean [µm]": f"{b['length']:.1f}",
            "measured f": _ci(b["fraction_mean"], b["fraction_lo"], b["fraction_hi"]),
            "trapped": _ci(b["trapped"], b["trapped_lo"], b["trapped_hi"]),
        }
        for s, g in m.model.groupby("setting"):
            r = g[g["bin"] == b["bin"]].iloc[0]
            tag = f" {_name(rep.settings[int(s)])}" if many else ""
            row[f"model f{tag}"] = _pm(r["fraction_mean"], math.nan, 2)
            row[f"model trapped{tag}"] = _pm(r["trapped"], math.nan, 2)
        rows.append(row)
    typer.echo(pd.DataFrame(rows).to_string(index=False))
    if m.critical.empty:
        f = m.bins["fraction_mean"].to_numpy(float)
        f = f[np.isfinite(f)]
        if not f.size:
            why = "no bin has a fiber that was not trapped"
        elif (f < m.level).all():
            why = f"f below {m.level:g} in every bin"
        elif (f > m.level).all():
            why = f"f above {m.level:g} in every bin"
        else:
            why = f"f does not cross {m.level:g} between two bins"
        typer.echo(f"critical length, measured: none in the bins ({why})")
    for r in m.critical.itertuples():
        typer.echo(
            f"critical length, measured ({'f rises' if r.rising else 'f falls'} through "
            f"{m.level:g}): "
            f"{critical_text(r.critical, r.ci_lo, r.ci_hi)}, between the bins at {r.lo:.1f} "
            f"and {r.hi:.1f} µm"
        )
    for s in range(len(rep.settings)):
        c = rep.critical[rep.critical["setting"] == s]
        tag = f" ({_name(rep.settings[s])})" if many else ""
        text = ", ".join(critical_text(r.critical, r.ci_lo, r.ci_hi) for r in c.itertuples())
        typer.echo(f"critical length, model{tag}: {text or 'none in the simulated lengths'}")
        both = [(a, b) for a in m.critical.itertuples() for b in c.itertuples()
                if a.rising == b.rising]  # fmt: skip
        if len(both) == 1:  # one edge each, the same way: how far apart, and is it clear
            a, b = both[0]
            known = all(math.isfinite(v) for v in (a.ci_lo, a.ci_hi, b.ci_lo, b.ci_hi))
            apart = a.ci_hi < b.ci_lo or b.ci_hi < a.ci_lo
            say = ("do not overlap" if apart else "overlap") if known else "are not both known"
            typer.echo(
                f"  measured - model: {a.critical - b.critical:+.1f} µm; "
                f"their {lev} intervals {say}"
            )
    t = m.trapped
    model = ", ".join(
        f"{_pm(v, math.nan, 2)}" + (f" ({_name(rep.settings[s])})" if many else "")
        for s, v in t.model.items()
    )
    typer.echo(
        f"trapped: measured {t.trapped} of {t.fibers} fibers, {t.share:.2f} ({lev}: "
        f"{t.lo:.2f} to {t.hi:.2f}); model at the same lengths {model}"
    )


def _ci(v: float, lo: float, hi: float) -> str:
    """'0.42 (0.21 to 0.66)': a share and its interval; '-' where there is none."""
    if not math.isfinite(v):
        return "-"
    v, lo, hi = (round(x, 2) + 0.0 for x in (v, lo, hi))  # no '-0.00'
    return f"{v:.2f} ({lo:.2f} to {hi:.2f})"


def _name(meta: dict) -> str:
    from fibersweep.sorting.report import setting_name

    return setting_name(meta)


def _interval(r) -> str:
    """'15.0 µm (95 %: 12.2 to 15.9 µm; statistical alone ± 0.3)': a critical length, its
    interval and, apart, its statistical error (a row of the critical table or curve)."""
    from fibersweep.sorting.report import critical_text

    text = critical_text(r.critical, r.ci_lo, r.ci_hi)
    if math.isfinite(r.se) and text.endswith(")"):
        text = text[:-1] + f"; statistical alone ± {r.se:.1f})"
    return text


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


def _echo_design(rep) -> None:
    """The critical length against the swept setting, and the answer for a target."""
    curve, key = rep.curve, rep.key
    name = key.rsplit(".", 1)[-1]
    typer.echo(
        f"\ncritical length against {name} (first length where f rises through 1/2; "
        "where it never rises, where it falls), with its interval (the runs' scatter and "
        "the interpolation between simulated lengths):"
    )
    for grp, g in curve.groupby("group", sort=False):
        if grp:
            typer.echo(f"  {grp}:")
        for r in g.itertuples():
            if math.isfinite(r.critical):
                txt = f"{_interval(r)}, between {r.lo:g} and {r.hi:g}"
                txt += "" if r.rising else ", f falls through 1/2"
            elif math.isfinite(r.lo):
                txt = f"above {r.lo:g} µm (f < 1/2 at every length)"
            else:
                txt = f"below {r.hi:g} µm (f > 1/2 at every length)"
            val = f"{r.value:g}" if isinstance(r.value, int | float) else r.value
            typer.echo(f"    {name} = {val}: {txt}")
    if rep.target is None:
        return
    if rep.separate is not None:
        pair = " and ".join(f"{v:g}" for v in rep.separate)
        what = f"to separate {pair} µm, a critical length halfway: {rep.target:g} µm"
    else:
        what = f"target critical length {rep.target:g} µm"
    typer.echo(f"\n{what}:")
    for ga in rep.answers:
        ans = ga.answer
        typer.echo(("  " + ga.group + ": " if ga.group else "  ") + ans.text)
        for line in ans.caveats:  # the runs it rests on, where they are few
            typer.secho(f"  caveat: {line}", fg=typer.colors.YELLOW)
        if ans.add:
            typer.echo("  to be sure, run:")
            for line in ans.add:
                typer.echo(f"    {line}")
        if ga.check is not None:
            values = sorted({*curve["value"], ga.check})
            typer.echo(
                f"  the check: add {ga.check:g} to the swept values, e.g. "
                f"'sweep.{key}=[{', '.join(f'{v:g}' for v in values)}]', and run the same "
                "sweep into this folder (only the new runs run); sort-report then reads "
                "its critical length"
            )
