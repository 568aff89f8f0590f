"""Chronophotograph of one fiber run: the fiber at regular times over the pillar."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.colors import Normalize  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.patches import Polygon  # noqa: E402

from fibersweep.fiber.result import RunResult  # noqa: E402
from fibersweep.plots.shapes import fiber_points  # noqa: E402
from fibersweep.plots.style import paper_style, save_figure, subplots  # noqa: E402
from fibersweep.units import Geometry  # noqa: E402

__all__ = ["chrono_figure", "chronophotograph"]


def _window(traj, geometry: Geometry, margin: float) -> np.ndarray:
    """Samples whose fiber overlaps the x-window around the pillar."""
    x_lo, _, x_hi, _ = geometry.shape.bounds
    lo, hi = x_lo - margin, x_hi + margin
    xs = np.column_stack([traj.head[:, 0], traj.tail[:, 0]])
    return (xs.max(axis=1) > lo) & (xs.min(axis=1) < hi)


def chronophotograph(
    result: RunResult,
    geometry: Geometry,
    path: str | Path,
    *,
    snapshots: int = 24,
    margin: float | None = None,
) -> Path:
    """Write :func:`chrono_figure` to ``path`` (format from the suffix), atomically."""
    with paper_style():
        return save_figure(
            chrono_figure(result, geometry, snapshots=snapshots, margin=margin), path
        )


def chrono_figure(
    result: RunResult,
    geometry: Geometry,
    *,
    snapshots: int = 24,
    margin: float | None = None,
) -> Figure:
    """Draw the fiber at ``snapshots`` regular times near the pillar, coloured by time.

    Parameters
    ----------
    result : RunResult
        A run with a recorded trajectory (``record.trajectories``; every bead is
        drawn when recorded, else the straight head-tail segment of a rigid fiber;
        a bead-spring fiber without its beads raises
        :class:`~fibersweep.plots.shapes.ShapeNotStored`).
    geometry : Geometry
        Channel and pillar of the run.
    snapshots : int
        Fiber positions drawn.
    margin : float, optional
        Half-width added around the pillar in x [µm]; default one fiber length + 40 µm.

    Returns
    -------
    Figure
        Drawn in the package style when called inside :func:`paper_style`.
    """
    tr = result.trajectory
    if tr is None or len(tr.t) < 2:
        raise ValueError("the run has no recorded trajectory (set record.trajectories)")
    length = float(np.hypot(*(tr.head[0] - tr.tail[0]))) + 4.0
    margin = length + 40.0 if margin is None else margin
    win = _window(tr, geometry, margin)
    idx = np.flatnonzero(win)
    if idx.size < 2:
        idx = np.arange(len(tr.t))
    moving = tr.com_speed > 0.01 * float(np.max(tr.com_speed))
    if not moving[idx[-1]] and moving[idx].any():
        # a fiber that stops (trapped): end the window shortly after it stops
        last = idx[np.flatnonzero(moving[idx])[-1]]
        stop_t = tr.t[last] + 0.1 * (tr.t[last] - tr.t[idx[0]])
        idx = idx[tr.t[idx] <= stop_t]
    t0, t1 = tr.t[idx[0]], tr.t[idx[-1]]
    times = np.linspace(t0, t1, snapshots)
    picks = np.unique(np.clip(np.searchsorted(tr.t, times), 0, len(tr.t) - 1))
    xb, yb = geometry.base_center
    h = geometry.pillar_height
    outline = geometry.shape.outline()
    cmap = matplotlib.colormaps["viridis"]
    norm = Normalize(t0, t1)
    fig, ax = subplots(figsize=(7.0, 3.0))
    ax.add_patch(Polygon((outline - [xb, yb]) / h, closed=True, fc="0.8", ec="0.3", lw=1.0))
    segs = []
    for k in picks:
        beads = None if tr.beads is None else tr.beads[k]
        pts = fiber_points(result.model, result.n_beads, beads, ends=(tr.tail[k], tr.head[k]))
        segs.append((pts - [xb, yb]) / h)
    lc = LineCollection(segs, cmap=cmap, norm=norm, lw=2.0, capstyle="round")
    lc.set_array(tr.t[picks])
    ax.add_collection(lc)
    hx = (tr.head[picks, 0] - xb) / h
    hy = (tr.head[picks, 1] - yb) / h
    ax.scatter(hx, hy, c=tr.t[picks], cmap=cmap, norm=norm, s=9, zorder=3, label="head")
    sel = slice(idx[0], idx[-1] + 1)
    ax.plot((tr.x[sel] - xb) / h, (tr.y[sel] - yb) / h, "--", color="0.25", lw=0.9,
            label="centre of mass")  # fmt: skip
    if result.contact and np.isfinite(result.y_c):
        kc = int(np.argmax(tr.contact))
        ax.plot((tr.x[kc] - xb) / h, (tr.y[kc] - yb) / h, "x", color="#D55E00", ms=6,
                label="centre of mass at first contact")  # fmt: skip
    # every drawn fiber and the pillar inside the axes, a little room around them
    pts = np.vstack([*segs, (outline - [xb, yb]) / h])
    pad = 0.08
    ax.set_xlim(pts[:, 0].min() - pad, pts[:, 0].max() + pad)
    ax.set_ylim(min(pts[:, 1].min(), 0.0) - pad, pts[:, 1].max() + pad)
    ax.set_aspect("equal")
    ax.set_xlabel(r"$x/h_{obs}$ (from the pillar centroid)")
    ax.set_ylabel(r"$y/h_{obs}$ (from the base)")
    st = result.start
    cls = result.cls or f"failed: {result.reason}"
    ax.set_title(
        rf"$\theta_0$ = {st.theta0:g}°, $y_0/h_{{obs}}$ = {st.y0:g}, "
        rf"$L/l_{{obs}}$ = {st.length:g}  →  {cls}"
        + (rf",  $\delta$ = {result.delta:.3f}" if np.isfinite(result.delta) else "")
    )
    # the bar in the axes' own coordinates: exactly as tall as the (equal-aspect) axes
    cax = ax.inset_axes([1.015, 0.0, 0.018, 1.0])
    cb = fig.colorbar(lc, cax=cax)
    cb.set_label(r"$t$ [s]")
    ax.legend(loc="upper left", handlelength=1.5, borderaxespad=0.2)
    return fig
