"""Outcomes against one setting: class fractions with binomial intervals, δ with its spread.

Both figures take any column of the runs table as the horizontal axis: the
fiber length, a swept setting (``fiber.effects.friction``, a geometry key) or a
start coordinate. Numeric columns are drawn on a numeric axis, others (the
pillar's surface model, a shape name) one position per value.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import NullFormatter
from scipy.stats import norm

from fibersweep.analysis.modes import MODES
from fibersweep.analysis.trajectory import CLASSES
from fibersweep.errors import InputError
from fibersweep.plots.labels import axis_label, display_values, is_decades, value_text
from fibersweep.plots.phase import swept_keys
from fibersweep.plots.style import CLASS_STYLE, MODE_STYLE, subplots

__all__ = [
    "class_fractions",
    "delta_by_figure",
    "delta_spread",
    "fraction_keys",
    "fractions_figure",
    "pooled_keys",
    "wilson_interval",
]

#: Outcome and bookkeeping columns that are no setting to plot against.
_OUTCOMES = {
    "id", "class", "status", "reason", "delta", "contact", "theta_c", "y_c", "t_contact",
    "t_pass", "x_f", "y_f", "theta_f", "n_steps", "wall_time", "cpu_time", "settings",
    "worker", "attempts", "finished_at", "round", "t_end", "min_clearance", "class_rule",
    "max_curvature", "min_end_to_end", "max_tension", "max_wrap", "rows", "shift_per_row",
    "migration_angle", "fraction", "mode", "wraps", "contacts", "bridging", "time_on_pillars",
}  # fmt: skip


def outcome_of(runs: pd.DataFrame) -> tuple[str, tuple[str, ...], dict]:
    """What a run's outcome is: ('class', the channel's classes, their styles), or for
    pillar-array runs ('mode', the transport modes, their styles)."""
    if "mode" in runs and runs["mode"].notna().any():
        return "mode", MODES, MODE_STYLE
    return "class", CLASSES, CLASS_STYLE


def fraction_keys(runs: pd.DataFrame) -> list[str]:
    """Columns the outcome can be plotted against: swept settings, length, the starts, model."""
    keys = [*swept_keys(runs), "length", "theta0", "y0", "model", "n_beads"]
    extra = [c for c in runs.columns if c not in keys and c not in _OUTCOMES and "." not in c]
    return [k for k in [*keys, *extra] if k in runs and k not in _OUTCOMES]


def _check_key(runs: pd.DataFrame, key: str) -> None:
    valid = fraction_keys(runs)
    if key not in valid:
        raise InputError(f"--by {key!r}: not a setting of these runs; valid: {', '.join(valid)}")


def wilson_interval(k: np.ndarray, n: np.ndarray, level: float = 0.95) -> np.ndarray:
    """Wilson score interval of a binomial proportion k/n.

    Unlike the normal (Wald) interval it stays inside [0, 1] and is not empty
    at k = 0 or k = n, which is where class fractions of a sweep often sit.

    Parameters
    ----------
    k, n : array_like of int
        Successes and trials (n >= 1).
    level : float
        Two-sided confidence level.

    Returns
    -------
    ndarray, shape (2, ...)
        Lower and upper bounds of the proportion.
    """
    k = np.asarray(k, dtype=float)
    n = np.asarray(n, dtype=float)
    z = float(norm.ppf(0.5 + level / 2))
    p = k / n
    denom = 1.0 + z**2 / n
    centre = (p + z**2 / (2 * n)) / denom
    half = z / denom * np.sqrt(p * (1 - p) / n + z**2 / (4 * n**2))
    return np.stack([np.clip(centre - half, 0.0, 1.0), np.clip(centre + half, 0.0, 1.0)])


def class_fractions(runs: pd.DataFrame, key: str, level: float = 0.95) -> pd.DataFrame:
    """Fraction of the classified runs in each class (array runs: each mode), per value of ``key``.

    Parameters
    ----------
    runs : DataFrame
        The runs table; only runs with status ``ok`` and a class count.
    key : str
        Column to group by (:func:`fraction_keys`).
    level : float
        Confidence level of the Wilson intervals.

    Returns
    -------
    DataFrame
        Columns ``key``, ``class`` (or ``mode``: :func:`outcome_of`), ``k`` (runs of
        the class), ``n`` (classified runs at the value), ``failed`` (runs at the
        value without a class), ``fraction``, ``lo``, ``hi``; every class that occurs
        anywhere gets a row at every value (k may be 0).
    """
    _check_key(runs, key)
    col, names, _ = outcome_of(runs)
    ok = runs["status"].eq("ok") & runs[col].isin(names)
    counts = pd.crosstab(runs.loc[ok, key], runs.loc[ok, col])
    classes = [c for c in names if c in counts.columns]
    counts = counts.reindex(columns=classes, fill_value=0)
    failed = (~ok).groupby(runs[key]).sum().reindex(counts.index, fill_value=0)
    n = counts.sum(axis=1)
    rows = []
    for cls in classes:
        lo, hi = wilson_interval(counts[cls].to_numpy(), n.to_numpy(), level)
        rows.append(pd.DataFrame({
            key: counts.index, col: cls, "k": counts[cls].to_numpy(), "n": n.to_numpy(),
            "failed": failed.to_numpy(), "fraction": counts[cls].to_numpy() / n.to_numpy(),
            "lo": lo, "hi": hi,
        }))  # fmt: skip
    if not rows:
        raise InputError("no classified runs to count")
    return pd.concat(rows, ignore_index=True)


def _axis_label(key: str, array: bool = False) -> str:
    """Axis label of ``key`` in words with units (:func:`fibersweep.plots.labels.axis_label`;
    in a pillar array L in µm and y0 a fraction of the period across the flow)."""
    return axis_label(key, array)


def _positions(values: pd.Series, key: str = "") -> tuple[np.ndarray, list[str] | None]:
    """Horizontal positions of ``values``: themselves if numeric (in the unit of the axis),
    else 0, 1, 2... with labels."""
    if pd.api.types.is_numeric_dtype(values) and not pd.api.types.is_bool_dtype(values):
        return display_values(key, values.to_numpy(dtype=float)), None
    order = list(dict.fromkeys(values.astype(str)))
    return np.array([order.index(v) for v in values.astype(str)], float), order


def pooled_keys(runs: pd.DataFrame, key: str) -> list[str]:
    """Settings besides ``key`` that take several values in a pillar array's runs: the
    swept settings, then the length. Their values are not pooled into one point: each
    combination gets a panel of :func:`fractions_figure` (a channel's runs: none, its
    classes are counted over the starts)."""
    if outcome_of(runs)[0] != "mode":
        return []
    keys = [k for k in (*swept_keys(runs), "length") if k in runs and k != key]
    return [k for k in keys if runs[k].nunique(dropna=False) > 1]


def _fixed_text(runs: pd.DataFrame, key: str, facets: list[str], array: bool) -> str:
    """Settings that take one value over the figure (and are not drawn): "L = 80 µm"."""
    keys = [k for k in ("length", *swept_keys(runs)) if k in runs and k != key]
    parts = []
    for k in keys:
        v = runs[k].dropna().unique()
        if k not in facets and len(v) == 1:
            parts.append(value_text(k, v[0].item() if hasattr(v[0], "item") else v[0], array))
    return ", ".join(parts)


def _draw_fractions(ax, fr: pd.DataFrame, col: str, styles: dict, classes: list,
                    x_all: np.ndarray, step: float, log: bool) -> None:  # fmt: skip
    """One panel's points; those of different classes at one value set a little apart
    (by a fraction of the closest values' distance, in log space on a log axis)."""
    for j, cls in enumerate(classes):
        sel = (fr[col] == cls).to_numpy()
        if not sel.any():
            continue
        q = fr[sel]
        shift = (j - (len(classes) - 1) / 2) * 0.06 * step
        x = x_all[sel] * np.exp(shift) if log else x_all[sel] + shift
        st = styles[cls]
        # rounding can put an end a hair inside a fraction of 0 or 1
        err = np.clip([q["fraction"] - q["lo"], q["hi"] - q["fraction"]], 0.0, None)
        ax.errorbar(
            x, q["fraction"], yerr=err,
            marker=st["marker"], color=st["color"], mec="k", mew=0.4, ms=5, lw=1.0,
            capsize=2.5, label=cls,
        )  # fmt: skip


def fractions_figure(runs: pd.DataFrame, key: str, level: float = 0.95) -> Figure:
    """Class fractions against ``key``, each with its Wilson interval (:func:`class_fractions`).

    Points of different classes at one value are set slightly apart, so their
    intervals do not hide each other. A pillar array's runs are never pooled over
    another setting: each value of the settings that vary besides ``key``
    (:func:`pooled_keys`, at most two) has its panel, one row per value of a swept
    setting and one column per length. A setting over decades is on a log axis.

    Raises
    ------
    InputError
        More than two other settings vary (select with ``--where``).
    """
    col, names, styles = outcome_of(runs)
    array = col == "mode"
    facets = pooled_keys(runs, key)
    if len(facets) > 2:
        raise InputError(
            f"--by {key}: the runs vary in {', '.join(facets)} besides; one figure draws two of "
            "them as rows and columns of panels: select the others with --where, e.g. "
            f"--where '{facets[0]} == {runs[facets[0]].dropna().iloc[0]!r}'"
        )
    fr_all = class_fractions(runs, key, level)
    classes = list(dict.fromkeys(fr_all[col]))
    x_ref, labels = _positions(fr_all[key], key)
    values = np.unique(x_ref)
    log = labels is None and is_decades(key, fr_all[key].to_numpy(float))
    spread = np.log(values) if log else values
    step = float(np.diff(spread).min()) if values.size > 1 else 1.0
    rows_v = _facet_values(runs, facets[0]) if len(facets) == 2 else [None]
    cols_v = _facet_values(runs, facets[-1]) if facets else [None]
    if len(facets) == 1 and len(cols_v) > 5:  # one setting: rows of up to 4 panels
        n = len(cols_v)
        ncols = 4
        cells = [(None, v) for v in cols_v]
        nrows = -(-n // ncols)
    else:
        nrows, ncols = len(rows_v), len(cols_v)
        cells = [(r, c) for r in rows_v for c in cols_v]
    single = len(cells) == 1
    w = 5.2 if single else min(2.3 * ncols + 0.6, 11.0)
    fig, axes = subplots(nrows, ncols, figsize=(w, 3.4 if single else 2.2 * nrows + 1.0),
                         sharex=True, sharey=True, squeeze=False, layout="constrained")  # fmt: skip
    counts_n, failed = [], 0
    for k, (rv, cv) in enumerate(cells):
        ax = axes.flat[k]
        sub = runs
        parts = []
        for fk, fv in ((facets[0] if len(facets) == 2 else None, rv),
                       (facets[-1] if facets else None, cv)):  # fmt: skip
            if fk is not None:
                sub = sub[_matches(sub[fk], fv)]
                parts.append(value_text(fk, fv, array))
        if sub.empty:
            ax.text(0.5, 0.5, "no runs", transform=ax.transAxes, ha="center", va="center",
                    color="0.5")  # fmt: skip
        else:
            fr = class_fractions(sub, key, level)
            x_all, _ = _positions(fr[key], key)
            if labels is not None:
                x_all = np.array([labels.index(str(v)) for v in fr[key]], float)
            _draw_fractions(ax, fr, col, styles, classes, x_all, step, log)
            per = fr.drop_duplicates(key)
            counts_n += list(per["n"])
            failed += int(per["failed"].sum())
        if parts:
            ax.set_title(", ".join(parts), fontsize=8)
    for ax in axes.flat[len(cells) :]:
        ax.set_visible(False)
    for ax in axes.flat[: len(cells)]:
        if log:
            ax.set_xscale("log")
        if labels is not None:
            ax.set_xticks(range(len(labels)), labels)
        elif values.size <= 9:
            ax.set_xticks(values, [f"{v:g}" for v in values])
            ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_ylim(-0.03, 1.03)
        ax.grid(True, axis="y")
    if labels is None and values.size > 1 and not log:
        pad = 0.06 * (values.max() - values.min())
        axes.flat[0].set_xlim(values.min() - pad, values.max() + pad)
    for k in range(len(cells)):
        r, c = divmod(k, ncols)
        if r == nrows - 1 or k + ncols >= len(cells):
            axes[r, c].set_xlabel(_axis_label(key, array))
            axes[r, c].xaxis.set_tick_params(labelbottom=True)
        if c == 0:
            axes[r, c].set_ylabel("fraction of runs" + (" in each mode" if array else ""))
    lo, hi = (min(counts_n), max(counts_n)) if counts_n else (0, 0)
    counts = f"{lo}" if lo == hi else f"{lo}–{hi}"
    what = "runs" if array else "classified runs"
    title = f"{counts} {what} per point, {int(level * 100)} % Wilson intervals"
    if failed:
        title += f"; {failed} failed left out"
    fixed = _fixed_text(runs, key, facets, array)
    text = title + (f"\n{fixed}" if fixed else "")
    if single:
        axes[0, 0].set_title(text, fontsize="small")
    else:
        fig.suptitle(text, fontsize="small")
    # one row where it fits; below the panels when the title is the figure's (no overlap)
    ncol = len(classes) if w >= 6.5 or len(classes) <= 4 else 3
    seen: dict = {}
    for ax in axes.flat[: len(cells)]:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            seen.setdefault(lab, h)
    order = [c for c in classes if c in seen]
    fig.legend([seen[c] for c in order], order, ncol=ncol, frameon=False,
               loc="outside upper center" if single else "outside lower center")  # fmt: skip
    return fig


def _facet_values(runs: pd.DataFrame, key: str) -> list:
    v = runs[key].dropna().unique()
    try:
        return sorted(v.tolist())
    except TypeError:
        return list(dict.fromkeys(map(str, v)))


def _matches(col: pd.Series, value) -> pd.Series:
    if isinstance(value, float):
        return pd.Series(np.isclose(col.astype(float), value, rtol=1e-9), index=col.index)
    return col == value


def delta_spread(runs: pd.DataFrame, key: str = "length") -> pd.DataFrame:
    """Spread of the finite δ of the ok runs per value of ``key``.

    Returns
    -------
    DataFrame
        ``key``, ``n``, ``mean``, ``sd``, ``q05``, ``q25``, ``median``, ``q75``, ``q95``
        (δ in h_obs); values without a finite δ are left out.
    """
    _check_key(runs, key)
    d = runs[runs["status"].eq("ok")]
    d = d[np.isfinite(d["delta"].to_numpy(dtype=float))]
    if d.empty:
        raise InputError("no run with a finite δ")
    g = d.groupby(key, sort=True)["delta"]
    out = pd.DataFrame({
        "n": g.size(), "mean": g.mean(), "sd": g.std(ddof=1), "q05": g.quantile(0.05),
        "q25": g.quantile(0.25), "median": g.median(), "q75": g.quantile(0.75),
        "q95": g.quantile(0.95),
    })  # fmt: skip
    return out.reset_index()


def delta_by_figure(runs: pd.DataFrame, key: str = "length", seed: int = 0) -> Figure:
    """δ against ``key``: every run (jittered, by class), its median, quartiles and 5–95 %.

    Parameters
    ----------
    runs : DataFrame
    key : str
        Column of the horizontal axis (default the fiber length L/l_obs).
    seed : int
        Seed of the horizontal jitter of the points (the figure is reproducible).
    """
    sp = delta_spread(runs, key)
    d = runs[runs["status"].eq("ok")]
    d = d[np.isfinite(d["delta"].to_numpy(dtype=float))]
    fig, ax = subplots(figsize=(5.2, 3.4), layout="constrained")
    x_sp, labels = _positions(sp[key], key)
    mapping = dict(zip(sp[key].astype(str), x_sp, strict=True))
    x_runs = d[key].astype(str).map(mapping).to_numpy(dtype=float)
    step = float(np.diff(np.unique(x_sp)).min()) if x_sp.size > 1 else 1.0
    rng = np.random.default_rng(seed)
    jitter = rng.uniform(-0.12, 0.12, len(d)) * step
    handles = []
    for cls in [c for c in CLASSES if (d["class"] == c).any()]:
        m = (d["class"] == cls).to_numpy()
        st = CLASS_STYLE[cls]
        ax.scatter(x_runs[m] + jitter[m], d.loc[m, "delta"], s=7, marker=st["marker"],
                   color=st["color"], alpha=0.55, lw=0, zorder=1)  # fmt: skip
        handles.append(Line2D([], [], ls="", marker=st["marker"], color=st["color"], label=cls))
    w = 0.2 * step
    ax.vlines(x_sp, sp["q05"], sp["q95"], color="k", lw=0.8, zorder=3)
    for xi, r in zip(x_sp, sp.itertuples(index=False), strict=True):
        ax.add_patch(_box(xi - w / 2, r.q25, w, r.q75 - r.q25))
    ax.scatter(x_sp, sp["median"], marker="_", s=160, color="k", lw=1.6, zorder=5)
    handles += [
        Line2D([], [], color="k", marker="_", ls="", ms=10, mew=1.6, label="median"),
        Line2D([], [], color="k", lw=5, alpha=0.25, label="quartiles"),
        Line2D([], [], color="k", lw=0.8, label="5–95 %"),
    ]
    ax.axhline(0.0, color="0.6", lw=0.6, ls=":", zorder=0)
    if labels is not None:
        ax.set_xticks(range(len(labels)), labels)
    elif x_sp.size <= 9:
        ax.set_xticks(x_sp)
    ax.set_xlabel(_axis_label(key))
    ax.set_ylabel(r"$\delta = (y_f - y_0)/h_{obs}$")
    n_trap = int((runs["status"].eq("ok") & runs["class"].eq("Trapping")).sum())
    notes = [f"{len(d)} runs with δ"] + ([f"{n_trap} trapped (no δ)"] if n_trap else [])
    fixed = _fixed_text(runs, key, [], False)
    ax.set_title(", ".join(notes) + (f"\n{fixed}" if fixed else ""), fontsize="small")
    fig.legend(handles=handles, loc="outside upper center", ncol=4, frameon=False)
    return fig


def _box(x: float, y: float, w: float, h: float):
    from matplotlib.patches import Rectangle

    return Rectangle((x, y), w, h, fc="k", alpha=0.25, ec="k", lw=0.6, zorder=4)
