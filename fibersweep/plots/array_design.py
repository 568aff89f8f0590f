"""The sorter designer's figures: f and migration against length with the critical
lengths marked, purity and recovery per outlet, the critical length against a
swept array setting. Data in (the tables of :mod:`fibersweep.sorting.report`
and :mod:`fibersweep.sorting.design`), matplotlib Figures out.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from fibersweep.plots.style import subplots

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
):
    """Mean f (± standard error) and migration angle (± sd) against length, per setting.

    The critical lengths (mean f crossing ``level``) are marked on both panels, with
    their statistical error as a shaded band; the trapped share of each length (runs
    not in the means) has its own panel below.

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
    """
    settings = sorted(table["setting"].unique())
    fig, (ax_f, ax_a, ax_t) = subplots(
        3, 1, figsize=(5.6, 6.4), sharex=True, layout="constrained",
        gridspec_kw={"height_ratios": [3, 3, 1.4]},
    )  # fmt: skip
    for s, col in zip(settings, _colours(len(settings)), strict=True):
        g = table[table["setting"] == s].sort_values("length")
        lab = labels.get(int(s)) or "array"
        mine = crit[crit["setting"] == s] if crit is not None else crit
        if mine is not None and len(mine):
            lab += (
                ": critical "
                + ", ".join(
                    f"{r.critical:.1f}" + (f" ± {r.se:.1f}" if math.isfinite(r.se) else "")
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
                    if math.isfinite(r.se) and r.se > 0:
                        ax.axvspan(
                            r.critical - r.se, r.critical + r.se, color=col, alpha=0.12, lw=0
                        )
    ax_f.axhline(level, color="0.5", lw=0.7, ls="-.")
    ax_f.axhline(0.0, color="0.8", lw=0.6)
    ax_f.axhline(1.0, color="0.8", lw=0.6)
    ax_f.set_ylabel("mean f of moving runs")
    ax_f.set_title(
        f"f = displacement per row / ε λy; dashed: critical lengths (f = {level:g}) ± error",
        fontsize=7,
    )
    ax_a.axhline(0.0, color="0.5", lw=0.6)
    ax_t.set_ylim(-0.05, 1.05)
    ax_t.set_ylabel("share trapped")
    ax_t.set_xlabel("fiber length L [µm]")
    ax_a.set_ylabel("migration angle [deg]")
    ax_a.set_title("mean ± sd; dotted: the array's tilt atan ε", fontsize=7)
    fig.legend(loc="outside upper center", fontsize=7, frameon=False,
               ncol=1 if len(settings) > 2 else len(settings))  # fmt: skip
    return fig


def outlets_figure(outlets: pd.DataFrame, labels: dict[int, str]):
    """Recovery (solid) and purity (dashed) against length, one panel per outlet, and the
    trapped share (which leaves through no outlet) in a last panel.

    Parameters
    ----------
    outlets : DataFrame
        :func:`fibersweep.sorting.report.outlet_table`.
    labels : dict
        Label per setting.
    """
    outs = sorted(outlets["outlet"].unique())
    settings = sorted(outlets["setting"].unique())
    n = len(outs) + 1
    fig, axes = subplots(
        1, n, figsize=(2.6 * n, 2.8), sharey=True, squeeze=False, layout="constrained"
    )
    axes = axes[0]
    cols = _colours(len(settings))
    for ax, k in zip(axes, outs, strict=False):
        sub = outlets[outlets["outlet"] == k]
        lo, hi = sub["from"].iloc[0], sub["to"].iloc[0]
        for s, col in zip(settings, cols, strict=True):
            g = sub[sub["setting"] == s].sort_values("length")
            ax.plot(
                g["length"],
                g["recovery"],
                "-o",
                ms=3,
                color=col,
                label=labels.get(int(s)) or "array",
            )
            ax.plot(g["length"], g["purity"], "--s", ms=3, color=col, mfc="none")
        rng = (
            f"f < {hi:g}"
            if not math.isfinite(lo)
            else f"f ≥ {lo:g}"
            if not math.isfinite(hi)
            else f"{lo:g} ≤ f < {hi:g}"
        )
        ax.set_title(f"outlet {k}: {rng}", fontsize=8)
        ax.set_xlabel("L [µm]")
    for s, col in zip(settings, cols, strict=True):
        g = outlets[(outlets["setting"] == s) & (outlets["outlet"] == outs[0])].sort_values(
            "length"
        )
        axes[-1].plot(g["length"], g["trapped"], "-D", ms=3, color=col)
    axes[-1].set_title("trapped (no outlet)", fontsize=8)
    axes[-1].set_xlabel("L [µm]")
    axes[0].set_ylabel("share")
    axes[0].set_ylim(-0.03, 1.03)
    from matplotlib.lines import Line2D

    handles = [
        Line2D([], [], color="k", marker="o", ms=3, label="recovery"),
        Line2D([], [], color="k", ls="--", marker="s", ms=3, mfc="none", label="purity"),
    ]
    if len(settings) > 1:
        handles += [
            Line2D([], [], color=c, label=labels.get(int(s)) or "array")
            for s, c in zip(settings, cols, strict=True)
        ]
    fig.legend(
        handles=handles,
        loc="outside upper center",
        ncol=min(len(handles), 6),
        fontsize=7,
        frameon=False,
    )
    return fig


def critical_figure(
    curve: pd.DataFrame, key: str, unit: str = "", answer=None, target: float | None = None
):
    """Critical length against a swept setting: ± its statistical error (bars) and the
    bracket of simulated lengths it lies in (grey); the target and the answer, if given.

    Parameters
    ----------
    curve : DataFrame
        :func:`fibersweep.sorting.design.critical_curve`.
    key : str
        The setting.
    unit : str
        Its unit ('' if none).
    answer : DesignAnswer, optional
    target : float, optional
        Target critical length [µm].
    """
    name = key.rsplit(".", 1)[-1]
    fig, ax = subplots(figsize=(5.0, 3.6), layout="constrained")
    numeric = pd.api.types.is_numeric_dtype(curve["value"])
    groups = list(dict.fromkeys(curve["group"]))
    for grp, col in zip(groups, _colours(len(groups)), strict=True):
        g = curve[curve["group"] == grp]
        g = g.sort_values("value") if numeric else g
        x = g["value"].to_numpy(float) if numeric else np.arange(len(g), dtype=float)
        ok = np.isfinite(g["critical"].to_numpy(float))
        ax.vlines(x[ok], g["lo"][ok], g["hi"][ok], color="0.75", lw=6, zorder=1)
        falls = ok & g["rising"].eq(False).fillna(False).to_numpy(bool)  # None: no crossing
        for sel, marker, face in ((ok & ~falls, "o", col), (falls, "v", "none")):
            if sel.any():
                ax.errorbar(
                    x[sel],
                    g["critical"][sel],
                    yerr=g["se"][sel].fillna(0.0),
                    marker=marker,
                    mfc=face,
                    capsize=3,
                    color=col,
                    zorder=3,
                    label=(grp or None) if marker == "o" or not (ok & ~falls).any() else None,
                )
        for xi, r in zip(x[~ok], g[~ok].itertuples(), strict=True):  # no crossing: a bound
            for bound, tip in ((r.lo, r.lo * 1.12), (r.hi, r.hi * 0.88)):
                if math.isfinite(bound):
                    ax.annotate("", (xi, tip), (xi, bound), arrowprops={"arrowstyle": "->"})
                    ax.plot([xi], [bound], "_", color=col, ms=10)
                    ax.update_datalim([(xi, tip)])  # the arrow inside the axes
                    break
        if not numeric:
            ax.set_xticks(x, g["value"].astype(str))
    values = curve["value"].to_numpy(float) if numeric else np.array([])
    if values.size and values.min() > 0 and values.max() >= 10 * values.min():
        ax.set_xscale("log")  # a setting over decades (a stiffness)
    ax.autoscale_view()
    if target is not None:
        ax.axhline(target, color="#D55E00", ls="--", lw=0.9, label=f"target {target:g} µm")
    if answer is not None and isinstance(answer.value, float):
        ax.axvline(answer.value, color="#D55E00", lw=0.9)
        if all(math.isfinite(v) for v in answer.span):
            ax.axvspan(*answer.span, color="#D55E00", alpha=0.1, lw=0)
        ax.annotate(
            f"{name} = {answer.value:.3g}",
            (answer.value, target or 0.0),
            xytext=(4, 6),
            textcoords="offset points",
            fontsize=7,
            color="#D55E00",
        )
    ax.set_xlabel(f"{name}" + (f" [{unit}]" if unit else ""))
    ax.set_ylabel("critical length [µm]")
    ax.set_title(
        "critical length: mean f = 1/2 (open triangles: f falls through it); bars:\n"
        "statistical error; grey: between the simulated lengths; arrows: none (f above\n"
        "or below 1/2 at every length)",
        fontsize=7,
    )
    if len(groups) > 1 or target is not None:
        ax.legend(fontsize=7)
    return fig
