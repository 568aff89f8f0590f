"""Figures of the discrepancy report, in the shared style (:mod:`fibersweep.plots.style`).

- ``phase_before_after.png``: (θ0, y0) classes of every fiber: measured, the
  baseline model, and the model with what was fitted (the named effect or set,
  else the best candidate, labelled as not named; no third panel when nothing
  was fitted);
- ``residual_map.png`` (only with a significant gap): the per-fiber gap binned
  over the start axes the data sample (an axis whose spread is that of the
  start noise alone is not one), each bin's mean as a z against the noise of a
  mean of that many fibers, on one symmetric scale; bins within the noise
  (|z| < :data:`NOISE_Z`) grey;
- ``gap_before_after.png``: out-of-sample gap per observable, baseline and with
  what was fitted, in copy-spread units;
- ``next_measure.png``: how well one fiber at each start separates the two
  hypotheses of what-to-measure-next, with the best starts marked.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fibersweep.discrepancy.array_report import ARRAY_AXES, array_phase, is_array_report
from fibersweep.discrepancy.candidates import show_values
from fibersweep.discrepancy.gap import GAP_UNIT, GapResult
from fibersweep.discrepancy.localise import binned_map
from fibersweep.discrepancy.observables import OBSERVABLES
from fibersweep.discrepancy.result import DiscrepancyResult, Discrimination
from fibersweep.plots.style import CLASS_STYLE, FAILED_STYLE, paper_style, save_figure, subplots

__all__ = ["NOISE_Z", "SAMPLED_SPREAD", "bin_z", "figures", "fitted_label", "next_figure"]

UNIT = GAP_UNIT

#: A bin's |z| below this is drawn as noise (grey) in the residual map.
NOISE_Z = 2.0

#: A start axis is mapped only if its measured spread exceeds this many start-noise sd:
#: a few dozen starts drawn around one value by the noise alone span about 4-5 sd.
SAMPLED_SPREAD = 8.0

AXES = {"theta0": r"$\theta_0$ [deg]", "y0": r"$y_0/h_{obs}$", "length": r"$L/l_{obs}$"}


def fitted_label(res: DiscrepancyResult) -> tuple[str | None, str, GapResult | None]:
    """(copies key, label, cross-fitted residual gap) of what the figures show as fitted.

    The named effect or set; for an ambiguous verdict its first alternative; else
    the best held-out candidate (labelled "not named"); (None, 'no effect fitted',
    None) when nothing was fitted. Values in their candidate's unit
    (:func:`.candidates.show_values`: a declared stiffness in Pa).
    """
    v = res.verdict
    declared = {c.name: c for c in res.settings.declared}
    if v.kind in ("named", "ambiguous") and v.alternatives:
        alt = v.alternatives[0]
        key = " + ".join(alt)
        text = show_values(dict(alt), declared)
        gap = None
        if len(alt) == 1:
            gap = next((h.residual for h in res.heldout if h.name == key), None)
        else:
            gap = next((s.residual for s in res.sets if s.name == key), None)
        tag = "named" if v.kind == "named" else "one of the alternatives"
        return key, f"{text} ({tag})", gap
    if res.heldout:
        h = max(res.heldout, key=lambda h: h.improvement[0])
        text = show_values({h.name: h.value}, declared)
        return h.name, f"{text} (best candidate, not named)", h.residual
    return None, "no effect fitted", None


def _class_groups(codes: np.ndarray) -> list[tuple[str, dict[str, object], np.ndarray]]:
    out = []
    for k, name in enumerate(OBSERVABLES["class"].categories):
        mask = codes == k
        if mask.any():
            out.append((name, CLASS_STYLE[name], mask))
    bad = ~np.isfinite(codes)
    if bad.any():
        out.append(("failed", FAILED_STYLE, bad))
    return out


def _axes(res: DiscrepancyResult) -> dict[str, str]:
    """Start-axis labels: the channel's, or a pillar array's (its own units)."""
    return ARRAY_AXES if is_array_report(getattr(res, "observables", ())) else AXES


def _phase(res: DiscrepancyResult, out: Path) -> str:
    from matplotlib.lines import Line2D

    if is_array_report(res.observables):  # f(L): the array's own picture
        key, label, _ = fitted_label(res)
        return array_phase(res, out, label, key)
    obs = res.observed
    codes = OBSERVABLES["class"].values
    key, label, _ = fitted_label(res)
    panels = [
        ("measured", codes(obs["class"])),
        ("baseline model (copy 1)", codes(res.baseline_copies[0]["class"])),
    ]
    if key is not None and key in res.effect_copies:
        panels.append((f"with {label}", codes(res.effect_copies[key][0]["class"])))
    fig, axes = subplots(1, len(panels), figsize=(3.3 * len(panels), 3.3), sharey=True)
    size = (8 + 20 * (obs["length"] - 0.4)).to_numpy()
    seen: dict[str, dict[str, object]] = {}
    for ax, (title, c) in zip(np.atleast_1d(axes), panels, strict=True):
        c = np.asarray(c, dtype=np.float64)
        for name, style, mask in _class_groups(c):
            ax.scatter(
                obs["theta0"][mask], obs["y0"][mask], s=size[mask], marker=style["marker"],
                color=style["color"], edgecolors="0.2" if name != "failed" else None,
                linewidths=0.3,
            )  # fmt: skip
            seen[name] = style
        ax.set_title(title, fontsize=8)
        ax.set_xlabel(AXES["theta0"])
    np.atleast_1d(axes)[0].set_ylabel(AXES["y0"])
    handles = [
        Line2D([], [], ls="", markersize=5, label=k, **st)  # type: ignore[arg-type]
        for k, st in seen.items()
    ]
    fig.legend(handles=handles, loc="outside lower center", ncol=len(handles), frameon=False)
    if key is None:
        fig.suptitle("No effect was fitted (no significant gap)")
    save_figure(fig, out / "phase_before_after.png", dpi=110)
    return "phase_before_after.png"


def _sampled_axes(res: DiscrepancyResult) -> list[str]:
    """The start axes the measured fibers sample beyond the start noise."""
    noise = res.settings.noise
    obs = res.observed
    return [c for c in ("theta0", "y0", "length")
            if float(np.ptp(obs[c])) > SAMPLED_SPREAD * float(getattr(noise, c))]  # fmt: skip


def bin_z(mean: np.ndarray, count: np.ndarray, sd: float) -> np.ndarray:
    """Each bin's mean per-fiber gap as a z: ``mean / (sd / sqrt(count))``.

    Parameters
    ----------
    mean, count : ndarray, same shape
        Mean gap [copy-spread units] and fibers per bin (:func:`.localise.binned_map`).
    sd : float
        Spread of the per-fiber gap over all fibers [copy-spread units]: the noise of
        one fiber (with a gap somewhere it is larger, so a bin's z errs small).

    Returns
    -------
    ndarray
        NaN for an empty bin or a zero ``sd``.
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        z = mean * np.sqrt(count) / sd if sd > 0 else np.full(mean.shape, np.nan)
    return np.where(count > 0, z, np.nan)


def _residual_map(res: DiscrepancyResult, out: Path) -> str | None:
    import matplotlib
    from matplotlib.colors import ListedColormap

    if not res.gap.any:
        return None  # no gap: a map of noise would only invite reading it
    axes_ = _sampled_axes(res)
    if "y0" not in axes_ or len(axes_) < 2:
        return None  # fewer than two sampled axes: no map to draw
    obs = res.observed
    exc = np.asarray(res.gap_per_fiber, dtype=np.float64)
    sd = float(np.nanstd(exc, ddof=1)) if np.isfinite(exc).sum() > 1 else 0.0
    y0 = obs["y0"].to_numpy(dtype=np.float64)
    maps = []
    # about two fibers per bin on average, at most 5 x 7 bins
    ny = int(np.clip(round(np.sqrt(len(obs) / 1.4)), 3, 7))
    nx = int(np.clip(round(0.7 * ny), 3, 5))
    for c in (a for a in axes_ if a != "y0"):
        x = obs[c].to_numpy(dtype=np.float64)
        xe = np.linspace(np.nanmin(x), np.nanmax(x) + 1e-9, nx + 1)
        ye = np.linspace(np.nanmin(y0), np.nanmax(y0) + 1e-9, ny + 1)
        m, cnt = binned_map(x, y0, exc, xe, ye)
        maps.append((c, xe, ye, bin_z(m, cnt, sd), cnt))
    top = max((float(np.nanmax(np.abs(z))) for *_, z, _ in maps if np.isfinite(z).any()),
              default=0.0)  # fmt: skip
    lim = max(4.0, float(np.ceil(top)))
    cmap = matplotlib.colormaps["RdBu_r"].with_extremes(bad="white")
    grey = ListedColormap(["0.85"])
    fig, axes = subplots(1, len(maps), figsize=(3.6 * len(maps) + 0.9, 3.3), layout="constrained")
    im = None
    for ax, (c, xe, ye, z, cnt) in zip(np.atleast_1d(axes), maps, strict=True):
        im = ax.pcolormesh(xe, ye, np.ma.masked_invalid(z.T), cmap=cmap, vmin=-lim, vmax=lim)
        quiet = np.where(np.isfinite(z) & (np.abs(z) < NOISE_Z), 1.0, np.nan)
        ax.pcolormesh(xe, ye, np.ma.masked_invalid(quiet.T), cmap=grey, vmin=0, vmax=1)
        xc, yc = 0.5 * (xe[1:] + xe[:-1]), 0.5 * (ye[1:] + ye[:-1])
        for i, j in zip(*np.nonzero(cnt), strict=True):  # fibers per bin: how much it rests on
            ax.text(xc[i], yc[j], str(cnt[i, j]), ha="center", va="center", fontsize=6,
                    color="0.35")  # fmt: skip
        ax.set_xlabel(_axes(res)[c])
        ax.set_ylabel(_axes(res)["y0"])
    cb = fig.colorbar(im, ax=np.atleast_1d(axes).tolist(),
                      label="z of the bin's mean gap\n(+: measured worse than the model)")
    cb.ax.axhspan(-NOISE_Z, NOISE_Z, color="0.85")  # the noise band, as on the map
    fig.suptitle(f"Where the gap is: grey |z| < {NOISE_Z:g} is noise, white no fibers, "
                 "numbers fibers per bin", fontsize=8)  # fmt: skip
    save_figure(fig, out / "residual_map.png", dpi=110)
    return "residual_map.png"


def _gap_bars(res: DiscrepancyResult, out: Path) -> str | None:
    key, label, after = fitted_label(res)
    if res.heldout_before is None or after is None:
        return None
    names = list(res.heldout_before.gaps)
    w = [res.weights.get(n, 0.0) for n in names]
    before = [
        np.multiply(res.heldout_before.gaps[n].excess, x) for n, x in zip(names, w, strict=True)
    ]
    aft = [np.multiply(after.gaps[n].excess, x) for n, x in zip(names, w, strict=True)]
    x = np.arange(len(names))
    fig, ax = subplots(figsize=(6.0, 3.2), layout="constrained")
    for off, vals, lab in ((-0.18, before, "baseline"), (0.18, aft, f"with {label}")):
        mean = np.array([v[0] for v in vals])
        err = np.abs(np.array([[v[0] - v[1], v[2] - v[0]] for v in vals]).T)
        ax.bar(x + off, mean, 0.36, yerr=err, capsize=3, label=lab)
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xticks(x, names)
    ax.set_ylabel(f"out-of-sample gap\n[{UNIT}, 95 % CI]")
    ax.legend(frameon=False, fontsize=7)
    save_figure(fig, out / "gap_before_after.png", dpi=110)
    return "gap_before_after.png"


def _next(res: DiscrepancyResult, out: Path) -> str | None:
    nx = res.extra.get("next")
    if nx is None:
        return None
    next_figure(nx, res.observed[["theta0", "y0"]].to_numpy(), out / "next_measure.png",
                _axes(res))  # fmt: skip
    return "next_measure.png"


def next_figure(
    nx: Discrimination, measured: np.ndarray, path: Path, axes: dict[str, str] | None = None
) -> Path:
    """Map of the separation per fiber over (θ0, y0), best over L, best starts circled.

    Parameters
    ----------
    nx : Discrimination
    measured : ndarray, shape (n, 2)
        Measured θ0 [deg], y0 [/h_obs] (small dots).
    path : Path
        PNG written.
    axes : dict, optional
        Axis labels (default :data:`AXES`, the channel's).
    """
    labels = axes or AXES
    g, d = nx.grid, nx.d
    th, ys = np.unique(g[:, 0]), np.unique(g[:, 1])
    D = np.full((len(th), len(ys)), np.nan)
    for (t, y, _), v in zip(g, d, strict=True):  # best over L at each (θ0, y0)
        i, j = np.searchsorted(th, t), np.searchsorted(ys, y)
        D[i, j] = v if not np.isfinite(D[i, j]) else max(D[i, j], v)
    fig, ax = subplots(figsize=(4.8, 3.6), layout="constrained")

    def edges(v: np.ndarray) -> np.ndarray:
        if len(v) == 1:
            return np.array([v[0] - 0.5, v[0] + 0.5])
        mid = 0.5 * (v[1:] + v[:-1])
        return np.concatenate([[2 * v[0] - mid[0]], mid, [2 * v[-1] - mid[-1]]])

    im = ax.pcolormesh(edges(th), edges(ys), D.T, cmap="viridis", vmin=0)
    ax.scatter(
        measured[:, 0],
        measured[:, 1],
        s=8,
        color="w",
        edgecolors="0.2",
        linewidths=0.4,
        label="measured starts",
    )  # dark edge: visible on the map and in the legend
    bt = np.array([[b.theta0, b.y0] for b in nx.best])
    ax.scatter(bt[:, 0], bt[:, 1], s=40, facecolors="none", edgecolors="r", label="best starts")
    ax.set_xlabel(labels["theta0"])
    ax.set_ylabel(labels["y0"])
    ax.set_title(f"{nx.labels[0]}  vs  {nx.labels[1]}", fontsize=8)
    ax.legend(frameon=False, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.15), ncol=2)
    fig.colorbar(im, ax=ax, label="separation per fiber (best over L) [noise sd]")
    return save_figure(fig, path, dpi=110)


def figures(res: DiscrepancyResult, out: Path) -> list[str]:
    """Write every figure that applies into ``out``; their file names."""
    made = []
    with paper_style():
        for make in (_phase, _residual_map, _gap_bars, _next):
            name = make(res, out)
            if name:
                made.append(name)
    return made
