"""Transport modes of a fiber through a pillar array: a pure function of its trajectory.

A stored trajectory (time, centre, angle, contact flag, centre speed) and the
array's periods give every per-run quantity the sort report needs, so the
modes can be re-labelled with other thresholds without simulating again.

- Row crossings: the first time the centre reaches x0 + k λx (k = 0, 1, ...).
- Migration per row m = (y_K − y_0) / K over the K whole rows crossed; the
  migration angle atan(m / λx); the displacement fraction f = m / (ε λy)
  (1: the fiber follows the tilt of the array, 0: it follows the mean flow).
- Wraps: contact episodes during which the fiber turned by more than 90°
  (it swung round a pillar, head and tail swapping, as pole-vaulting does
  on the single pillar).

Modes (thresholds in :class:`ModeSettings`):

- ``trapped``: the run ends in contact with the centre slower than
  ``trap_speed`` (the integrator's stop rule, re-applied to the record);
- ``wrap-and-jump``: wraps in at least ``wrap_fraction`` of the rows crossed
  and f > ``zigzag_max``;
- ``displacement``: f ≥ ``displacement_min``;
- ``zigzag``: |f| ≤ ``zigzag_max``;
- ``mixed``: anything in between (or a run that crossed fewer than 2 rows).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "MODES",
    "ModeSettings",
    "RowSummary",
    "summarise_rows",
    "summarise_trajectory",
    "row_crossings",
]

MODES = ("zigzag", "displacement", "wrap-and-jump", "trapped", "mixed")


@dataclass(frozen=True)
class ModeSettings:
    """Thresholds of the mode rule (fractions of ε λy, of rows; speed in µm/s)."""

    zigzag_max: float = 0.25
    displacement_min: float = 0.75
    wrap_fraction: float = 0.2
    wrap_angle_deg: float = 90.0
    trap_speed: float = 6.0


@dataclass(frozen=True)
class RowSummary:
    """What one run did in the array.

    Attributes
    ----------
    rows : int
        Whole rows crossed.
    shift_per_row : float
        Mean lateral displacement per row m [µm] (NaN below one row).
    angle_deg : float
        Migration angle atan(m / λx) [deg].
    fraction : float
        m / (ε λy).
    wraps : int
        Contact episodes with a turn beyond ``wrap_angle_deg``.
    mode : str
        One of :data:`MODES`.
    """

    rows: int
    shift_per_row: float
    angle_deg: float
    fraction: float
    wraps: int
    mode: str


def row_crossings(x: np.ndarray, y: np.ndarray, period_x: float) -> np.ndarray:
    """Lateral position [µm] where the centre first reaches x0 + k λx, k = 0..K (shape (K+1,))."""
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    if x.size < 2:
        return y[:1].copy()
    xm = np.maximum.accumulate(x)
    k_max = int(math.floor((xm[-1] - x[0]) / period_x + 1e-9))
    targets = x[0] + period_x * np.arange(k_max + 1)
    idx = np.searchsorted(xm, targets, side="left")
    idx = np.clip(idx, 1, x.size - 1)
    x0, x1 = xm[idx - 1], xm[idx]
    w = np.where(x1 > x0, (targets - x0) / np.where(x1 > x0, x1 - x0, 1.0), 1.0)
    out = y[idx - 1] + w * (y[idx] - y[idx - 1])
    out[0] = y[0]
    return out


def _wraps(th: np.ndarray, contact: np.ndarray, angle: float) -> int:
    n = 0
    start = None
    for i, c in enumerate(contact > 0.5):
        if c and start is None:
            start = i
        if (not c or i == contact.size - 1) and start is not None:
            seg = th[start : i + 1]
            if seg.size and (seg.max() - seg.min()) > angle:
                n += 1
            start = None
    return n


def summarise_rows(
    traj: dict,
    period_x: float,
    lateral_shift: float,
    settings: ModeSettings = ModeSettings(),
) -> RowSummary:
    """Migration and mode of one run from its trajectory.

    Parameters
    ----------
    traj : dict of ndarray
        ``t`` [s], ``xc``, ``yc`` [µm], ``th`` [rad], ``contact`` (0/1), ``speed`` [µm/s],
        in time order.
    period_x, lateral_shift : float
        λx and ε λy [µm].
    settings : ModeSettings
    """
    x, y = np.asarray(traj["xc"]), np.asarray(traj["yc"])
    contact = np.asarray(traj["contact"], dtype=np.float64)
    ycross = row_crossings(x, y, period_x)
    rows = ycross.size - 1
    wraps = _wraps(np.asarray(traj["th"]), contact, math.radians(settings.wrap_angle_deg))
    if rows >= 1:
        m = float((ycross[-1] - ycross[0]) / rows)
        frac = m / lateral_shift if lateral_shift > 0 else math.nan
        ang = math.degrees(math.atan2(m, period_x))
    else:
        m = frac = ang = math.nan
    speed = np.asarray(traj["speed"])
    if contact.size and contact[-1] > 0.5 and speed[-1] < settings.trap_speed:
        mode = "trapped"
    elif rows < 2 or not math.isfinite(frac):
        mode = "mixed"
    elif wraps >= settings.wrap_fraction * rows and frac > settings.zigzag_max:
        mode = "wrap-and-jump"
    elif frac >= settings.displacement_min:
        mode = "displacement"
    elif abs(frac) <= settings.zigzag_max:
        mode = "zigzag"
    else:
        mode = "mixed"
    return RowSummary(rows, m, ang, frac, wraps, mode)


def summarise_trajectory(
    traj, array, trap_speed: float, settings: ModeSettings | None = None
) -> RowSummary:
    """:func:`summarise_rows` of a stored :class:`~fibersweep.analysis.trajectory.Trajectory`.

    Parameters
    ----------
    traj : Trajectory
        A run's (thinned) trajectory: centre [µm], angle [deg], contact flag, centre speed.
    array : fibersweep.geometry.array.PillarArray
        Its periods and row shift.
    trap_speed : float
        Centre speed below which a run that ends in contact is trapped [µm/s]
        (``fiber.classify.trap_speed`` × u_center, the integrator's stop rule).
    settings : ModeSettings, optional
        The other thresholds (defaults of :class:`ModeSettings`).
    """
    base = settings or ModeSettings()
    rule = ModeSettings(
        zigzag_max=base.zigzag_max,
        displacement_min=base.displacement_min,
        wrap_fraction=base.wrap_fraction,
        wrap_angle_deg=base.wrap_angle_deg,
        trap_speed=trap_speed,
    )
    d = {
        "t": traj.t,
        "xc": traj.x,
        "yc": traj.y,
        "th": np.radians(traj.theta),
        "contact": np.asarray(traj.contact, dtype=np.float64),
        "speed": traj.com_speed,
    }
    return summarise_rows(d, array.period_x, array.lateral_shift, rule)
