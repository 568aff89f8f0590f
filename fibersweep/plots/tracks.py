"""Stored trajectories drawn: an overlay of many runs, and one run as an animation.

The trajectories are the sweep's trajectory table (one row per sample: ``id``,
``t`` [s], ``x``, ``y``, ``head_x``, ``head_y``, ``tail_x``, ``tail_y`` [µm]).
Positions are drawn as the other figures quote them: from the pillar's base
centre, in units of h_obs, each run against its own pillar (a folder may sweep
the geometry).

The animation is written by matplotlib's writers: ``.gif`` with
:class:`~matplotlib.animation.PillowWriter` (Pillow is a dependency of
matplotlib, so it always works), ``.mp4`` with
:class:`~matplotlib.animation.FFMpegWriter`, which needs the ``ffmpeg``
program on the PATH.
"""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Polygon

from fibersweep.analysis.trajectory import CLASSES
from fibersweep.errors import InputError
from fibersweep.plots.style import CLASS_STYLE, UNCLASSIFIED_STYLE, subplots
from fibersweep.units import Geometry

__all__ = ["ANIMATION_FORMATS", "animate_run", "movie_writer", "normalised", "overlay_figure"]

#: Animation formats and the matplotlib writer each needs.
ANIMATION_FORMATS = {".gif": "pillow", ".mp4": "ffmpeg"}


def movie_writer(name: str, fps: int):
    """The matplotlib writer of an animation: for a GIF, Pillow with every frame quantised
    to one shared palette (without dithering), so a pixel that does not change keeps its
    colour index and each frame stores only what moved: a GIF of a few hundred kB at
    1000 px wide, where a palette per frame changes scattered pixels everywhere."""
    from matplotlib import animation

    if name != "pillow":
        return animation.FFMpegWriter(fps=fps)

    class SharedPaletteGif(animation.PillowWriter):
        def finish(self) -> None:
            from PIL import Image

            frames = [f.convert("RGB") for f in self._frames]
            picks = frames[:: max(1, len(frames) // 8)] + [frames[-1]]
            w, h = frames[0].size
            sheet = Image.new("RGB", (w, h * len(picks)))
            for k, f in enumerate(picks):
                sheet.paste(f, (0, k * h))
            pal = sheet.quantize(colors=256, method=Image.Quantize.MEDIANCUT,
                                 dither=Image.Dither.NONE)  # fmt: skip
            q = [f.quantize(palette=pal, dither=Image.Dither.NONE) for f in frames]
            q[0].save(self.outfile, save_all=True, append_images=q[1:],
                      duration=int(1000 / self.fps), loop=0)  # fmt: skip

    return SharedPaletteGif(fps=fps)


def _geometry_of(geometries: Geometry | Mapping[str, Geometry], run: pd.Series) -> Geometry:
    if isinstance(geometries, Geometry):
        return geometries
    return geometries[str(run["settings"])]


def normalised(samples: pd.DataFrame, geometry: Geometry) -> dict[str, np.ndarray]:
    """Sample positions from the pillar's base centre in units of h_obs.

    Parameters
    ----------
    samples : DataFrame
        One run's trajectory rows, time-ordered (``x``, ``y``, ``head_x``, ``head_y``,
        ``tail_x``, ``tail_y`` [µm]).
    geometry : Geometry

    Returns
    -------
    dict of ndarray
        ``x``, ``y``, ``head_x``, ``head_y``, ``tail_x``, ``tail_y``, each shape (m,).
    """
    xb, yb = geometry.base_center
    h = geometry.pillar_height
    out = {}
    for c in ("x", "head_x", "tail_x"):
        out[c] = (samples[c].to_numpy(dtype=float) - xb) / h
    for c in ("y", "head_y", "tail_y"):
        out[c] = (samples[c].to_numpy(dtype=float) - yb) / h
    return out


def _outline(geometry: Geometry) -> np.ndarray:
    xb, yb = geometry.base_center
    return (geometry.shape.outline() - [xb, yb]) / geometry.pillar_height


def _style(cls: object) -> dict:
    return CLASS_STYLE.get(str(cls), UNCLASSIFIED_STYLE)


def overlay_figure(
    runs: pd.DataFrame,
    samples: pd.DataFrame,
    geometries: Geometry | Mapping[str, Geometry],
    *,
    title: str = "",
    window: float = 3.0,
) -> Figure:
    """Centre-of-mass paths of ``runs`` over the pillar, coloured by class.

    Parameters
    ----------
    runs : DataFrame
        The runs to draw (``id``, ``class``, ``settings``); those without a
        stored trajectory are counted in the title, not drawn.
    samples : DataFrame
        Their trajectory rows (``id``, ``sample`` and the position columns).
    geometries : Geometry or mapping of settings id -> Geometry
    title : str
        What was selected (e.g. the ``--where`` expression).
    window : float
        Half-width of the drawn x range around the pillar [h_obs].
    """
    fig, ax = subplots(figsize=(7.0, 3.2), layout="constrained")
    by_id = dict(tuple(samples.groupby("id", sort=False))) if len(samples) else {}
    outlines: dict[tuple, np.ndarray] = {}
    segs: dict[str, list[np.ndarray]] = {}
    n_drawn = 0
    for _, run in runs.iterrows():
        s = by_id.get(run["id"])
        if s is None or len(s) < 2:
            continue
        g = _geometry_of(geometries, run)
        outlines.setdefault(tuple(np.round(_outline(g), 6).ravel()), _outline(g))
        p = normalised(s.sort_values("sample"), g)
        segs.setdefault(str(run["class"]) if run["status"] == "ok" else "failed", []).append(
            np.column_stack([p["x"], p["y"]])
        )
        n_drawn += 1
    if not n_drawn:
        raise InputError("none of the selected runs has a stored trajectory "
                         "(set fiber.record.trajectories: true)")  # fmt: skip
    alpha = float(np.clip(12.0 / np.sqrt(n_drawn), 0.15, 0.9))
    handles = []
    for cls in [*CLASSES, *sorted(set(segs) - set(CLASSES))]:
        if cls not in segs:
            continue
        color = _style(cls)["color"] if cls != "failed" else "0.45"
        ax.add_collection(LineCollection(segs[cls], colors=color, lw=0.9, alpha=alpha))
        handles.append(Line2D([], [], color=color, lw=1.5, label=f"{cls} ({len(segs[cls])})"))
    for out in outlines.values():
        ax.add_patch(Polygon(out, closed=True, fc="0.85", ec="0.3", lw=1.0, zorder=3,
                             alpha=0.8 if len(outlines) > 1 else 1.0))  # fmt: skip
    for cls, paths in segs.items():  # where each run ended
        ends = np.array([q[-1] for q in paths])
        color = _style(cls)["color"] if cls != "failed" else "0.45"
        ax.scatter(ends[:, 0], ends[:, 1], s=6, color=color, zorder=4, lw=0)
    pts = np.concatenate([np.concatenate(v) for v in segs.values()])
    pil = np.concatenate(list(outlines.values()))
    ax.set_xlim(
        min(max(pts[:, 0].min(), -window), pil[:, 0].min()) - 0.05,
        max(min(pts[:, 0].max(), window), pil[:, 0].max()) + 0.05,
    )
    inside = np.abs(pts[:, 0]) <= window
    ylo = min(pts[inside, 1].min(), 0.0) if inside.any() else 0.0
    yhi = max(pts[inside, 1].max(), 1.0) if inside.any() else 1.0
    ax.set_ylim(ylo - 0.08, yhi + 0.08)
    ax.set_aspect("equal")
    # a figure as tall as the equal-aspect axes need, plus room for the labels and legend
    x0, x1 = ax.get_xlim()
    fig.set_size_inches(7.0, float(np.clip(6.0 * (yhi - ylo + 0.16) / (x1 - x0) + 0.9, 2.0, 6.0)))
    ax.set_xlabel(r"$x/h_{obs}$ (from the pillar centroid)")
    ax.set_ylabel(r"$y/h_{obs}$ (from the base)")
    missing = len(runs) - n_drawn
    head = f"{n_drawn} runs" + (f" ({missing} without a stored trajectory)" if missing else "")
    ax.set_title(head + (f": {title}" if title else ""), fontsize="small")
    fig.legend(handles=handles, loc="outside upper center", ncol=len(handles), frameon=False)
    return fig


def _shapes(run: pd.Series, s: pd.DataFrame, geometry: Geometry, picks: np.ndarray) -> list:
    """The fiber at the samples ``picks`` in h_obs from the base centre: every stored bead
    of a flexible fiber, the two ends of a rigid one (:func:`~.shapes.fiber_points`)."""
    from fibersweep.plots.shapes import fiber_points

    xb, yb = geometry.base_center
    h = geometry.pillar_height
    has_beads = "beads" in s.columns
    out = []
    for i in picks:
        beads = s["beads"].iloc[i] if has_beads else None
        beads = None if beads is None or np.size(beads) == 0 else np.asarray(beads, dtype=float)
        ends = (s[["tail_x", "tail_y"]].iloc[i].to_numpy(float),
                s[["head_x", "head_y"]].iloc[i].to_numpy(float))  # fmt: skip
        pts = fiber_points(run.get("model"), int(run.get("n_beads") or 0), beads, ends=ends)
        out.append((pts - [xb, yb]) / h)
    return out


def animate_run(
    run: pd.Series,
    samples: pd.DataFrame,
    geometry: Geometry,
    path: str | Path,
    *,
    frames: int = 120,
    fps: int = 20,
    dpi: int = 130,
) -> Path:
    """Write one run as an animation: the fiber moving past the pillar, its path behind it.

    Frames are 8 in wide at ``dpi`` (1040 px at the default); the clock is written above
    the axes, clear of the pillar and the fiber.

    Parameters
    ----------
    run : Series
        The run's row of the runs table (for the title).
    samples : DataFrame
        Its trajectory rows.
    geometry : Geometry
    path : str or Path
        ``.gif`` (Pillow) or ``.mp4`` (ffmpeg on the PATH); written atomically.
    frames : int
        Frames at regular times over the record.
    fps : int
        Frames per second of the file.
    dpi : int
        Resolution.

    Raises
    ------
    InputError
        Unknown suffix, no ffmpeg for an MP4, fewer than two samples, a bead-spring
        run stored without its bead positions (:class:`~.shapes.ShapeNotStored`).
    """
    from matplotlib import animation

    from fibersweep.atomic import atomic_path

    out = Path(path)
    writer_name = ANIMATION_FORMATS.get(out.suffix.lower())
    if writer_name is None:
        raise InputError(f"{out}: animation formats are {', '.join(ANIMATION_FORMATS)}")
    if writer_name == "ffmpeg" and not animation.FFMpegWriter.isAvailable():
        raise InputError(f"{out}: an MP4 needs the ffmpeg program on the PATH; write a .gif")
    s = samples.sort_values("sample")
    if len(s) < 2:
        raise InputError(f"run {run['id']}: no stored trajectory to animate")
    p = normalised(s, geometry)
    t = s["t"].to_numpy(dtype=float)
    # the part of the record near the pillar: one fiber length (and a bit) either side
    pil = _outline(geometry)
    reach = float(np.hypot(p["head_x"][0] - p["tail_x"][0], p["head_y"][0] - p["tail_y"][0]))
    lo, hi = pil[:, 0].min() - reach - 0.5, pil[:, 0].max() + reach + 0.5
    near = np.flatnonzero((p["x"] > lo) & (p["x"] < hi))
    t0, t1 = (t[near[0]], t[near[-1]]) if near.size > 1 else (t[0], t[-1])
    picks = np.unique(np.searchsorted(t, np.linspace(t0, t1, frames)).clip(0, len(t) - 1))
    shapes = _shapes(run, s, geometry, picks)
    fig, ax = subplots(figsize=(8.0, 4.0), layout="constrained")
    ax.add_patch(Polygon(pil, closed=True, fc="0.85", ec="0.3", lw=1.0))
    color = _style(run["class"])["color"]
    ax.plot(p["x"], p["y"], color="0.8", lw=0.8, ls="--")
    trail, = ax.plot([], [], color=color, lw=1.0)  # fmt: skip
    fiber, = ax.plot([], [], color="k", lw=2.5, solid_capstyle="round")  # fmt: skip
    head, = ax.plot([], [], "o", color=color, ms=4, mec="k", mew=0.5)  # fmt: skip
    clock = ax.set_title(" ", loc="left", fontsize=9, family="monospace")  # above the axes
    xs = np.concatenate([*(q[:, 0] for q in shapes), pil[:, 0]])
    ys = np.concatenate([*(q[:, 1] for q in shapes), pil[:, 1]])
    ax.set_xlim(xs.min() - 0.1, xs.max() + 0.1)
    ax.set_ylim(ys.min() - 0.1, ys.max() + 0.1)
    ax.set_aspect("equal")
    # as tall as the equal-aspect axes need, plus the titles and labels
    span = (ys.max() - ys.min() + 0.2) / (xs.max() - xs.min() + 0.2)
    fig.set_size_inches(8.0, float(np.clip(7.3 * span + 1.3, 2.4, 8.0)))
    ax.set_xlabel(r"$x/h_{obs}$")
    ax.set_ylabel(r"$y/h_{obs}$")
    cls = run["class"] if run.get("status", "ok") == "ok" else f"failed ({run.get('reason')})"
    fig.suptitle(rf"$\theta_0$ = {run['theta0']:g}°, $y_0/h_{{obs}}$ = {run['y0']:g}, "
                 rf"$L/l_{{obs}}$ = {run['length']:g}  →  {cls}", fontsize=9)  # fmt: skip

    def draw(k: int) -> tuple:
        i = picks[k]
        fiber.set_data(shapes[k][:, 0], shapes[k][:, 1])
        head.set_data([p["head_x"][i]], [p["head_y"][i]])
        trail.set_data(p["x"][: i + 1], p["y"][: i + 1])
        clock.set_text(f"t = {t[i]:.2f} s")
        return fiber, head, trail, clock

    anim = animation.FuncAnimation(fig, draw, frames=len(picks), blit=False)
    writer = movie_writer(writer_name, fps)
    # the writers take the format from the file name's suffix: draw into a scratch file of
    # the right name, then put it in place atomically
    with tempfile.TemporaryDirectory() as scratch, atomic_path(out) as tmp:
        draft = Path(scratch) / f"animation{out.suffix.lower()}"
        anim.save(str(draft), writer=writer, dpi=dpi)
        shutil.copyfile(draft, tmp)
    return out
