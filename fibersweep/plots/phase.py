"""Figures of a sweep: phase diagram, δ map, contact map, δ distribution.

All in the model's normalised units: θ0 and θ_c in degrees, y0 and y_c as
y/h_obs from the pillar base, lengths as L/l_obs. Every figure is written to a
temporary file and renamed, like the tables.
"""

from __future__ import annotations

import logging
import math
import re
from collections.abc import Callable
from functools import partial
from pathlib import Path

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.colors import Normalize  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
from matplotlib.ticker import FuncFormatter, NullFormatter  # noqa: E402

from fibersweep.errors import InputError  # noqa: E402
from fibersweep.fiber.result import CLASSES  # noqa: E402
from fibersweep.plots import FORMATS  # noqa: E402
from fibersweep.plots.density import boundary_segments, column_cells, is_dense  # noqa: E402
from fibersweep.plots.style import (  # noqa: E402
    CLASS_STYLE,
    FAILED_STYLE,
    UNCLASSIFIED_STYLE,
    paper_style,
    save_figure,
    subplots,
)

__all__ = [
    "FORMATS",
    "contact_figure",
    "delta_hist_figure",
    "draw_boundaries",
    "facet_keys",
    "phase_figure",
    "plot_all",
    "swept_keys",
    "varying_keys",
]

log = logging.getLogger(__name__)

WIDTH_IN = 7.0  # two-column figure width [in]
THETA = r"$\theta_0$ [deg]"
Y0 = r"$y_0/h_{obs}$"


#: Columns that are the panel axes or per-run outcomes, never facets.
_NOT_FACETS = {"theta0", "y0", "id", "settings", "worker", "finished_at", "wall_time"}


def swept_keys(runs: pd.DataFrame) -> list[str]:
    """Columns of swept settings (dotted keys) in the runs table, in table order."""
    return [c for c in runs.columns if "." in c]


def varying_keys(runs: pd.DataFrame) -> list[str]:
    """Facet candidates that take more than one value: swept settings, then length."""
    keys = [*swept_keys(runs), "length"]
    return [k for k in keys if k in runs and runs[k].nunique(dropna=False) > 1]


def facet_keys(
    runs: pd.DataFrame, col: str | None = None, row: str | None = None
) -> tuple[str | None, str | None, list[str]]:
    """Columns and rows of the phase figures, and the keys left to split figures by.

    Defaults from what varies: the first varying key (swept settings before
    length) across, the second down; any further varying key gets one figure per
    value (:func:`plot_all`).

    Raises
    ------
    InputError
        ``col`` or ``row`` is not a column that can be faceted by (valid ones named).
    """
    valid = [c for c in [*swept_keys(runs), "length"] if c in runs]
    valid += [c for c in runs.columns if c not in valid and c not in _NOT_FACETS and c in {
        "model", "class", "contact"}]  # fmt: skip
    for opt, key in (("--col", col), ("--row", row)):
        if key is not None and key not in valid:
            raise InputError(f"{opt} {key!r}: not a column to facet by; valid: {', '.join(valid)}")
    if col is not None and col == row:
        raise InputError(f"--col and --row are both {col!r}")
    free = [k for k in varying_keys(runs) if k not in (col, row)]
    if col is None and free:
        col = free.pop(0)
    if row is None and free:
        row = free.pop(0)
    return col, row, free


def _grid(n: int, panel_h: float = 2.3) -> tuple[Figure, np.ndarray]:
    nrows = math.ceil(n / 4)
    ncols = math.ceil(n / nrows)  # balanced rows: 5 panels -> 3 + 2, not 4 + 1
    fig, axes = subplots(
        nrows,
        ncols,
        figsize=(WIDTH_IN if n > 1 else 4.2, panel_h * nrows + 0.6),
        sharex=True,
        sharey=True,
        squeeze=False,
    )
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    return fig, axes


def _values(runs: pd.DataFrame, key: str | None) -> list:
    if key is None:
        return [None]
    v = runs[key].dropna().unique().tolist()
    try:
        return sorted(v)
    except TypeError:
        return v


def _label(key: str) -> str:
    """Label of a facet key in words with units (:mod:`fibersweep.plots.labels`)."""
    if key == "length":
        return r"$L/l_{obs}$"
    from fibersweep.plots.labels import axis_label

    return axis_label(key)


def _value(key: str, value: object) -> str:
    """A facet's value in words with its unit: "friction coefficient = 0.3"."""
    from fibersweep.plots.labels import value_text

    return value_text(key, value.item() if hasattr(value, "item") else value)


def _fmt(v: object) -> str:
    return f"{v:.3g}" if isinstance(v, float) else str(v)


def _select(runs: pd.DataFrame, key: str | None, value: object) -> pd.DataFrame:
    if key is None:
        return runs
    col = runs[key]
    if isinstance(value, float):
        return runs[np.isclose(col.astype(float), value, rtol=1e-9, atol=1e-12)]
    return runs[col == value]


def _refined(runs: pd.DataFrame) -> bool:
    """Whether the table holds refinement runs (``round`` > 0)."""
    return "round" in runs and bool((runs["round"].fillna(0) > 0).any())


def _marker_size(panel: pd.DataFrame) -> float:
    """Markers that fill, but do not overlap on, the sweep's grid (refinement points left out)."""
    if _refined(panel):
        panel = panel[panel["round"].fillna(0) == 0]
    cells = max(1, panel["theta0"].nunique() * panel["y0"].nunique())
    return float(np.clip(2400.0 / cells, 5.0, 42.0))


def _sizes(panel: pd.DataFrame, s: float) -> np.ndarray | float:
    """Grid points at ``s``; refinement points smaller, so the boundaries they trace show."""
    if "round" not in panel:
        return s
    return np.where(panel["round"].fillna(0).to_numpy() > 0, 0.3 * s, s)


#: Look of the located class boundaries, and their legend entry.
BOUNDARY_STYLE = {"color": "0.1", "lw": 1.0}
BOUNDARY_LABEL = "boundary between runs"


def draw_boundaries(ax: Axes, panel: pd.DataFrame) -> bool:
    """Draw the class boundaries that a refined panel's runs support; True if any.

    Only where two neighbouring runs of different class bracket a boundary
    (:func:`fibersweep.plots.density.boundary_segments`): a tick across the
    column at the bracket's midpoint and a thin line over the bracket. Nothing
    is drawn between columns, where no run was made.
    """
    from matplotlib.collections import LineCollection

    ticks, spans, _ = boundary_segments(panel)
    if not len(ticks):
        return False
    ax.add_collection(LineCollection(spans, colors=BOUNDARY_STYLE["color"], linewidths=0.5,
                                     zorder=2))  # fmt: skip
    ax.add_collection(LineCollection(ticks, colors=BOUNDARY_STYLE["color"], zorder=4,
                                     linewidths=BOUNDARY_STYLE["lw"] * 1.3))  # fmt: skip
    ax.autoscale_view()
    return True


def _draw_cells(ax: Axes, good: pd.DataFrame, by: str, norm: Normalize) -> object:
    """A dense panel as a class map of its columns (one cell per run); the δ mappable or None."""
    from matplotlib.collections import PolyCollection

    rects, runs = column_cells(good)
    if not len(rects):
        return None
    if by == "class":
        colors = [_style(c)["color"] if c in CLASS_STYLE else UNCLASSIFIED_STYLE["color"]
                  for c in runs["class"]]  # fmt: skip
        ax.add_collection(PolyCollection(rects, facecolors=colors, edgecolors="none", zorder=2))
        ax.autoscale_view()
        return None
    d = runs["delta"].to_numpy(dtype=float)
    fin = np.isfinite(d)
    pc = PolyCollection(rects[fin], array=d[fin], cmap="RdBu_r", norm=norm, edgecolors="none",
                        zorder=2)  # fmt: skip
    ax.add_collection(pc)
    if (~fin).any():
        ax.add_collection(PolyCollection(rects[~fin], facecolors=DENSE_NO_DELTA, zorder=2,
                                         edgecolors="none"))  # fmt: skip
    ax.autoscale_view()
    return pc


#: Fill of a dense δ map's cells without δ (trapped runs).
DENSE_NO_DELTA = "0.15"


def _label_axes(axes: np.ndarray, n: int) -> None:
    ncols = axes.shape[1]
    for k, ax in enumerate(axes.flat[:n]):
        if k % ncols == 0:
            ax.set_ylabel(Y0)
        if k >= n - ncols:
            ax.set_xlabel(THETA)
            ax.xaxis.set_tick_params(labelbottom=True)


def _separatrix(ax: Axes, sep: float | None) -> None:
    if sep is not None and np.isfinite(sep):
        ax.axhline(sep, color="0.2", lw=1.0, ls="--", zorder=1)


def _style(cls: str) -> dict[str, object]:
    return CLASS_STYLE.get(cls, UNCLASSIFIED_STYLE)


def _present(runs: pd.DataFrame) -> list[str]:
    """Classes of the ok runs, in CLASSES order, then 'unclassified' if any run has none."""
    ok = runs.loc[runs["status"] == "ok", "class"]
    out = [c for c in CLASSES if (ok == c).any()]
    return out + (["unclassified"] if (~ok.isin(CLASSES)).any() else [])


def _of_class(df: pd.DataFrame, cls: str) -> pd.DataFrame:
    return df[~df["class"].isin(CLASSES)] if cls == "unclassified" else df[df["class"] == cls]


def _legend_handles(
    present: list[str], sep: float | None, failed: bool, dense: bool = False
) -> list:
    hs: list = [
        Line2D([], [], ls="", markersize=6, label=c, **_style(c))  # type: ignore[arg-type]
        for c in present
    ]
    if dense:  # some panel drawn as cells: their fill, beside the markers
        hs = [Patch(fc=_style(c)["color"], label=c) for c in present]
    if failed:
        hs.append(Line2D([], [], ls="", markersize=6, label="failed", **FAILED_STYLE))
    if sep is not None:
        hs.append(Line2D([], [], color="0.2", ls="--", lw=1.0, label=_sep_label(sep)))
    return hs


def _sep_label(sep: float) -> str:
    return f"separatrix ({sep:.3f})"


def phase_figure(
    runs: pd.DataFrame,
    separatrix: float | None | dict[str, float | None],
    by: str = "class",
    col: str | None = "length",
    row: str | None = None,
) -> Figure:
    """(θ0, y0/h) phase diagram, one panel per value of ``col`` (and ``row``).

    Parameters
    ----------
    runs : DataFrame
        The runs table (columns theta0, y0, length, class, status, delta).
    separatrix : float, None or dict
        Far-upstream y/h of the separatrix streamline; a dict maps settings id
        -> separatrix (a folder of several flow fields: drawn in a panel when its
        runs share one).
    by : {'class', 'delta'}
        Marker per class, or colour by δ on one colour scale shared by all panels.
    col, row : str or None
        Runs-table columns to facet by (:func:`facet_keys`); only ``col``: its
        panels wrap in rows of at most four.
    """
    cols, rows = _values(runs, col), _values(runs, row)
    if row is None:
        fig, axes = _grid(len(cols))
        cells = [(ax, c, None) for ax, c in zip(axes.flat, cols, strict=False)]
    else:
        fig, axes = subplots(
            len(rows), len(cols),
            figsize=(min(WIDTH_IN * 1.4, 2.0 + 2.4 * len(cols)), 2.3 * len(rows) + 0.6),
            sharex=True, sharey=True, squeeze=False,
        )  # fmt: skip
        cells = [(axes[i, j], c, r) for i, r in enumerate(rows) for j, c in enumerate(cols)]
    n_panels = len(cells)
    ok = runs["status"] == "ok"
    fin = runs.loc[ok, "delta"].to_numpy(dtype=float)
    fin = fin[np.isfinite(fin)]
    lim = float(np.percentile(np.abs(fin), 99)) if fin.size else 1.0
    norm = Normalize(-max(lim, 1e-3), max(lim, 1e-3))
    sc = None
    present = _present(runs)
    seps: set[float] = set()
    boundaries = False
    dense = False
    for ax, cv, rv in cells:
        p = _select(_select(runs, col, cv), row, rv)
        s = min(_marker_size(p), _spacing_limit(p, runs, ax)) if len(p) else 10.0
        sep = _panel_separatrix(p, separatrix)
        if sep is not None:
            seps.add(round(sep, 6))
        _separatrix(ax, sep)
        good = p[p["status"] == "ok"]
        if len(p) and is_dense(p, math.sqrt(s)):
            dense = True
            sc = _draw_cells(ax, good, by, norm) or sc
        elif by == "class":
            for c in present:
                q = _of_class(good, c)
                if len(q):
                    ax.scatter(
                        q["theta0"], q["y0"], s=_sizes(q, s), lw=0.4, edgecolor="k", **_style(c)
                    )
            if _refined(p):
                boundaries |= draw_boundaries(ax, p)
        else:
            has = good[np.isfinite(good["delta"].to_numpy(dtype=float))]
            sc = ax.scatter(
                has["theta0"], has["y0"], c=has["delta"], s=_sizes(has, s), cmap="RdBu_r",
                norm=norm, marker="o", lw=0.3, edgecolor="0.3",
            )  # fmt: skip
            trap = good[good["class"] == "Trapping"]
            if len(trap):
                ax.scatter(
                    trap["theta0"], trap["y0"], s=s, marker="D", facecolor="none",
                    edgecolor="k", lw=0.8,
                )  # fmt: skip
        bad = p[p["status"] != "ok"]
        if len(bad):
            ax.scatter(bad["theta0"], bad["y0"], s=max(s, 9.0), lw=1.0, zorder=5, **FAILED_STYLE)
        title = [_value(k, v) for k, v in ((col, cv), (row, rv)) if k is not None]
        if title and (len(cols) > 1 or len(rows) > 1):
            ax.set_title(", ".join(title), fontsize=7 if len(title) > 1 else None)
        elif n_panels == 1:
            ax.set_title(_fixed_title(runs, col, row))
    # settings fixed over a faceted figure head its legend (a suptitle would collide with it)
    fixed = _fixed_title(runs, col, row) if n_panels > 1 else ""
    legend_kw = {"title": fixed, "title_fontsize": "medium"} if fixed else {}
    thetas = np.unique(runs["theta0"].to_numpy(dtype=float))
    if 1 < thetas.size <= 9:  # few start angles: a tick at each, or at every other
        every = 1 if thetas.size * axes.shape[1] <= 18 else 2  # side by side, labels collide
        for ax, _, _ in cells:
            ax.set_xticks(thetas[::every])
            ax.xaxis.set_major_formatter("{x:g}")
    if row is None:
        _label_axes(axes, n_panels)
    else:
        for ax in axes[:, 0]:
            ax.set_ylabel(Y0)
        for ax in axes[-1, :]:
            ax.set_xlabel(THETA)
    failed = bool((~ok).any())
    legend_sep = next(iter(seps)) if len(seps) == 1 else None
    if by == "class":
        hs = _legend_handles(present, legend_sep, failed, dense)
        if boundaries:
            hs.append(Line2D([], [], label=BOUNDARY_LABEL, **BOUNDARY_STYLE))  # type: ignore[arg-type]
        if len(seps) > 1:
            hs.append(Line2D([], [], color="0.2", ls="--", lw=1.0, label="separatrix (per field)"))
        fig.legend(handles=hs, loc="outside upper center", ncol=_legend_columns(hs, n_panels),
                   frameon=False, **legend_kw)  # fmt: skip
    else:
        visible = [a for a in axes.flat if a.get_visible()]
        cb = fig.colorbar(sc, ax=visible, shrink=0.9, extend="both")
        cb.set_label(r"lateral displacement $\delta = (y_f - y_0)/h_{obs}$")
        hs = []
        if (runs.loc[ok, "class"] == "Trapping").any():
            hs.append(
                Patch(fc=DENSE_NO_DELTA, label="Trapping (no δ)")
                if dense
                else Line2D([], [], ls="", marker="D", mfc="none", mec="k", label="Trapping (no δ)")
            )
        if failed:
            hs.append(Line2D([], [], ls="", markersize=6, label="failed", **FAILED_STYLE))
        if legend_sep is not None:
            hs.append(Line2D([], [], color="0.2", ls="--", lw=1.0, label=_sep_label(legend_sep)))
        if hs:
            fig.legend(handles=hs, loc="outside upper center", ncol=_legend_columns(hs, n_panels),
                   frameon=False, **legend_kw)  # fmt: skip
        elif fixed:
            fig.suptitle(fixed, fontsize="medium")
    return fig


def _fixed_title(runs: pd.DataFrame, col: str | None, row: str | None) -> str:
    """Settings that are one value over the figure and no facet: length, then swept keys."""
    keys = [k for k in ("length", *swept_keys(runs)) if k in runs and k not in (col, row)]
    parts = []
    for k in keys:
        v = runs[k].dropna().unique()
        if len(v) == 1:
            parts.append(_value(k, v[0]))
    return ", ".join(parts)


def _single_length(runs: pd.DataFrame) -> str:
    """The fiber length of a table with one length, as a title; '' otherwise."""
    lengths = runs["length"].dropna().unique() if "length" in runs else []
    return f"{_label('length')} = {_fmt(float(lengths[0]))}" if len(lengths) == 1 else ""


def _legend_columns(handles: list, n_panels: int) -> int:
    """One row above a wide figure; at most three columns above a single panel."""
    return max(1, min(len(handles), 3 if n_panels == 1 else 6))


def _spacing_limit(panel: pd.DataFrame, runs: pd.DataFrame, ax: Axes) -> float:
    """Largest marker area [pt²] that does not overlap on the closest grid points.

    The closest pair of distinct θ0 (and y0) values of ``panel``'s grid (refinement
    points, ``round`` > 0, left out), over the range of ``runs``, at the size of
    ``ax`` on its figure: a grid denser in one place than another keeps apart.
    """
    if "round" in panel:
        panel = panel[panel["round"].fillna(0) == 0]
    fig_w, fig_h = ax.figure.get_size_inches()
    pos = ax.get_position()
    diam = 14.0
    for col, size_pt in (("theta0", pos.width * fig_w * 72), ("y0", pos.height * fig_h * 72)):
        vals = np.unique(panel[col].to_numpy(dtype=float))
        span = float(np.ptp(runs[col].to_numpy(dtype=float))) or 1.0
        if vals.size > 1:
            diam = min(diam, 0.85 * float(np.diff(vals).min()) / (1.1 * span) * size_pt)
    return float(max(diam, 2.5) ** 2)


def _panel_separatrix(
    panel: pd.DataFrame, separatrix: float | None | dict[str, float | None]
) -> float | None:
    """The separatrix of a panel's runs: the one value, or the one their settings share."""
    if not isinstance(separatrix, dict):
        return separatrix
    if "settings" not in panel or panel.empty:
        return None
    vals = {separatrix.get(sid) for sid in panel["settings"].unique()}
    vals = {v for v in vals if v is not None}
    return vals.pop() if len(vals) == 1 else None


def contact_figure(runs: pd.DataFrame) -> Figure:
    """Contact map: fiber angle θ_c and contact point y_c/h at first contact, by class."""
    fig, ax = subplots(figsize=(5.2, 3.4))
    c = runs[(runs["status"] == "ok") & runs["contact"].fillna(False).astype(bool)]
    c = c[np.isfinite(c["theta_c"].to_numpy(dtype=float))]
    for k in _present(c):
        q = _of_class(c, k)
        if len(q):
            ax.scatter(q["theta_c"], q["y_c"], s=16, lw=0.4, edgecolor="k", label=k, **_style(k))
    # y/h is quoted from the pillar's lowest point for every shape and rotation; only the
    # unrotated triangle has its apex at 1, so the upper line is named by its height
    # the two lines are named in the right margin, where no marker can cover the name
    for y, what in ((0.0, "base line"), (1.0, "base line\n" r"+ $h_{obs}$")):
        ax.axhline(y, color="0.6", lw=0.8, ls=":")
        ax.annotate(what, (1.0, y), xycoords=("axes fraction", "data"), ha="left", va="center",
                    xytext=(3, 0), textcoords="offset points", fontsize=7, color="0.4",
                    annotation_clip=False)  # fmt: skip
    ax.set_xlabel(r"$\theta_c$ at first contact [deg]")
    ax.set_ylabel(r"$y_c/h_{obs}$ at first contact")
    nl = runs["length"].nunique()
    lens = f", {_single_length(runs)}" if nl == 1 else f", {nl} lengths"
    ax.set_title(f"{len(c)} runs with contact{lens}")
    if len(c):
        fig.legend(frameon=False, loc="outside upper center", ncol=4)
    else:
        ax.text(0.5, 0.5, "no run touched the pillar", ha="center", transform=ax.transAxes)
    return fig


def delta_hist_figure(runs: pd.DataFrame) -> Figure:
    """Distribution of δ for runs with and without contact (counts per bin, log scale)."""
    fig, ax = subplots(figsize=(4.2, 3.0))
    ok = runs[(runs["status"] == "ok")]
    d = ok["delta"].to_numpy(dtype=float)
    touched = ok["contact"].fillna(False).astype(bool).to_numpy()
    fin = np.isfinite(d)
    if not fin.any():
        ax.text(0.5, 0.5, "no finite δ", ha="center", transform=ax.transAxes)
        return fig
    lo, hi = float(d[fin].min()), float(d[fin].max())
    pad = 0.05 * max(hi - lo, 1e-3)
    bins = np.linspace(lo - pad, hi + pad, 41)
    for mask, label, color in (
        (~touched, "no contact", "#0072B2"),
        (touched, "contact", "#D55E00"),
    ):
        x = d[fin & mask]
        if x.size:
            ax.hist(x, bins=bins, histtype="step", lw=1.5, color=color,
                    label=f"{label}: n = {x.size}, sd = {np.std(x):.4f}")  # fmt: skip
    # log counts, from 0.5 so that a bin holding a single run stands clear of the axis;
    # the legend goes above the axes, so the bars use the whole height
    ax.set_yscale("log")
    ax.set_ylim(0.5, 1.5 * ax.get_ylim()[1])
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel(r"$\delta = (y_f - y_0)/h_{obs}$")
    ax.set_ylabel("runs per bin")
    fig.legend(frameon=False, loc="outside upper center", ncol=1)
    n_trap = int((ok["class"] == "Trapping").sum())
    notes = [t for t in (_single_length(runs),) if t]
    if n_trap:
        notes.append(f"{n_trap} trapped runs have no δ")
    if notes:
        ax.set_title(", ".join(notes))
    return fig


def plot_all(
    runs: pd.DataFrame,
    out: Path | str,
    fmt: str = "png",
    *,
    separatrix: float | None | dict[str, float | None] = None,
    col: str | None = None,
    row: str | None = None,
) -> list[Path]:
    """Write every figure of a sweep's runs table.

    Parameters
    ----------
    runs : pandas.DataFrame
        The runs table (:func:`fibersweep.sweep.store.read_runs`).
    out : path
        Figure folder (created if missing).
    fmt : {'png', 'pdf', 'svg'}
    separatrix : float, dict or None
        Far-upstream separatrix y/h_obs, drawn as a line (a dict: per settings id).
    col, row : str, optional
        Facets of the phase figures (default from what varies, :func:`facet_keys`);
        keys that vary beyond them split the phase figures into one file per
        value (``phase-KEY=VALUE.png``).

    Returns
    -------
    list of Path
        phase, phase_delta, contact_map and delta_hist figures.

    Raises
    ------
    InputError
        Unknown format, unknown facet, or no runs.
    """
    if fmt not in FORMATS:
        raise InputError(f"--format {fmt!r}: expected one of {', '.join(FORMATS)}")
    if runs.empty:
        raise InputError("no runs to plot")
    col, row, rest = facet_keys(runs, col, row)
    if col is None and row is not None:
        col, row = row, None
    out = Path(out)
    paths = []
    pages: list[tuple[str, pd.DataFrame]] = [("", runs)]
    if rest:
        pages = []
        for values, page in runs.groupby(rest, sort=True):
            values = values if isinstance(values, tuple) else (values,)
            tag = "-".join(f"{k}={_fmt(v)}" for k, v in zip(rest, values, strict=True))
            pages.append(("-" + re.sub(r"[^A-Za-z0-9_.=+-]", "_", tag), page))
    figures: dict[str, Callable[[], Figure]] = {}
    for tag, page in pages:
        figures[f"phase{tag}"] = partial(phase_figure, page, separatrix, "class", col, row)
        figures[f"phase_delta{tag}"] = partial(phase_figure, page, separatrix, "delta", col, row)
    figures["contact_map"] = partial(contact_figure, runs)
    figures["delta_hist"] = partial(delta_hist_figure, runs)
    with paper_style():
        for name, make in figures.items():
            paths.append(save_figure(make(), out / f"{name}.{fmt}", format=fmt))
    log.info("wrote %d figures to %s", len(paths), out)
    return paths
