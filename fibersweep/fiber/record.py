"""The per-step record the integrators write, their stop codes and their shared stop rule."""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fibersweep.analysis.trajectory import Trajectory

__all__ = ["COLS", "NCOLS", "STOP_REASONS", "stop_test", "trajectory_from_record", "write_row"]

# Columns of one record row (one per accepted step, at the start of the step).
T, XC, YC, TH, VX, VY, OM, CONTACT, CX, CY, MIN_DIST, HEAD_SPEED, COM_SPEED, HX, HY, TX, TY = range(
    17
)
COLS = (
    "t",
    "x",
    "y",
    "theta_rad",
    "vx",
    "vy",
    "omega",
    "contact",
    "contact_x",
    "contact_y",
    "min_dist",
    "head_speed",
    "com_speed",
    "head_x",
    "head_y",
    "tail_x",
    "tail_y",
)
NCOLS = len(COLS)

# Stop codes returned by the kernels.
CHUNK_FULL = 0
PASSED = 1
TRAPPED = 2
TIME_REACHED = 3
NAN = -1
PENETRATION = -2
TIME_LIMIT = -3
WALL = -4

STOP_REASONS = {
    NAN: "nan",
    PENETRATION: "penetration",
    TIME_LIMIT: "time limit",
    WALL: "left the channel",
}


@nb.njit(cache=True, inline="always")
def write_row(r, t, xc, yc, th, vx, vy, om, contact, cx, cy, min_d, head_speed, com_speed, hx, hy,
              tx, ty):  # fmt: skip
    """Fill one record row ``r`` (NCOLS,) in the order of COLS (see there for the units)."""
    r[T] = t
    r[XC] = xc
    r[YC] = yc
    r[TH] = th
    r[VX] = vx
    r[VY] = vy
    r[OM] = om
    r[CONTACT] = contact
    r[CX] = cx
    r[CY] = cy
    r[MIN_DIST] = min_d
    r[HEAD_SPEED] = head_speed
    r[COM_SPEED] = com_speed
    r[HX] = hx
    r[HY] = hy
    r[TX] = tx
    r[TY] = ty


@nb.njit(cache=True, inline="always")
def stop_test(p, t, finite, min_d, y_min, y_max, stopped, stopped_since, x_rear, t_tol):
    """The stop rule shared by both integrators, on the state about to be recorded.

    Parameters
    ----------
    p : bundles.Params
    t : float
        Time [s].
    finite : bool
        Whether the state (or its velocity) is finite.
    min_d : float
        Smallest bead-centre distance to the pillar [µm].
    y_min, y_max : float
        Lowest and highest bead centre [µm].
    stopped : bool
        In contact and slower than ``p.trap_speed``.
    stopped_since : float
        When the current stop began [s] (NaN when not stopped).
    x_rear : float
        x of the rearmost end bead [µm].
    t_tol : float
        Mode 1 stops at ``t >= p.t_stop - t_tol`` [s].

    Returns
    -------
    (code, stopped_since) : (int, float)
        CHUNK_FULL to go on, or the stop code; the updated stop start.
    """
    if stopped:
        if not math.isfinite(stopped_since):
            stopped_since = t
    else:
        stopped_since = math.nan
    # np.int64: plain (non-literal) integers, as Numba's literal_unroll callers need
    code = np.int64(CHUNK_FULL)
    if not finite:
        code = np.int64(NAN)
    elif min_d < 0.5 * p.a:
        code = np.int64(PENETRATION)
    elif y_min < p.y_lo or y_max > p.y_hi:
        code = np.int64(WALL)
    elif stopped and t - stopped_since >= p.trap_time:
        code = np.int64(TRAPPED)
    elif p.mode == 0 and x_rear > p.x_stop:
        code = np.int64(PASSED)
    elif p.mode == 1 and t >= p.t_stop - t_tol:
        code = np.int64(TIME_REACHED)
    elif t >= p.t_max:
        code = np.int64(TIME_LIMIT)
    return code, stopped_since


def trajectory_from_record(rec: np.ndarray, beads: np.ndarray | None = None) -> Trajectory:
    """Full-resolution Trajectory from integrator rows (record.COLS), shape (m, NCOLS).

    ``theta`` is the directed tail→head angle in degrees, unwrapped.
    """
    th = np.degrees(np.unwrap(rec[:, TH]))
    return Trajectory(
        t=rec[:, T].copy(),
        x=rec[:, XC].copy(),
        y=rec[:, YC].copy(),
        theta=th,
        head=rec[:, [HX, HY]].copy(),
        tail=rec[:, [TX, TY]].copy(),
        head_speed=rec[:, HEAD_SPEED].copy(),
        com_speed=rec[:, COM_SPEED].copy(),
        contact=rec[:, CONTACT] > 0.5,
        beads=beads,
    )
