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
                   ncols: int | None = None, shifts: dict | None = None):  # fmt: skip
    """Lateral displacement y − y0 [µm] against rows crossed, many fibers per panel.

    One panel per (setting, length) of ``runs`` (a setting's label in the title when
    there are several), coloured by mode; the dotted line is the array's tilt (a
    fiber in the displacement mode follows it), the grey one the mean flow.

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
        Panels per row (default: with several settings one per length, up to 7, so
        a row is a setting; with one, up to 3).
    shifts : dict, optional
        ε λy [µm] per setting index (the tilt line).
    """
    settings = sorted(runs["setting"].unique()) if "setting" in runs else [None]
    lengths = lengths if lengths is not None else sorted(runs["length"].unique())
    panels = [
        (s, L)
        for s in settings
        for L in lengths
        if ((runs["length"] == L) & ((runs["setting"] == s) if s is not None else True)).any()
    ]
    # one setting: rows of 3 panels; several: a row per setting (up to 7 lengths)
    ncols = min(ncols or min(len(lengths), 3 if len(settings) == 1 else 7), len(panels))
    nrows = -(-len(panels) // ncols)
    fig, axes = subplots(nrows, ncols, figsize=(2.3 * ncols, 2.0 * nrows + 0.4), sharey=True,
                         sharex=True, squeeze=False, layout="constrained")  # fmt: skip
    flat = axes.ravel()
    for ax, (s, L) in zip(flat, panels, strict=False):
        sel = runs["length"] == L
        if s is not None:
            sel &= runs["setting"] == s
        px = period_x[s] if isinstance(period_x, dict) else period_x
        rows_max = 0.0
        for _, r in runs[sel].iterrows():
            x = (np.asarray(r["traj_xc"]) - r["traj_xc"][0]) / px
            y = np.asarray(r["traj_yc"]) - r["traj_yc"][0]
            rows_max = max(rows_max, float(x.max()))
            ax.plot(x, y, color=MODE_STYLE.get(r["mode"], {"color": "k"})["color"], lw=0.7,
                    alpha=0.75)  # fmt: skip
        if shifts is not None and s in shifts:
            ax.plot([0, rows_max], [0, shifts[s] * rows_max], ":", color="k", lw=0.8)
        ax.axhline(0.0, color="0.6", lw=0.6)
        lab = runs.loc[sel, "setting_label"].iloc[0] if "setting_label" in runs else ""
        ax.set_title(f"L = {L:g} µm" + (f", {lab}" if lab and len(settings) > 1 else ""),
                     fontsize=7)  # fmt: skip
    for ax in flat[len(panels) :]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("rows crossed")
    for ax in axes[:, 0]:
        ax.set_ylabel("y − y0 [µm]")
    present = [m for m in MODE_STYLE if (runs["mode"] == m).any()]
    handles = [Line2D([], [], color=MODE_STYLE[m]["color"], label=m) for m in present]
    handles.append(Line2D([], [], color="k", ls=":", lw=0.8, label="array tilt"))
    fig.legend(handles=handles, loc="outside upper center", ncol=len(handles), fontsize=7,
               frameon=False)  # fmt: skip
    return fig
