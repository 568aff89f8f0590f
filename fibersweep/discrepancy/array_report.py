"""The array parts of the discrepancy report: start units, axis labels, the f(L) figure.

A report on a pillar array (its observables :mod:`.array_observables`) speaks of
starts in the array's units (y0 as a fraction of period_y, L in µm) and shows,
in place of the channel's (θ0, y0) class map, ``phase_before_after.png``: the
displacement fraction f of every measured fiber against its length, beside the
baseline model's copy and the model with what was fitted (trapped fibers at the
bottom, marked). This is the sorter designer's curve f(L).
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from fibersweep.discrepancy.observables import geometry_of

__all__ = ["ARRAY_AXES", "array_phase", "is_array_report", "start_units"]

#: Start-axis labels of an array's figures.
ARRAY_AXES = {"theta0": r"$\theta_0$ [deg]", "y0": r"$y_0/\lambda_y$", "length": r"$L$ [µm]"}

#: (y0, L) units of the starts as reports write them.
_UNITS = {"channel": ("h_obs", "l_obs"), "array": ("period_y", "µm")}


def is_array_report(observables: Iterable[str]) -> bool:
    """Whether a result or summary of these observables is a pillar array's."""
    return geometry_of(observables) == "array"


def start_units(observables: Iterable[str]) -> tuple[str, str]:
    """Units of y0 and L in words: ('h_obs', 'l_obs') in a channel, ('period_y', 'µm')."""
    return _UNITS[geometry_of(observables)]


def array_phase(res: Any, out: Path, label: str, key: str | None) -> str:
    """``phase_before_after.png`` of an array: f against L, measured / baseline / fitted.

    Parameters
    ----------
    res : DiscrepancyResult
    out : Path
        Report folder.
    label, key : str, str or None
        What was fitted, as :func:`.report_figures.fitted_label` gives it.
    """
    from fibersweep.plots.style import save_figure, subplots

    obs = res.observed
    panels = [("measured", obs), ("baseline model (copy 1)", res.baseline_copies[0])]
    if key is not None and key in res.effect_copies:
        panels.append((f"with {label}", res.effect_copies[key][0]))
    L = obs["length"].to_numpy(dtype=np.float64)
    fig, axes = subplots(1, len(panels), figsize=(3.3 * len(panels), 3.3), sharey=True)
    for ax, (title, t) in zip(np.atleast_1d(axes), panels, strict=True):
        f = t["fraction"].to_numpy(dtype=np.float64)
        trapped = np.asarray(t["trapped"], dtype=np.float64) > 0.5
        free = np.isfinite(f) & ~trapped
        ax.scatter(L[free], f[free], s=10, color="C0", edgecolors="0.2", linewidths=0.3)
        if trapped.any():
            ax.scatter(L[trapped], np.full(int(trapped.sum()), -0.15), s=14, marker="x",
                       color="C3", label="trapped (drawn at f = -0.15)")  # fmt: skip
            ax.legend(frameon=False, fontsize=6, loc="upper left")
        ax.axhline(0.0, color="0.7", lw=0.6)
        ax.axhline(1.0, color="0.7", lw=0.6)
        ax.set_title(title, fontsize=8)
        ax.set_xlabel(ARRAY_AXES["length"])
    np.atleast_1d(axes)[0].set_ylabel("displacement fraction f\n(1 displaced, 0 zigzag)")
    if key is None:
        fig.suptitle("No effect was fitted (no significant gap)")
    save_figure(fig, out / "phase_before_after.png", dpi=110)
    return "phase_before_after.png"
