"""The start points of a sweep: the grid of the start axes, or seeded random draws.

With ``sweep.random: {count: N, seed: S}`` every length gets N starts drawn
uniform in the ``theta0`` and ``y0`` ranges ``[lo, hi]``; a start that touches
the pillar (a channel: the run's own start check,
:func:`fibersweep.fiber.setup.check_start`; an array: any pillar within the
contact cutoff, :func:`fibersweep.fiber.array_run.start_clear`) is drawn again.
The generator of a length is seeded by ``(S, the bits of L)``: the same config
gives the same starts, a length added later leaves the others' draws as they
were (so a resumed sweep keeps its run ids), and every setting combination
draws from the same stream (common random numbers; only redraws differ).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from fibersweep.config.axes import axis_values
from fibersweep.errors import InputError
from fibersweep.fiber.result import FiberStart

__all__ = ["start_points", "MAX_TRIES_PER_START"]

#: Draws per accepted start before a length is declared impossible to place.
MAX_TRIES_PER_START = 1000


def _range(axis: Any) -> tuple[float, float]:
    v = axis_values(axis)
    return float(v[0]), float(v[-1])


def _clear_test(cfg: Any) -> Callable[[float, float, float], bool]:
    """(theta0, y0, length) -> whether that start is clear (raises for a bad length)."""
    fiber = cfg.fiber
    if cfg.flow.array is not None:
        from fibersweep.fiber.array_run import n_beads_of, start_clear
        from fibersweep.fiber.rows import array_pillar

        array = cfg.flow.array.to_array()
        pillar = array_pillar(array, fiber, cfg.flow.fluid.viscosity, cfg.flow.fluid.u_center)

        def clear(t: float, y: float, L: float) -> bool:
            n = n_beads_of(L, fiber.bead_radius, fiber.bead_spacing)
            return start_clear(array, pillar, n, fiber.bead_radius, y, t, fiber.bead_spacing)

        return clear
    from fibersweep.fiber.contact.pillar import make_pillar
    from fibersweep.fiber.setup import check_start

    geo = cfg.flow.geometry.to_geometry()
    pillar = make_pillar(geo, fiber.contact, fiber.bead_radius, 1.0)

    def clear_channel(t: float, y: float, L: float) -> bool:
        try:
            check_start(geo, cfg.flow.dx, fiber, FiberStart(t, y, L), pillar)
        except InputError as exc:
            if str(exc).startswith(("length", "x0", "theta0")):
                raise  # no redraw of the position mends these
            return False
        return True

    return clear_channel


def start_points(cfg: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The sweep's start points (theta0 [deg], y0, length), length varying slowest.

    Parameters
    ----------
    cfg : Config
        Without ``sweep.random``: its grid (:meth:`SweepSettings.grid`).

    Raises
    ------
    InputError
        A length whose fiber cannot be placed (``length: ...``), or no clear start
        found in ``MAX_TRIES_PER_START`` draws per start (``y0: ...``).
    """
    r = cfg.sweep.random
    if r is None:
        return cfg.sweep.grid()
    t_lo, t_hi = _range(cfg.sweep.theta0)
    y_lo, y_hi = _range(cfg.sweep.y0)
    clear = _clear_test(cfg)
    ts, ys, Ls = [], [], []
    for L in axis_values(cfg.sweep.length).tolist():
        rng = np.random.default_rng([r.seed, int(np.float64(L).view(np.uint64))])
        got = 0
        for _ in range(MAX_TRIES_PER_START * r.count):
            t = float(rng.uniform(t_lo, t_hi))
            y = float(rng.uniform(y_lo, y_hi))
            if clear(t, y, L):
                ts.append(t)
                ys.append(y)
                Ls.append(L)
                got += 1
                if got == r.count:
                    break
        else:
            raise InputError(
                f"y0: no start of the fiber of length {L:g} clears the pillars in "
                f"{MAX_TRIES_PER_START * r.count} draws over y0 in [{y_lo:g}, {y_hi:g}], "
                f"theta0 in [{t_lo:g}, {t_hi:g}]; widen the ranges or shorten the fiber"
            )
    return np.array(ts), np.array(ys), np.array(Ls, dtype=np.float64)
