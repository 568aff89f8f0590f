"""Array starts clear of every pillar: the check, and the redraw at a fiber's own length.

A start (θ0 [deg], y0 [fraction of period_y], L [µm]) whose fiber would touch a pillar
is no start: the run refuses it (:class:`fibersweep.fiber.array_run.ArrayCase`). The
synthesised fibers, the power analysis's starts and the simulator's batches check it
here, the same way.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from fibersweep.config.fiber import FiberSettings
from fibersweep.errors import InputError

__all__ = ["AXES", "MAX_REDRAWS", "clear_starts", "redraw_clear"]

#: The start columns, in order.
AXES = ("theta0", "y0", "length")
#: Redraws of a start that touches a pillar before giving up (a box mostly inside pillars).
MAX_REDRAWS = 50


def clear_starts(field: Any, fiber: FiberSettings, starts: np.ndarray) -> np.ndarray:
    """Whether each start (θ0 [deg], y0 [/period_y], L [µm]) clears every pillar, shape (n,)."""
    from fibersweep.fiber.array_run import n_beads_of, start_clear
    from fibersweep.fiber.rows import array_pillar

    array = field.array
    pillar = array_pillar(array, fiber, field.viscosity, field.u_center)
    a = float(fiber.bead_radius)
    return np.array([
        start_clear(array, pillar, n_beads_of(L, a, fiber.bead_spacing), a, y, th,
                    fiber.bead_spacing)
        for th, y, L in starts
    ], dtype=bool)  # fmt: skip



def redraw_clear(
    field: Any,
    fiber: FiberSettings,
    starts: np.ndarray,
    box: Mapping[str, tuple[float, float]],
    rng: np.random.Generator,
    what: str,
) -> np.ndarray:
    """``starts`` with each one that touches a pillar redrawn at its own length.

    Only θ0 and y0 are redrawn (uniform in ``box``), so the lengths keep the
    distribution they were drawn with (redrawing L too would favour short fibers,
    which touch less often).

    Parameters
    ----------
    starts : ndarray, shape (n, 3)
        θ0 [deg], y0 [/period_y], L [µm]; changed in place and returned.
    what : str
        The command, for the message.

    Raises
    ------
    InputError
        Some start still touches a pillar after :data:`MAX_REDRAWS` redraws.
    """
    lo = np.array([box[k][0] for k in AXES[:2]], dtype=np.float64)
    hi = np.array([box[k][1] for k in AXES[:2]], dtype=np.float64)
    for _ in range(MAX_REDRAWS):  # a start inside a pillar's reach is no start
        bad = ~clear_starts(field, fiber, starts)
        if not bad.any():
            return starts
        starts[bad, :2] = lo + (hi - lo) * rng.random((int(bad.sum()), 2))
    raise InputError(
        f"{what}: {int(bad.sum())} of {len(starts)} starts still touch a pillar after "
        f"{MAX_REDRAWS} redraws of θ0 and y0 at their length; widen sweep.y0 or shorten "
        "sweep.length"
    )
