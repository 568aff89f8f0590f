"""Figure of a flow field: speed and streamlines near the pillar, separatrix, profiles."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fibersweep.flow.analysis import flux_separatrix, stream_function
from fibersweep.flow.field import FlowField
from fibersweep.flow.streamlines import separatrix_y
from fibersweep.plots.style import new_figure, paper_style, save_figure

__all__ = ["plot_flow"]


def plot_flow(field: FlowField, path: str | Path, *, half_window: float | None = None) -> Path:
    """Draw the field and write it atomically to ``path`` (format from the suffix).

    Top: |u| / U_center near the pillar with streamlines, the pillar and the
    separatrix (the streamline that ends on the upstream face: the contour of
    the stream function at the flux passing below the pillar). Bottom: ux / U_center
    along x through the pillar centroid, and along y through the apex.

    Parameters
    ----------
    field : FlowField
    path : str or Path
        Output image.
    half_window : float, optional
        Half width in x of the top panel around the pillar [µm]; default 4 h_obs.
    """
    geom = field.geometry
    u0 = field.fluid.u_center
    xc, yc = geom.centroid
    hw = half_window or 4.0 * geom.pillar_height
    x = field.x_nodes
    y = field.y_nodes
    ux = np.asarray(field.ux) / u0
    uy = np.asarray(field.uy) / u0
    speed = np.hypot(ux, uy)
    hh = 0.55 * hw  # half height of the top panel
    sel = (x > xc - hw) & (x < xc + hw)
    sely = (y > yc - hh) & (y < yc + hh)
    sep = flux_separatrix(field)
    y_traced = separatrix_y(field)
    psi = stream_function(field)

    with paper_style():
        fig = _draw(field, x, y, ux, uy, speed, sel, sely, sep, y_traced, psi, hw)
        return save_figure(fig, path, dpi=160)


def _draw(field, x, y, ux, uy, speed, sel, sely, sep, y_traced, psi, hw):
    """The three panels of :func:`plot_flow` (inside the package style)."""
    from matplotlib.patches import Polygon

    geom = field.geometry
    xc, yc = geom.centroid
    fig = new_figure(figsize=(7.0, 5.4), layout="constrained")
    gs = fig.add_gridspec(2, 2, height_ratios=[1.45, 1.0])
    ax = fig.add_subplot(gs[0, :])
    xs, ys = x[sel], y[sely]
    box = np.ix_(sel, sely)
    im = ax.pcolormesh(xs, ys, speed[box].T, shading="auto", cmap="viridis", vmin=0,
                       rasterized=True)  # fmt: skip
    fig.colorbar(im, ax=ax, label=r"$|u|/U_{center}$", shrink=0.9, pad=0.01)
    ax.streamplot(
        xs, ys, ux[box].T, uy[box].T, color="white", linewidth=0.45, density=1.1, arrowsize=0.5
    )
    ax.contour(xs, ys, psi[box].T, levels=[sep.psi], colors="#D55E00", linewidths=1.5)
    ax.add_patch(Polygon(geom.vertices, closed=True, fc="0.35", ec="black", lw=0.8, zorder=3))
    # The traced streamline is what a midplane fiber follows (canonical); the ψ contour
    # drawn is the flux estimate, which differs by well under a grid cell.
    label = (
        rf"separatrix: $y/h_{{obs}}$ = {y_traced:.3f} far upstream "
        f"(traced; {sep.y_far_over_h:.3f} from the flux)"
    )
    ax.plot([], [], color="#D55E00", lw=1.5, label=label)
    ax.axhline(geom.y_from_base(y_traced), color="#D55E00", lw=0.7, ls=":")
    ax.legend(loc="upper right", frameon=True, framealpha=0.9, edgecolor="none")
    ax.set_xlim(xs[0], xs[-1])
    ax.set_ylim(ys[0], ys[-1])
    ax.set_aspect("equal")
    ax.set_xlabel(r"$x$ [µm]")
    ax.set_ylabel(r"$y$ [µm]")
    u0 = field.fluid.u_center
    ax.set_title(
        rf"midplane velocity (z-averaged as the fibers see it), $\Delta x$ = {field.dx:g} µm, "
        rf"$U_{{center}}$ = {u0:g} µm/s"
    )

    # Profiles stop at the wall: a sub-grid pillar's solid nodes hold ghost values (the
    # mirror of the flow outside, for interpolation), which are not a velocity.
    ux_fluid = np.where(np.asarray(field.solid), np.nan, ux)
    ax1 = fig.add_subplot(gs[1, 0])
    j = int(np.argmin(np.abs(y - yc)))
    ax1.plot(x, ux_fluid[:, j])
    ax1.axvspan(*geom.vertices[:2, 0], color="0.85", label="pillar")
    ax1.set_xlabel(r"$x$ [µm]")
    ax1.set_ylabel(r"$u_x/U_{center}$")
    ax1.set_title(rf"along $x$ at $y$ = {y[j]:.0f} µm (through the centroid)")
    ax1.set_xlim(xc - 2.5 * hw, xc + 2.5 * hw)
    ax1.grid(True)
    ax1.legend(loc="lower left")

    ax2 = fig.add_subplot(gs[1, 1])
    i = int(np.argmin(np.abs(x - xc)))
    ax2.plot(y, ux_fluid[i], label="through the apex")
    i_far = int(np.argmin(np.abs(x - geom.x_far)))
    ax2.plot(y, ux[i_far], ls="--", label="far from the pillar")
    yb = geom.base_center[1]
    ax2.axvspan(yb, yb + geom.pillar_height, color="0.85", label="pillar")
    ax2.set_xlabel(r"$y$ [µm]")
    ax2.set_ylabel(r"$u_x/U_{center}$")
    ax2.set_title(rf"along $y$ at $x$ = {x[i]:.0f} µm")
    ax2.grid(True)
    ax2.legend(loc="upper left")
    return fig
