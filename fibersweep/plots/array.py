"""Figures of a pillar-array sweep: cell flow, chronophotographs, migration, trajectories.

Every function takes data (no files) and returns a matplotlib Figure.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.patches import Circle, Polygon

from fibersweep.analysis.modes import MODES
from fibersweep.plots.style import subplots

__all__ = ["cell_flow_figure", "chrono_figure", "migration_figure", "overlay_figure"]

_MODE_COLOURS = dict(zip(MODES, ("#1f77b4", "#d62728", "#9467bd", "#7f7f7f", "#ff7f0e"),
                         strict=True))  # fmt: skip


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
    ax.set_title(f"unit cell ×9: ε = {arr.shift:g}, G = {d['gap']:.0f} µm, "
                 f"mean flow {field.meta['mean_flow_angle_deg']:.2f}°", fontsize=8)  # fmt: skip
    return fig


def chrono_figure(array, runs: list[dict], bead_radius: float, frames: int = 30):
    """One panel per run (a mode each): the fiber drawn at equal time intervals over the pillars.

    A run with stored bead positions (``traj_beads``, shape (samples, n_beads, 2) [µm];
    bead-spring runs with ``fiber.record.all_beads``) is drawn through its beads, so a
    bent or wrapped fiber shows its shape; otherwise as the straight rod of its angle.
    """
    fig, axes = subplots(len(runs), 1, figsize=(7.0, 1.9 * len(runs)), squeeze=False)
    for ax, run in zip(axes[:, 0], runs, strict=True):
        t = np.asarray(run["traj_t"])
        xc, yc, th = (np.asarray(run[f"traj_{c}"]) for c in ("xc", "yc", "th"))
        half = 0.5 * (run["n_beads"] - 1) * 2 * bead_radius
        times = np.linspace(t[0], t[-1], frames)
        k = np.searchsorted(t, times).clip(0, t.size - 1)
        col = _MODE_COLOURS.get(run["mode"], "k")
        beads = run.get("traj_beads")
        for j in k:
            if beads is not None:  # a flexible fiber: its beads, bent as they were
                ax.plot(beads[j, :, 0], beads[j, :, 1], color=col, lw=1.4, alpha=0.8,
                        solid_capstyle="round")  # fmt: skip
                continue
            c, s = math.cos(th[j]), math.sin(th[j])
            if half == 0.0:  # one bead: a sphere
                ax.add_patch(Circle((xc[j], yc[j]), bead_radius, fc=col, ec="none", alpha=0.8))
                continue
            ax.plot([xc[j] - half * c, xc[j] + half * c], [yc[j] - half * s, yc[j] + half * s],
                    color=col, lw=1.4, alpha=0.8, solid_capstyle="round")  # fmt: skip
        x0, x1 = xc.min() - half - 10, xc.max() + half + 10
        y0, y1 = yc.min() - half - 30, yc.max() + half + 30
        _pillars(ax, array, x0, x1, y0, y1)
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
        ax.set_aspect("equal")
        ax.set_title(f"{run['mode']}: L = {run['length']:g} µm, y0 = {run['y0']:.2f} λy, "
                     f"θ0 = {run['theta0']:.1f}°", fontsize=8)  # fmt: skip
        ax.set_ylabel("y [µm]")
    axes[-1, 0].set_xlabel("x [µm]")
    return fig


def migration_figure(table, tilts: dict[int, float], labels: dict[int, str]):
    """Mean migration angle ± one standard deviation against length, one line per setting."""
    fig, ax = subplots(figsize=(5.0, 3.6))
    for s, g in table.groupby("setting"):
        g = g.sort_values("length")
        line = ax.errorbar(g["length"], g["angle_mean"], yerr=g["angle_std"], marker="o",
                           capsize=3, label=labels.get(int(s)) or "array")  # fmt: skip
        ax.axhline(tilts[int(s)], color=line[0].get_color(), ls=":", lw=0.8)
    ax.axhline(0.0, color="0.5", lw=0.6)
    ax.set_xlabel("fiber length L [µm]")
    ax.set_ylabel("migration angle [deg]")
    ax.legend(fontsize=7, title="dotted: array tilt atan ε", title_fontsize=7)
    return fig


def overlay_figure(runs, period_x: float, lengths: list[float], ncols: int = 3):
    """Lateral displacement y − y0 against rows crossed, many fibers per length."""
    nrows = -(-len(lengths) // ncols)
    fig, axes = subplots(nrows, ncols, figsize=(2.4 * ncols, 2.2 * nrows), sharey=True,
                         sharex=True, squeeze=False)  # fmt: skip
    flat = axes.ravel()
    for ax, L in zip(flat, lengths, strict=False):
        for _, r in runs[runs["length"] == L].iterrows():
            x = (np.asarray(r["traj_xc"]) - r["traj_xc"][0]) / period_x
            y = np.asarray(r["traj_yc"]) - r["traj_yc"][0]
            ax.plot(x, y, color=_MODE_COLOURS.get(r["mode"], "k"), lw=0.6, alpha=0.7)
        ax.set_title(f"L = {L:g} µm", fontsize=8)
    for ax in flat[len(lengths) :]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("rows")
    for ax in axes[:, 0]:
        ax.set_ylabel("y − y0 [µm]")
    handles = [flat[0].plot([], [], color=c, label=m)[0] for m, c in _MODE_COLOURS.items()]
    flat[0].legend(handles=handles, fontsize=6)
    return fig
