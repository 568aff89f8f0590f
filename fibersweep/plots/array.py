"""Figures of a pillar-array sweep: the cell's flow and the fibers' paths through the rows.

Every function takes data (no files) and returns a matplotlib Figure. The
chronophotographs are in :mod:`.array_chrono`, the designer's figures (migration
and critical lengths, outlets, the critical length against a setting) in
:mod:`.array_design`; both are re-exported here.
"""

from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Polygon

from fibersweep.plots.array_chrono import chrono_figure
from fibersweep.plots.array_design import migration_figure
from fibersweep.plots.style import MODE_STYLE, subplots

__all__ = ["cell_flow_figure", "chrono_figure", "migration_figure", "overlay_figure"]


def _pillars(ax, array, x0, x1, y0, y1) -> None:
    for _, _, sh in array.images(x0, y0, x1, y1, 0.0):
        ax.add_patch(Polygon(sh.outline(64), closed=True, fc="0.75", ec="0.3", lw=0.6))


def cell_flow_figure(field):
    """Speed of the unit-cell midplane flow on a 3 × 3 block of cells, with streamlines."""
    arr = field.array
    pad = 0
    ux, uy = field.extended(pad)
    nx, ny = ux.shape
    reps = 3
    X = (np.arange(reps * nx) + 0.5) * field.dx
    big_u = np.zeros((reps * nx, reps * ny))
    big_v = np.zeros_like(big_u)
    for r in range(reps):
        for c in range(reps):
            s = int(field.meta["shift_cells"]) * r
            big_u[r * nx : (r + 1) * nx, c * ny : (c + 1) * ny] = np.roll(ux, s, axis=1)
            big_v[r * nx : (r + 1) * nx, c * ny : (c + 1) * ny] = np.roll(uy, s, axis=1)
    Y = (np.arange(reps * ny) + 0.5) * field.dx
    inside = np.zeros_like(big_u, dtype=bool)
    XX, YY = np.meshgrid(X, Y, indexing="ij")
    for _, _, sh in arr.images(0, 0, X[-1], Y[-1], 0.0):
        inside |= sh.inside(XX, YY)
    speed = np.hypot(big_u, big_v)
    speed[inside] = np.nan
    fig, ax = subplots(figsize=(5.2, 4.6))
    im = ax.pcolormesh(X, Y, speed.T, shading="auto", cmap="viridis")
    fig.colorbar(im, ax=ax, label="midplane speed [µm/s]")
    u = np.where(inside, 0.0, big_u).T
    v = np.where(inside, 0.0, big_v).T
    ax.streamplot(X, Y, u, v, color="w", linewidth=0.5, density=1.4, arrowsize=0.6)
    _pillars(ax, arr, X[0], X[-1], Y[0], Y[-1])
    ax.set_xlim(X[0], X[-1])
    ax.set_ylim(Y[0], Y[-1])
    ax.set_aspect("equal")
    ax.set_xlabel("x [µm]")
    ax.set_ylabel("y [µm]")
    d = arr.describe()
    angle = round(field.meta["mean_flow_angle_deg"], 2) or 0.0  # no "-0.00"
    ax.set_title(f"unit cell ×9: ε = {arr.shift:g}, G = {d['gap']:.0f} µm, "
                 f"mean flow {angle:.2f}°", fontsize=8)  # fmt: skip
    return fig


def overlay_figure(runs, period_x: float | dict, lengths: list[float] | None = None,
                   ncols: int | None = None, shifts: dict | None = None,
                   labels: dict | None = None, title: str = ""):  # fmt: skip
    """Lateral displacement y − y0 [µm] against rows crossed, many fibers per panel.

    One panel per (setting, length) of ``runs``, coloured by mode; the dotted line is
    the array's tilt (a fiber in the displacement mode follows it), the grey one the
    mean flow. With several settings the panels are a grid grouped by setting: one row
    per setting (named at the row's left), one column per length (named at the top);
    the reverse when there are fewer lengths than settings, or more than 10 lengths.
    One setting: rows of up to ``ncols`` panels, the setting named in the figure's title.

    Parameters
    ----------
    runs : DataFrame
        Array runs with ``traj_xc``, ``traj_yc``, ``mode``, ``length`` (and
        ``setting``, ``setting_label`` when several settings are drawn).
    period_x : float or dict
        λx [µm], or per setting index.
    lengths : list of float, optional
        The lengths to draw (default: all).
    ncols : int, optional
        One setting: panels per row (default up to 4, the rows balanced).
    shifts : dict, optional
        ε λy [µm] per setting index (the tilt line).
    labels : dict, optional
        Label of each setting index in words with units
        (:func:`fibersweep.plots.labels.describe`); default the runs' ``setting_label``.
    title : str
        What was selected (e.g. the ``--where`` expression), added to the title.
    """
    settings = sorted(runs["setting"].unique()) if "setting" in runs else [None]
    lengths = lengths if lengths is not None else sorted(runs["length"].unique())

    def label(s) -> str:
        if s is None:
            return ""
        if labels is not None and int(s) in labels:
            return labels[int(s)]
        if "setting_label" in runs:
            lab = runs.loc[runs["setting"] == s, "setting_label"]
            return str(lab.iloc[0]) if len(lab) else ""
        return ""

    def has(s, L) -> bool:
        sel = runs["length"] == L
        return bool((sel & (runs["setting"] == s) if s is not None else sel).any())

    if len(settings) == 1:
        panels = [(settings[0], L) for L in lengths if has(settings[0], L)]
        if ncols is None:  # balanced rows of up to 4: 6 panels are 3 + 3, not 4 + 2
            ncols = -(-len(panels) // -(-len(panels) // 4))
        ncols = min(ncols, len(panels))
        nrows = -(-len(panels) // ncols)
        grid = {divmod(k, ncols): p for k, p in enumerate(panels)}
        by_length = False
    else:
        # the reverse (a row per length, a column per setting) when it is the wider grid
        by_length = len(lengths) < len(settings) or len(settings) < len(lengths) > 10
        outer, inner = (lengths, settings) if by_length else (settings, lengths)
        nrows, ncols = len(outer), len(inner)
        grid = {
            (r, c): ((b, a) if by_length else (a, b))
            for r, a in enumerate(outer)
            for c, b in enumerate(inner)
        }
    w = 1.55 if ncols > 4 else 2.2
    fig, axes = subplots(nrows, ncols, figsize=(w * ncols + 0.5, 1.45 * nrows + 0.7),
                         sharey=True, sharex=True, squeeze=False, layout="constrained")  # fmt: skip
    for (r, c), (s, L) in grid.items():
        ax = axes[r, c]
        sel = runs["length"] == L
        if s is not None:
            sel &= runs["setting"] == s
        if not sel.any():
            ax.text(0.5, 0.5, "no runs", transform=ax.transAxes, ha="center", va="center",
                    color="0.5", fontsize=8)  # fmt: skip
            continue
        px = period_x[s] if isinstance(period_x, dict) else period_x
        rows_max = 0.0
        for _, run in runs[sel].iterrows():
            x = (np.asarray(run["traj_xc"]) - run["traj_xc"][0]) / px
            y = np.asarray(run["traj_yc"]) - run["traj_yc"][0]
            rows_max = max(rows_max, float(x.max()))
            colour = MODE_STYLE.get(run["mode"], {"color": "k"})["color"]
            ax.plot(x, y, color=colour, lw=0.7, alpha=0.75)
            if run["mode"] == "trapped":  # where it stopped (before a row: no line to see)
                ax.plot([x[-1]], [y[-1]], "D", ms=3.5, color=colour, mec="k", mew=0.4)
        if shifts is not None and s in shifts:
            ax.plot([0, rows_max], [0, shifts[s] * rows_max], ":", color="k", lw=0.8)
        ax.axhline(0.0, color="0.6", lw=0.6)
        if len(settings) == 1:
            ax.set_title(f"L = {L:g} µm ({int(sel.sum())} runs)", fontsize=8)
    for r, c in set(np.ndindex(nrows, ncols)) - set(grid):
        axes[r, c].set_visible(False)
    if len(settings) > 1:  # name the columns at the top, the rows at the left
        outer, inner = (lengths, settings) if by_length else (settings, lengths)
        for c, b in enumerate(inner):
            axes[0, c].set_title(label(b) if by_length else f"L = {b:g} µm", fontsize=8,
                                 fontweight="bold")  # fmt: skip
        for r, a in enumerate(outer):
            name = f"L = {a:g} µm" if by_length else label(a)
            axes[r, 0].set_ylabel(f"{name}\ny − y0 [µm]", fontsize=8)
    else:
        for r in range(nrows):
            axes[r, 0].set_ylabel("y − y0 [µm]")
    for c in range(ncols):
        col = [r for r in range(nrows) if (r, c) in grid]
        if col:
            axes[max(col), c].set_xlabel("rows crossed")
            axes[max(col), c].xaxis.set_tick_params(labelbottom=True)
    head = label(settings[0]) if len(settings) == 1 else ""
    head = ", ".join(p for p in (head, f"selected: {title}" if title else "") if p)
    if head:
        fig.suptitle(head, fontsize=9)
    present = [m for m in MODE_STYLE if (runs["mode"] == m).any()]
    handles = [
        Line2D([], [], color=MODE_STYLE[m]["color"], label=m,
               **({"marker": "D", "ms": 3.5, "mec": "k", "mew": 0.4} if m == "trapped" else {}))
        for m in present
    ]  # fmt: skip
    handles.append(Line2D([], [], color="k", ls=":", lw=0.8, label="array tilt"))
    fig.legend(handles=handles, loc="outside lower center" if head else "outside upper center",
               ncol=len(handles), fontsize=8, frameon=False)  # fmt: skip
    return fig
