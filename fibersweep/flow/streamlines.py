"""The separatrix by streamline tracing (canonical): far-upstream y/h_obs of its streamline.

Streamlines of the midplane field below the separatrix pass under the pillar
(the triangle's base), those above it pass over it (the apex); the one in between ends at the
stagnation point on the upstream face. We trace a row of streamlines from the
fibers' start line (x = L_ch/4 by default) with RK4, note on which side of the
pillar each one crosses the pillar's centre line x = x_c, and bisect the
bracket [highest below, lowest above] with finer rows. Streamlines that stall
near the stagnation point cross neither way and simply stay inside the bracket.
"""

from __future__ import annotations

import logging

import numpy as np

from fibersweep.flow.field import FlowField

__all__ = ["separatrix_y", "trace_sides"]

log = logging.getLogger(__name__)


def trace_sides(
    field: FlowField,
    y_over_h: np.ndarray,
    x_start: float | None = None,
    max_transits: float = 30.0,
    step_fraction: float = 0.5,
) -> np.ndarray:
    """Which side of the pillar streamlines from ``(x_start, y)`` pass.

    Parameters
    ----------
    field : FlowField
    y_over_h : ndarray, shape (k,)
        Start positions, y/h_obs from the pillar base.
    x_start : float, optional
        Start x [µm]; default L_ch/4 (the fibers' start line).
    max_transits : float
        Give up after this many free-stream transit times to the pillar.
    step_fraction : float
        Largest move per RK4 step, in lattice spacings.

    Returns
    -------
    ndarray, shape (k,), int
        −1 below the pillar, +1 above, 0 stalled (still upstream of x_c).
    """
    g = field.geometry
    xc, _ = g.base_center
    low, high = g.shape.span_at(xc)  # the pillar on its centre line x = x_c
    ymid = 0.5 * float(low[0] + high[0])
    x0 = g.length / 4.0 if x_start is None else x_start
    if x0 >= xc:
        raise ValueError(f"x_start = {x0} µm must be upstream of the pillar centre x = {xc} µm")
    pts = np.column_stack([np.full(len(y_over_h), x0), g.y_from_base(np.asarray(y_over_h))])
    side = np.zeros(len(pts), dtype=np.int64)
    u_ref = max(field.fluid.u_center, float(np.abs(field.ux).max()), 1e-300)
    dt = step_fraction * field.dx / u_ref
    n_max = int(np.ceil(max_transits * (xc - x0) / (u_ref * dt)))
    active = np.arange(len(pts))
    p = pts.copy()
    for _ in range(n_max):
        if active.size == 0:
            break
        q = p[active]
        k1 = field.velocity(q)
        k2 = field.velocity(q + 0.5 * dt * k1)
        k3 = field.velocity(q + 0.5 * dt * k2)
        k4 = field.velocity(q + dt * k3)
        q = q + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        p[active] = q
        crossed = q[:, 0] >= xc
        if crossed.any():
            side[active[crossed]] = np.where(q[crossed, 1] > ymid, 1, -1)
            active = active[~crossed]
    return side


def separatrix_y(
    field: FlowField,
    x_start: float | None = None,
    lo: float = -0.5,
    hi: float = 1.5,
    n: int = 17,
    rounds: int = 4,
) -> float:
    """Far-upstream y/h_obs of the separatrix.

    Parameters
    ----------
    field : FlowField
    x_start : float, optional
        Upstream line [µm]; default L_ch/4.
    lo, hi : float
        Initial bracket in y/h_obs (must pass below / above).
    n : int
        Streamlines per round.
    rounds : int
        Refinements; the bracket shrinks about (n−1)-fold per round.

    Returns
    -------
    float
        Midpoint of the final bracket; its half-width is logged.

    Raises
    ------
    ValueError
        If the initial bracket does not straddle the separatrix.
    """
    a, b = lo, hi
    for r in range(rounds):
        ys = np.linspace(a, b, n)
        side = trace_sides(field, ys, x_start)
        below, above = ys[side < 0], ys[side > 0]
        if below.size == 0 or above.size == 0:
            raise ValueError(
                f"no streamline from y/h in [{a:.4g}, {b:.4g}] passes "
                f"{'below' if below.size == 0 else 'above'} the pillar (round {r})"
            )
        a, b = float(below.max()), float(above.min())
        if a > b:
            raise ValueError("streamlines cross: the field is not a steady 2D flow past the pillar")
    log.info("separatrix y/h = %.5f +- %.1e", 0.5 * (a + b), 0.5 * (b - a))
    return 0.5 * (a + b)
