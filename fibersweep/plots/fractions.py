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
from scipy.stats import norm

from fibersweep.analysis.modes import MODES
from fibersweep.analysis.trajectory import CLASSES
from fibersweep.errors import InputError
from fibersweep.plots.phase import _fixed_title, _label, swept_keys
from fibersweep.plots.style import CLASS_STYLE, MODE_STYLE, subplots

__all__ = [
    "class_fractions",
    "delta_by_figure",
    "delta_spread",
    "fraction_keys",
    "fractions_figure",
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
    """Axis label of ``key``: the start coordinates as the phase diagrams write them
    (in a pillar array: L in µm, y0 a fraction of the period across the flow)."""
    if array:
        fixed = {"length": "L [µm]", "y0": r"$y_0/\lambda_y$", "theta0": r"$\theta_0$ [deg]"}
        return fixed.get(key) or _label(key)
    return {"theta0": r"$\theta_0$ [deg]", "y0": r"$y_0/h_{obs}$"}.get(key) or _label(key)


def _positions(values: pd.Series) -> tuple[np.ndarray, list[str] | None]:
    """Horizontal positions of ``values``: themselves if numeric, else 0, 1, 2... with labels."""
    if pd.api.types.is_numeric_dtype(values) and not pd.api.types.is_bool_dtype(values):
        return values.to_numpy(dtype=float), None
    order = list(dict.fromkeys(values.astype(str)))
    return np.array([order.index(v) for v in values.astype(str)], float), order


def fractions_figure(runs: pd.DataFrame, key: str, level: float = 0.95) -> Figure:
    """Class fractions against ``key``, each with its Wilson interval (:func:`class_fractions`).

    Points of different classes at one value are set slightly apart, so their
    intervals do not hide each other.
    """
    fr = class_fractions(runs, key, level)
    col, _, styles = outcome_of(runs)
    fig, ax = subplots(figsize=(5.2, 3.4), layout="constrained")
    classes = list(dict.fromkeys(fr[col]))
    x_all, labels = _positions(fr[key])
    values = np.unique(x_all)
    step = float(np.diff(values).min()) if values.size > 1 else 1.0
    for j, cls in enumerate(classes):
        sel = (fr[col] == cls).to_numpy()
        q = fr[sel]
        x = x_all[sel] + (j - (len(classes) - 1) / 2) * 0.06 * step
        st = styles[cls]
        # rounding can put an end a hair inside a fraction of 0 or 1
        err = np.clip([q["fraction"] - q["lo"], q["hi"] - q["fraction"]], 0.0, None)
        ax.errorbar(
            x, q["fraction"], yerr=err,
            marker=st["marker"], color=st["color"], mec="k", mew=0.4, ms=5, lw=1.0,
            capsize=2.5, label=cls,
        )  # fmt: skip
    if labels is not None:
        ax.set_xticks(range(len(labels)), labels)
    elif values.size <= 9:
        ax.set_xticks(values)
    ax.set_ylim(-0.03, 1.03)
    ax.set_xlabel(_axis_label(key, array=col == "mode"))
    ax.set_ylabel("fraction of runs" + (" in each mode" if col == "mode" else ""))
    n = fr.drop_duplicates(key)
    counts = f"{int(n['n'].min())}" if n["n"].nunique() == 1 else (
        f"{int(n['n'].min())}–{int(n['n'].max())}")  # fmt: skip
    what = "runs" if col == "mode" else "classified runs"
    title = f"{counts} {what} per value, {int(level * 100)} % Wilson intervals"
    if int(n["failed"].sum()):
        title += f"; {int(n['failed'].sum())} failed left out"
    fixed = _fixed_title(runs, key, None)
    if col == "mode":  # an array sweep: say which other settings each point pools
        pooled = [k for k in ("length", *swept_keys(runs)) if k != key and runs[k].nunique() > 1]
        if pooled:
            fixed = (
                ", ".join(
                    [fixed] * bool(fixed)
                    + [f"pooled over {'L' if k == 'length' else _label(k)}" for k in pooled]
                )
                + " (--where selects one)"
            )
    ax.set_title(title + (f"\n{fixed}" if fixed else ""), fontsize="small")
    fig.legend(loc="outside upper center", ncol=len(classes), frameon=False)
    return fig


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
    x_sp, labels = _positions(sp[key])
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
    fixed = _fixed_title(runs, key, None)
    ax.set_title(", ".join(notes) + (f"\n{fixed}" if fixed else ""), fontsize="small")
    fig.legend(handles=handles, loc="outside upper center", ncol=4, frameon=False)
    return fig


def _box(x: float, y: float, w: float, h: float):
    from matplotlib.patches import Rectangle

    return Rectangle((x, y), w, h, fc="k", alpha=0.25, ec="k", lw=0.6, zorder=4)
