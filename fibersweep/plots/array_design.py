"""The sorter designer's figures: f and migration against length with the critical
lengths marked, purity and recovery per outlet, the critical length against a
swept array setting. Data in (the tables of :mod:`fibersweep.sorting.report`
and :mod:`fibersweep.sorting.design`), matplotlib Figures out.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from fibersweep.plots.style import subplots

if TYPE_CHECKING:
    from fibersweep.sorting.measured import Measured

__all__ = ["critical_figure", "migration_figure", "outlets_figure"]


def _colours(n: int) -> list:
    import matplotlib

    cyc = matplotlib.rcParams["axes.prop_cycle"].by_key().get("color", ["k"])
    return [cyc[k % len(cyc)] for k in range(n)]


def migration_figure(
    table: pd.DataFrame,
    tilts: dict[int, float],
    labels: dict[int, str],
    crit: pd.DataFrame | None = None,
    level: float = 0.5,
    measured: Measured | None = None,
):
    """Mean f (± standard error) and migration angle (± sd) against length, per setting.

    The critical lengths (mean f crossing ``level``) are marked on every panel, with
    their 95 % interval (scatter and interpolation between the simulated lengths,
    ``ci_lo``–``ci_hi`` of the critical table) as a shaded band; the trapped share of
    each length (runs not in the means) has its own panel below. With ``measured``,
    the measured f and trapped share per length bin are black squares with their 95 %
    Wilson interval, labelled "measured (N fibers)", and the measured critical length
    a black dash-dotted line with its interval hatched.

    Parameters
    ----------
    table : DataFrame
        :func:`fibersweep.sorting.report.migration_table`.
    tilts : dict
        Array tilt atan ε [deg] per setting.
    labels : dict
        Label per setting ('' for a single setting).
    crit : DataFrame, optional
        :func:`fibersweep.sorting.report.critical_table`.
    measured : Measured, optional
        :func:`fibersweep.sorting.measured.compare`.
    """
    settings = sorted(table["setting"].unique())
    fig, (ax_f, ax_a, ax_t) = subplots(
        3, 1, figsize=(5.6, 6.4), sharex=True, layout="constrained",
        gridspec_kw={"height_ratios": [3, 3, 1.4]},
    )  # fmt: skip
    for s, col in zip(settings, _colours(len(settings)), strict=True):
        g = table[table["setting"] == s].sort_values("length")
        lab = labels.get(int(s)) or ("model" if measured is not None else "array")
        mine = crit[crit["setting"] == s] if crit is not None else crit
        if mine is not None and len(mine):
            both = mine["rising"].nunique() > 1  # a band: say which edge is which
            lab += (
                ": critical "
                + ", ".join(
                    (("rising " if r.rising else "falling ") if both else "")
                    + f"{r.critical:.1f}"
                    + (
                        f" (95 %: {r.ci_lo:.1f} to {r.ci_hi:.1f})"
                        if math.isfinite(r.ci_lo) and math.isfinite(r.ci_hi)
                        else ""
                    )
                    for r in mine.itertuples()
                )
                + " µm"
            )
        ax_f.errorbar(
            g["length"],
            g["fraction_mean"],
            yerr=g["fraction_se"].fillna(0.0),
            marker="o",
            ms=4,
            capsize=3,
            color=col,
            label=lab,
        )
        ax_t.plot(g["length"], g["trapped"], marker="o", ms=3, color=col)
        ax_a.errorbar(
            g["length"],
            g["angle_mean"],
            yerr=g["angle_std"].fillna(0.0),
            marker="o",
            ms=4,
            capsize=3,
            color=col,
        )
        ax_a.axhline(tilts[int(s)], color=col, ls=":", lw=0.8)
        if mine is not None:
            for r in mine.itertuples():
                for ax in (ax_f, ax_a, ax_t):
                    ax.axvline(r.critical, color=col, ls="--", lw=0.9)
                    if math.isfinite(r.ci_lo) and math.isfinite(r.ci_hi) and r.ci_hi > r.ci_lo:
                        ax.axvspan(r.ci_lo, r.ci_hi, color=col, alpha=0.12, lw=0)
    if measured is not None:
        _measured_points(ax_f, ax_t, measured)
    ax_f.axhline(level, color="0.5", lw=0.7, ls="-.")
    ax_f.axhline(0.0, color="0.8", lw=0.6)
    ax_f.axhline(1.0, color="0.8", lw=0.6)
    ax_f.set_ylabel("mean f of moving runs")
    title = (
        f"f = displacement per row / ε λy; dashed: critical lengths (f = {level:g}), "
        "shaded: their 95 % interval"
    )
    if measured is not None:
        title += (
            "\nsquares: measured (95 % Wilson interval); dash-dot, hatched: measured "
            "critical length (95 %)"
        )
    ax_f.set_title(title, fontsize=7)
    ax_a.axhline(0.0, color="0.5", lw=0.6)
    ax_t.set_ylim(-0.05, 1.05)
    ax_t.set_ylabel("share trapped")
    ax_t.set_xlabel("fiber length L [µm]")
    ax_a.set_ylabel("migration angle [deg]")
    ax_a.set_title(
        "mean ± sd; dotted: the array's tilt atan ε"
        + ("; the model's only (no angle measured)" if measured is not None else ""),
        fontsize=7,
    )
    fig.legend(loc="outside upper center", fontsize=7, frameon=False,
               ncol=1 if len(settings) > 2 else len(settings))  # fmt: skip
    return fig


def _measured_points(ax_f, ax_t, measured: Measured) -> None:
    """The measured bins (f and trapped share with their Wilson intervals) and the
    measured critical lengths on the f and trapped panels."""
    b = measured.bins
    lab = f"measured ({measured.binned} fibers)"
    c = measured.critical
    if len(c):
        lab += (
            ": critical "
            + ", ".join(
                f"{r.critical:.1f}"
                + (
                    f" (95 %: {r.ci_lo:.1f} to {r.ci_hi:.1f})"
                    if math.isfinite(r.ci_lo) and math.isfinite(r.ci_hi)
                    else ""
                )
                for r in c.itertuples()
            )
            + " µm"
        )
    f = b[b["moving"] > 0]
    yerr = np.vstack([f["fraction_mean"] - f["fraction_lo"], f["fraction_hi"] - f["fraction_mean"]])
    # a mean f a little below 0 (a zigzag) keeps its bar at 0: the interval is a share's
    ax_f.errorbar(f["length"], f["fraction_mean"], yerr=np.clip(yerr, 0.0, None), ls="none",
                  marker="s", ms=5, mfc="none", mec="k", ecolor="k", capsize=3, zorder=5,
                  label=lab)  # fmt: skip
    terr = np.vstack([b["trapped"] - b["trapped_lo"], b["trapped_hi"] - b["trapped"]])
    ax_t.errorbar(b["length"], b["trapped"], yerr=terr, ls="none", marker="s", ms=4,
                  mfc="none", mec="k", ecolor="k", capsize=2, zorder=5)  # fmt: skip
    for r in c.itertuples():
        for ax in (ax_f, ax_t):
            ax.axvline(r.critical, color="k", ls="-.", lw=0.9)
            if math.isfinite(r.ci_lo) and math.isfinite(r.ci_hi) and r.ci_hi > r.ci_lo:
                ax.axvspan(r.ci_lo, r.ci_hi, facecolor="none", edgecolor="0.75", hatch="//",
                           lw=0)  # fmt: skip


def outlets_figure(outlets: pd.DataFrame, labels: dict[int, str]):
    """Recovery (top row) and purity (bottom row) against length, one column per outlet;
    the trapped share (which leaves through no outlet) beside the recoveries.

    Recovery and purity are in panels of their own, so they never hide each other where
    they coincide (an outlet that takes one length only); within a panel the settings
    differ by colour and marker, with one line style.

    Parameters
    ----------
    outlets : DataFrame
        :func:`fibersweep.sorting.report.outlet_table`.
    labels : dict
        Label per setting (in words with units: :func:`fibersweep.plots.labels.describe`).
    """
    from matplotlib.lines import Line2D

    outs = sorted(outlets["outlet"].unique())
    settings = sorted(outlets["setting"].unique())
    n = len(outs) + 1
    fig, axes = subplots(
        2, n, figsize=(2.3 * n + 0.4, 4.6), sharex=True, sharey=True, squeeze=False,
        layout="constrained",
    )  # fmt: skip
    cols = _colours(len(settings))
    markers = ["o", "s", "^", "D", "v", "P", "X", "h"]
    style = {
        s: {"color": c, "marker": markers[k % len(markers)], "ms": 4, "lw": 1.1}
        for k, (s, c) in enumerate(zip(settings, cols, strict=True))
    }
    for c, k in enumerate(outs):
        sub = outlets[outlets["outlet"] == k]
        lo, hi = sub["from"].iloc[0], sub["to"].iloc[0]
        empty = []
        for s in settings:
            g = sub[sub["setting"] == s].sort_values("length")
            axes[0, c].plot(g["length"], g["recovery"], **style[s])
            axes[1, c].plot(g["length"], g["purity"], **style[s])
            if not np.isfinite(g["purity"].to_numpy(float)).any():
                empty.append(labels.get(int(s)) or "array")
        if empty:  # purity is undefined where no fiber leaves: say so, draw nothing
            axes[1, c].text(0.03, 0.97, "no fiber leaves here:\n" + "\n".join(empty),
                            transform=axes[1, c].transAxes, va="top", fontsize=7,
                            color="0.35")  # fmt: skip
        rng = (
            f"f < {hi:g}"
            if not math.isfinite(lo)
            else f"f ≥ {lo:g}"
            if not math.isfinite(hi)
            else f"{lo:g} ≤ f < {hi:g}"
        )
        axes[0, c].set_title(f"outlet {k} ({rng}): recovery", fontsize=8)
        axes[1, c].set_title(f"outlet {k}: purity", fontsize=8)
    for s in settings:
        g = outlets[(outlets["setting"] == s) & (outlets["outlet"] == outs[0])].sort_values(
            "length"
        )
        axes[0, -1].plot(g["length"], g["trapped"], **style[s])
    axes[0, -1].set_title("trapped (no outlet)", fontsize=8)
    axes[0, 0].set_ylabel("recovery\n(share of a length)")
    axes[1, 0].set_ylabel("purity\n(share of an outlet)")
    axes[0, 0].set_ylim(-0.04, 1.04)
    for ax in axes.ravel():
        ax.grid(True)
    for ax in axes[1, :-1]:
        ax.set_xlabel("fiber length L [µm]")
    axes[0, -1].set_xlabel("fiber length L [µm]")
    axes[0, -1].xaxis.set_tick_params(labelbottom=True)
    key = axes[1, -1]  # the free corner holds the key
    key.axis("off")
    handles = [Line2D([], [], **style[s], label=labels.get(int(s)) or "array") for s in settings]
    key.legend(handles=handles, loc="center", fontsize=7, frameon=False,
               title="recovery + trapped = 1\nper length", title_fontsize=7)  # fmt: skip
    return fig


def _value_axis(ax, key: str, values: np.ndarray) -> None:
    """A setting's axis: log over decades (a stiffness), ticks at the simulated values."""
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullFormatter

    from fibersweep.plots.labels import display_values, is_decades

    if is_decades(key, values):
        ax.set_xscale("log")
    xs = np.unique(display_values(key, values, array=True))
    if xs.size <= 8:
        ax.xaxis.set_major_locator(FixedLocator(xs))
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_formatter(NullFormatter())


def critical_figure(
    curve: pd.DataFrame,
    key: str,
    unit: str = "",
    answer=None,
    target: float | None = None,
    crossings: pd.DataFrame | None = None,
):
    """Critical lengths against a swept setting: where f rises through 1/2 (filled
    circles, solid line) and where it falls through it (open triangles, dashed line),
    each ± its statistical error (bars) in the bracket of simulated lengths it lies in
    (grey), with its 95 % interval where the table has one (``ci_lo``, ``ci_hi``: a pale
    bar); a combination without a crossing as an arrow from the simulated length that
    bounds it; the target and the answer, if given.

    Parameters
    ----------
    curve : DataFrame
        :func:`fibersweep.sorting.design.critical_curve` (one crossing per combination,
        and the bounds of those without one).
    key : str
        The setting (words and unit from :mod:`fibersweep.plots.labels`).
    unit : str
        Unused (the unit comes with the label); kept for callers that pass it.
    answer : DesignAnswer, optional
    target : float, optional
        Target critical length [µm].
    crossings : DataFrame, optional
        :func:`fibersweep.sorting.report.critical_table`: every crossing of every
        combination (a band-pass has a rising and a falling one); without it only the
        curve's crossing of each combination is drawn.
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    from fibersweep.plots.labels import axis_label, display_values, is_decades, short_name

    del unit
    fig, ax = subplots(figsize=(5.6, 3.8), layout="constrained")
    numeric = pd.api.types.is_numeric_dtype(curve["value"])
    value_of = dict(zip(curve["setting"], curve["value"], strict=True))
    group_of = dict(zip(curve["setting"], curve["group"], strict=True))
    groups = list(dict.fromkeys(curve["group"]))
    order = list(dict.fromkeys(curve["value"])) if not numeric else []

    def pos(values) -> np.ndarray:
        if numeric:
            return display_values(key, list(values), array=True)
        return np.array([order.index(v) for v in values], dtype=float)

    log_x = numeric and is_decades(key, curve["value"].to_numpy(float))
    # every crossing: the table's when given, else the curve's (one per combination)
    if crossings is not None and len(crossings):
        cr = crossings[crossings["setting"].isin(value_of)].copy()
    else:
        cr = curve[np.isfinite(curve["critical"].to_numpy(float))].copy()
    cr["value"] = cr["setting"].map(value_of)
    cr["group"] = cr["setting"].map(group_of)
    cr["rising"] = cr["rising"].astype(object).eq(True)
    kinds = (
        (True, "o", "-", "f rises through 1/2 (lower edge)"),
        (False, "v", "--", "f falls through 1/2 (upper edge)"),
    )
    handles, drawn_kinds, has_ci = [], set(), False
    cols = _colours(len(groups))
    for grp, col in zip(groups, cols, strict=True):
        g = cr[cr["group"] == grp]
        for rising, marker, ls, _ in kinds:
            k = g[g["rising"] == rising]
            if not len(k):
                continue
            drawn_kinds.add(rising)
            x = pos(k["value"])
            if not rising:  # a little to the right, so the two kinds' bars stay apart
                x = x * 1.06 if log_x else x + 0.012 * (np.ptp(pos(curve["value"])) or 1.0)
            ax.vlines(x, k["lo"], k["hi"], color="0.8", lw=7, zorder=1)
            if {"ci_lo", "ci_hi"} <= set(k.columns):  # the interval, scatter included
                ci = np.isfinite(k["ci_lo"].to_numpy(float))
                if ci.any():
                    has_ci = True
                    ax.vlines(x[ci], k["ci_lo"][ci], k["ci_hi"][ci], color=col, lw=2.6,
                              alpha=0.35, zorder=2)  # fmt: skip
            ax.errorbar(x, k["critical"], yerr=k["se"].fillna(0.0).to_numpy(float),
                        ls="none", marker=marker, ms=7, mfc=col if rising else "white",
                        mec=col, mew=1.3, capsize=3, color=col, zorder=4)  # fmt: skip
            # the line joins the first crossing of this kind of neighbouring setting
            # values, broken where a value has none (no line across a gap)
            first = k.sort_values("critical").drop_duplicates("setting")
            at = dict(zip(pos(first["value"]), first["critical"], strict=True))
            xs = np.unique(pos(curve.loc[curve["group"] == grp, "value"]))
            ys = np.array([at.get(xv, np.nan) for xv in xs], dtype=float)
            if np.isfinite(ys).sum() > 1:
                ax.plot(xs, ys, ls=ls, color=col, lw=1.1, zorder=3)
        if len(groups) > 1 and grp:
            handles.append(Patch(color=col, label=grp))
    # combinations without a crossing: f above 1/2 at every length (critical below the
    # shortest), or below it at every length (critical above the longest)
    none = curve[~np.isfinite(curve["critical"].to_numpy(float))]
    none = none[~none["setting"].isin(cr["setting"])]
    lengths = np.concatenate([cr[["lo", "hi"]].to_numpy(float).ravel(),
                              none[["lo", "hi"]].to_numpy(float).ravel()])  # fmt: skip
    lengths = lengths[np.isfinite(lengths)]
    span = float(np.ptp(lengths)) if lengths.size > 1 else 10.0
    bounds = False
    for r in none.itertuples():
        col = cols[groups.index(r.group)]
        xi = float(pos([r.value])[0])
        above = math.isfinite(r.hi)  # f > 1/2 at every length: critical < shortest
        bound = r.hi if above else r.lo
        if not math.isfinite(bound):
            continue
        bounds = True
        tip = bound - 0.25 * span if above else bound + 0.25 * span
        ax.annotate("", (xi, tip), (xi, bound), zorder=4,
                    arrowprops={"arrowstyle": "-|>", "color": col, "lw": 1.4,
                                "mutation_scale": 12})  # fmt: skip
        ax.plot([xi], [bound], marker="_", ms=14, mew=2.0, color=col, zorder=4)
        ax.annotate("f > 1/2 at every L" if above else "f < 1/2 at every L", (xi, bound),
                    xytext=(6, 4 if not above else -10), textcoords="offset points",
                    fontsize=7, color=col)  # fmt: skip
        ax.update_datalim([(xi, tip)])
    if numeric:
        _value_axis(ax, key, curve["value"].to_numpy(float))
    else:
        ax.set_xticks(range(len(order)), [str(v) for v in order])
        ax.set_xlim(-0.5, len(order) - 0.5)
    ax.margins(x=0.08)
    ax.autoscale_view()
    if target is not None:
        ax.axhline(target, color="#D55E00", ls="--", lw=1.0)
        handles.append(Line2D([], [], color="#D55E00", ls="--", label=f"target {target:g} µm"))
    if answer is not None and isinstance(answer.value, float):
        xa = float(pos([answer.value])[0]) if numeric else answer.value
        from fibersweep.plots.labels import value_text

        ax.axvline(xa, color="#D55E00", lw=0.9)
        what = f"answer {value_text(key, answer.value, array=True)}"
        if all(math.isfinite(v) for v in answer.span):
            ax.axvspan(*pos(list(answer.span)), color="#D55E00", alpha=0.1, lw=0)
            what += " (shaded: whatever the interpolation)"
        handles.append(Line2D([], [], color="#D55E00", lw=0.9, label=what))
    for rising, marker, ls, text in kinds:
        if rising in drawn_kinds:
            handles.insert(len([h for h in handles if isinstance(h, Line2D)
                                and h.get_marker() in ("o", "v")]),
                           Line2D([], [], color="k", marker=marker, ls=ls, ms=6,
                                  mfc="k" if rising else "white", label=text))  # fmt: skip
    if has_ci:
        handles.append(Line2D([], [], color="k", lw=2.6, alpha=0.35,
                              label="95 % interval (scatter and interpolation)"))  # fmt: skip
    handles.append(Patch(color="0.8", label="between the simulated lengths"))
    if bounds:
        text = "no crossing: the simulated length that bounds it"
        handles.append(Line2D([], [], color="k", marker="_", ms=10, mew=2, ls="none", label=text))
    ax.set_xlabel(axis_label(key, array=True))
    ax.set_ylabel("critical length [µm]")
    spread = "95 % interval, bars ± statistical error" if has_ci else "± statistical error"
    ax.set_title(f"critical length (mean f = 1/2) against {short_name(key, array=True)}, "
                 f"{spread}", fontsize=8)  # fmt: skip
    fig.legend(handles=handles, loc="outside lower center", ncol=2, fontsize=7, frameon=False)
    return fig
