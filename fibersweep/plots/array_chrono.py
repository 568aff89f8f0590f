"""A fiber through the rows of a pillar array: chronophotographs and animations.

A run crosses many rows (20 by default, 1600 µm for 80 µm periods) while the
events that make its mode happen within a row or two: the jump back of a
zigzag, a wrap round a pillar, the stop of a trapped fiber. Each panel is
therefore framed on a window of :data:`WINDOW_ROWS` rows around the event that
shows the mode (:func:`event_window`), drawn to scale with the pillars, the
fiber at regular times in that window (coloured by time) and its centre's path.
Flexible fibers are drawn through all their beads
(:func:`fibersweep.plots.shapes.fiber_points`).

Runs are dicts (or Series) with the columns of
:func:`fibersweep.results.load_array_results`: ``traj_t`` [s],
``traj_xc``, ``traj_yc`` [µm], ``traj_th`` [rad], ``traj_contact``, optionally
``traj_beads`` (samples, n_beads, 2) [µm], and ``mode``, ``length``, ``n_beads``,
``model``, ``y0``, ``theta0``, ``fraction``.
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.colors import Normalize
from matplotlib.patches import Circle, Polygon

from fibersweep.analysis.modes import row_crossings
from fibersweep.plots.shapes import fiber_points
from fibersweep.plots.style import MODE_STYLE, subplots

__all__ = [
    "WINDOW_ROWS",
    "animate_array_run",
    "chrono_figure",
    "event_window",
    "fraction_text",
    "run_dict",
    "run_figure",
    "snapshots",
]

#: Rows shown around the event of a panel.
WINDOW_ROWS = 3.0


def _get(run, name, default=None):
    v = run.get(name, default) if hasattr(run, "get") else default
    return default if v is None else v


def event_window(run, array) -> tuple[int, int, str]:
    """Sample range [i0, i1] to show, and what it shows.

    * trapped: the last rows before the stop;
    * otherwise the row whose lateral step differs most from the run's typical
      step (the jump back of a zigzag, the row a mixed fiber skips), when it differs
      by more than a quarter of the row shift; else the middle rows of the run.
    """
    x = np.asarray(run["traj_xc"], dtype=float)
    y = np.asarray(run["traj_yc"], dtype=float)
    px = array.period_x
    if run["mode"] == "trapped":
        x_mid = x[-1] - 0.5 * (WINDOW_ROWS - 1) * px
        what = "where it stopped"
    else:
        yk = row_crossings(x, y, px)
        steps = np.diff(yk)
        if steps.size >= 2:
            dev = np.abs(steps - np.median(steps))
            k = int(np.argmax(dev))
            if dev[k] > 0.25 * array.lateral_shift:
                x_mid, what = x[0] + (k + 0.5) * px, "its largest jump"
            else:
                k = steps.size // 2
                x_mid, what = x[0] + (k + 0.5) * px, "mid-run"
        else:
            x_mid, what = 0.5 * (x[0] + x[-1]), "the whole run"
    half = 0.5 * WINDOW_ROWS * px
    inside = np.flatnonzero((x >= x_mid - half) & (x <= x_mid + half))
    if inside.size < 2:
        return 0, x.size - 1, "the whole run"
    return int(inside[0]), int(inside[-1]), what


def snapshots(run, bead_radius: float, i0: int, i1: int, frames: int) -> tuple[list, np.ndarray]:
    """The fiber at ``frames`` regular times between samples i0 and i1: (points, times).

    Each element of points has shape (m, 2) [µm]: every bead of a flexible fiber,
    the two ends of a rigid one (one point for a sphere).
    """
    t = np.asarray(run["traj_t"], dtype=float)
    xc, yc, th = (np.asarray(run[f"traj_{c}"], dtype=float) for c in ("xc", "yc", "th"))
    beads = _get(run, "traj_beads")
    n = int(run["n_beads"])
    half = 0.5 * (n - 1) * 2 * bead_radius
    times = np.linspace(t[i0], t[i1], frames)
    picks = np.unique(np.searchsorted(t, times).clip(i0, i1))
    pts = [
        fiber_points(
            _get(run, "model", "rigid"),
            n,
            None if beads is None else beads[k],
            centre=(xc[k], yc[k]),
            angle=th[k],
            half_length=half,
        )
        for k in picks
    ]
    return pts, t[picks]


def _beads_text(n: int) -> str:
    return "one bead, a sphere" if n == 1 else f"{n} beads"


def _pillars(ax, array, x0, x1, y0, y1) -> None:
    for _, _, sh in array.images(x0, y0, x1, y1, 0.0):
        ax.add_patch(Polygon(sh.outline(64), closed=True, fc="0.82", ec="0.3", lw=0.7, zorder=1))


def _frame(run, array, bead_radius: float, frames: int) -> dict:
    """What one panel draws: the window, the snapshots, the limits [µm]."""
    i0, i1, what = event_window(run, array)
    pts, times = snapshots(run, bead_radius, i0, i1, frames)
    xc = np.asarray(run["traj_xc"], dtype=float)[i0 : i1 + 1]
    yc = np.asarray(run["traj_yc"], dtype=float)[i0 : i1 + 1]
    allp = np.vstack(pts)
    reach = bead_radius + 6.0
    x0 = min(allp[:, 0].min(), xc.min()) - reach
    x1 = max(allp[:, 0].max(), xc.max()) + reach
    y0 = min(allp[:, 1].min(), yc.min()) - reach
    y1 = max(allp[:, 1].max(), yc.max()) + reach
    # whole pillars that the frame cuts, so the obstacles that steer the fiber show
    box = (x0, y0, x1, y1)
    for _, _, sh in array.images(*box, 0.0):
        px0, py0, px1, py1 = sh.bounds
        if px1 > box[0] and px0 < box[2] and py1 > box[1] and py0 < box[3]:
            x0, x1 = min(x0, px0 - 3.0), max(x1, px1 + 3.0)
            y0, y1 = min(y0, py0 - 3.0), max(y1, py1 + 3.0)
    return {
        "i0": i0,
        "i1": i1,
        "what": what,
        "pts": pts,
        "times": times,
        "xc": xc,
        "yc": yc,
        "lim": (x0, x1, y0, y1),
    }


def _draw(ax, run, array, bead_radius: float, fr: dict):
    """One framed panel (:func:`_frame`); returns the time colour mapping (for a colour bar)."""
    pts, times, xc, yc = fr["pts"], fr["times"], fr["xc"], fr["yc"]
    norm = Normalize(times[0], times[-1] if times[-1] > times[0] else times[0] + 1.0)
    cmap = matplotlib.colormaps["viridis"]
    lines = [p for p in pts if len(p) > 1]
    if lines:
        lc = LineCollection(lines, cmap=cmap, norm=norm, lw=2.2, capstyle="round", zorder=3)
        lc.set_array(np.array([tk for p, tk in zip(pts, times, strict=True) if len(p) > 1]))
        ax.add_collection(lc)
    for p, tk in zip(pts, times, strict=True):
        if len(p) == 1:  # a sphere
            ax.add_patch(
                Circle(tuple(p[0]), bead_radius, fc=cmap(norm(tk)), ec="k", lw=0.3, zorder=3)
            )
    ax.plot(xc, yc, "--", color="0.3", lw=0.8, zorder=2)
    x0, x1, y0, y1 = fr["lim"]
    _pillars(ax, array, x0, x1, y0, y1)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    rows = (xc[0] - float(run["traj_xc"][0])) / array.period_x
    rows_end = (xc[-1] - float(run["traj_xc"][0])) / array.period_x
    total = (float(run["traj_xc"][-1]) - float(run["traj_xc"][0])) / array.period_x
    label = _get(run, "setting_label", "")
    f = _get(run, "fraction", math.nan)
    where = (
        f"rows {rows:.0f}–{rows_end:.0f} of {total:.0f} ({fr['what']})"
        if total >= 1
        else f"{fr['what']}, before crossing a row"
    )
    ax.set_title(
        f"{run['mode']}: L = {run['length']:g} µm ({_beads_text(int(run['n_beads']))})"
        + (f", {label}" if label else "")
        + (f"; f = {f:.2f}" if math.isfinite(f) else "")
        + f"; {where}",
        fontsize=7,
        loc="left",
    )
    ax.set_ylabel("y [µm]")
    return cmap, norm


def chrono_figure(
    array, runs: list, bead_radius: float, frames: int = 18, arrays: list | None = None
):
    """One panel per run, each framed on the event of its mode (module docstring).

    Parameters
    ----------
    array : PillarArray
        The array of the runs (``arrays`` gives one per run when they differ).
    runs : list of dict
        The runs to draw (module docstring).
    bead_radius : float
        a [µm].
    frames : int
        Fiber positions drawn per panel.
    arrays : list of PillarArray, optional
        One array per run.

    Raises
    ------
    ShapeNotStored
        A flexible run without its stored bead positions.
    """
    arrays = arrays or [array] * len(runs)
    frs = [_frame(run, arr, bead_radius, frames) for run, arr in zip(runs, arrays, strict=True)]
    ratios = [(f["lim"][3] - f["lim"][2]) / (f["lim"][1] - f["lim"][0]) for f in frs]
    width = 7.0
    heights = [float(np.clip(6.3 * r, 1.0, 5.0)) + 0.5 for r in ratios]
    fig, axes = subplots(
        len(runs),
        1,
        figsize=(width, sum(heights)),
        squeeze=False,
        layout="constrained",
        gridspec_kw={"height_ratios": heights},
    )
    for ax, run, arr, fr in zip(axes[:, 0], runs, arrays, frs, strict=True):
        cmap, norm = _draw(ax, run, arr, bead_radius, fr)
        cb = fig.colorbar(
            matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, fraction=0.025, pad=0.01
        )
        cb.set_label("t [s]", fontsize=7)
        cb.ax.tick_params(labelsize=6)
    axes[-1, 0].set_xlabel("x [µm] (flow →)")
    return fig


def animate_array_run(
    run,
    array,
    bead_radius: float,
    path: str | Path,
    *,
    frames: int = 120,
    fps: int = 20,
    dpi: int = 130,
    label: str = "",
) -> Path:
    """Write one array run as an animation: the fiber crossing the rows, the view following it.

    ``.gif`` (Pillow) or ``.mp4`` (ffmpeg), written atomically; the fiber is drawn
    through every bead of a flexible fiber (:func:`fibersweep.plots.shapes.fiber_points`).
    Frames are 8 in wide at ``dpi`` (1040 px at the default); the clock and the row
    are written above the axes, where no pillar is. ``label``: the run's setting in
    words (e.g. "E = 10 kPa"), in the title.

    Raises
    ------
    InputError
        Unknown suffix, no ffmpeg for an MP4.
    ShapeNotStored
        A flexible run without its stored bead positions.
    """
    import shutil
    import tempfile

    from matplotlib import animation

    from fibersweep.atomic import atomic_path
    from fibersweep.errors import InputError
    from fibersweep.plots.tracks import ANIMATION_FORMATS, movie_writer

    out = Path(path)
    writer_name = ANIMATION_FORMATS.get(out.suffix.lower())
    if writer_name is None:
        raise InputError(f"{out}: animation formats are {', '.join(ANIMATION_FORMATS)}")
    if writer_name == "ffmpeg" and not animation.FFMpegWriter.isAvailable():
        raise InputError(f"{out}: an MP4 needs the ffmpeg program on the PATH; write a .gif")
    t = np.asarray(run["traj_t"], dtype=float)
    xc = np.asarray(run["traj_xc"], dtype=float)
    yc = np.asarray(run["traj_yc"], dtype=float)
    pts, times = snapshots(run, bead_radius, 0, t.size - 1, frames)
    allp = np.vstack(pts)
    half_w = 0.5 * WINDOW_ROWS * array.period_x
    ymin, ymax = allp[:, 1].min() - 15, allp[:, 1].max() + 15
    half_h = max(
        0.5 * (ymax - ymin) / max(1.0, (xc[-1] - xc[0]) / (2 * half_w)), 0.6 * array.period_y
    )
    width = 8.0
    fig, ax = subplots(figsize=(width, width * half_h / half_w + 1.0), layout="constrained")
    _pillars(
        ax,
        array,
        xc.min() - 2 * half_w,
        xc.max() + 2 * half_w,
        ymin - 2 * half_h,
        ymax + 2 * half_h,
    )
    ax.plot(xc, yc, color="0.75", lw=0.8, ls="--")
    colour = MODE_STYLE.get(str(run["mode"]), {"color": "k"})["color"]
    (trail,) = ax.plot([], [], color=colour, lw=1.0)
    (fiber,) = ax.plot(
        [],
        [],
        color="k",
        lw=2.5,
        solid_capstyle="round",
        marker="o" if len(pts[0]) == 1 else None,
        ms=2 * bead_radius,
    )
    clock = ax.set_title(" ", loc="left", fontsize=9, family="monospace")  # above the axes
    ax.set_aspect("equal")
    ax.set_xlabel("x [µm] (flow →)")
    ax.set_ylabel("y [µm]")
    fig.suptitle(
        f"{run['mode']}: L = {run['length']:g} µm"
        + (f", {label}" if label else "")
        + f"; start y0 = {run['y0']:.2f} λy, θ0 = {run['theta0']:.1f}°; {fraction_text(run)}",
        fontsize=9,
    )
    picks = np.searchsorted(t, times).clip(0, t.size - 1)

    def draw(k: int) -> tuple:
        p = pts[k]
        fiber.set_data(p[:, 0], p[:, 1])
        i = picks[k]
        trail.set_data(xc[: i + 1], yc[: i + 1])
        cx, cy = p[:, 0].mean(), p[:, 1].mean()
        ax.set_xlim(cx - half_w, cx + half_w)
        ax.set_ylim(cy - half_h, cy + half_h)
        clock.set_text(f"t = {times[k]:.2f} s, row {(cx - xc[0]) / array.period_x:.1f}")
        return fiber, trail, clock

    anim = animation.FuncAnimation(fig, draw, frames=len(pts), blit=False)
    writer = movie_writer(writer_name, fps)
    with tempfile.TemporaryDirectory() as scratch, atomic_path(out) as tmp:
        draft = Path(scratch) / f"animation{out.suffix.lower()}"
        anim.save(str(draft), writer=writer, dpi=dpi)
        shutil.copyfile(draft, tmp)
    return out


def fraction_text(run) -> str:
    """What the run's displacement fraction is: "f = 0.93"; a run that crossed no row has
    none ("trapped before row 1", or "f = —")."""
    f = _get(run, "fraction", math.nan)
    try:
        f = float(f)
    except (TypeError, ValueError):
        f = math.nan
    if math.isfinite(f):
        return f"f = {f:.2f}"
    if str(_get(run, "mode", "")) == "trapped":
        rows = _get(run, "rows", 0)
        rows = int(rows) if isinstance(rows, int | float) and math.isfinite(rows) else 0
        return f"trapped before row {rows + 1} (no f)"
    return "f = —"


def run_dict(result, bead_radius: float) -> dict:
    """A :class:`~fibersweep.fiber.result.RunResult` of an array run as the run dict the
    figures here take (``traj_*`` from its kept trajectory)."""
    tr = result.trajectory
    st = result.start
    return {
        "traj_t": tr.t,
        "traj_xc": tr.x,
        "traj_yc": tr.y,
        "traj_th": np.radians(tr.theta),
        "traj_contact": np.asarray(tr.contact, dtype=float),
        "traj_speed": tr.com_speed,
        "traj_beads": tr.beads,
        "mode": result.mode,
        "length": st.length,
        "y0": st.y0,
        "theta0": st.theta0,
        "n_beads": result.n_beads,
        "model": result.model,
        "fraction": result.fraction,
    }


def run_figure(array, run, bead_radius: float, frames: int = 18):
    """One run through the rows: its lateral displacement against the rows crossed (the
    stretch drawn below shaded), and the chronophotograph framed on its event."""
    fr = _frame(run, array, bead_radius, frames)
    x0, x1, y0, y1 = fr["lim"]
    ratio = (y1 - y0) / (x1 - x0)
    fig, (top, ax) = subplots(
        2,
        1,
        figsize=(7.0, 2.4 + float(np.clip(6.3 * ratio, 1.0, 5.0)) + 0.5),
        layout="constrained",
        gridspec_kw={"height_ratios": [2.0, float(np.clip(6.3 * ratio, 1.0, 5.0)) + 0.5]},
    )
    xc = np.asarray(run["traj_xc"], dtype=float)
    yc = np.asarray(run["traj_yc"], dtype=float)
    rows = (xc - xc[0]) / array.period_x
    colour = MODE_STYLE.get(str(run["mode"]), {"color": "k"})["color"]
    top.plot(rows, yc - yc[0], color=colour, lw=1.2, label=f"this run ({run['mode']})")
    top.plot([0, rows.max()], [0, array.lateral_shift * rows.max()], ":", color="k", lw=0.8,
             label="array tilt (displacement)")  # fmt: skip
    top.axhline(0.0, color="0.6", lw=0.6, label="mean flow (zigzag)")
    top.axvspan(rows[fr["i0"]], rows[fr["i1"]], color="0.85", lw=0, label="drawn below")
    top.set_xlabel("rows crossed")
    top.set_ylabel("y − y0 [µm]")
    top.legend(fontsize=6, ncol=4, loc="upper left")
    cmap, norm = _draw(ax, run, array, bead_radius, fr)
    cb = fig.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, fraction=0.025,
                      pad=0.01)  # fmt: skip
    cb.set_label("t [s]", fontsize=7)
    ax.set_xlabel("x [µm] (flow →)")
    return fig
