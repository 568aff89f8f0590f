"""The per-step record every integrator writes: its columns, the pose of a bead chain, the stop
codes, the stop rule they share, and the chunked loop that collects a run's rows."""

from __future__ import annotations

import math
from collections.abc import Callable

import numba as nb
import numpy as np

from fibersweep.analysis.trajectory import Trajectory

__all__ = [
    "CHUNK",
    "COLS",
    "NCOLS",
    "STOP_REASONS",
    "bead_pose",
    "collect",
    "stop_test",
    "trajectory_from_record",
    "write_bead_row",
    "write_row",
]

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
CHUNK = 20_000  # record rows per kernel call

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
def bead_pose(q, v, theta):
    """Pose of a bead chain at positions ``q`` (2n) [µm] moving with velocities ``v`` (2n) [µm/s].

    ``theta`` is the last unwrapped axis angle [rad]; the new one is the tail→head
    angle (bead 0 → bead n−1) continued from it by less than π.

    Returns
    -------
    (theta, xc, yc, vxc, vyc, com_speed, hx, hy, tx, ty, y_min, y_max, finite_q, finite_v)
        Axis angle [rad], centre and its velocity [µm, µm/s], its speed, head and
        tail bead [µm], lowest and highest bead centre [µm], whether q and v are
        finite.
    """
    n = q.shape[0] // 2
    hx = q[2 * n - 2]
    hy = q[2 * n - 1]
    tx = q[0]
    ty = q[1]
    ang = math.atan2(hy - ty, hx - tx)
    theta += (ang - theta + math.pi) % (2.0 * math.pi) - math.pi
    xc = 0.0
    yc = 0.0
    vxc = 0.0
    vyc = 0.0
    y_min = 1e300
    y_max = -1e300
    finite_q = True
    finite_v = True
    for i in range(n):
        xc += q[2 * i] / n
        yc += q[2 * i + 1] / n
        vxc += v[2 * i] / n
        vyc += v[2 * i + 1] / n
        y_min = min(y_min, q[2 * i + 1])
        y_max = max(y_max, q[2 * i + 1])
        if not (math.isfinite(q[2 * i]) and math.isfinite(q[2 * i + 1])):
            finite_q = False
        if not (math.isfinite(v[2 * i]) and math.isfinite(v[2 * i + 1])):
            finite_v = False
    com_speed = math.hypot(vxc, vyc)
    return theta, xc, yc, vxc, vyc, com_speed, hx, hy, tx, ty, y_min, y_max, finite_q, finite_v


@nb.njit(cache=True, inline="always")
def write_bead_row(r, br, t, q, v, pose, contact, cx, cy, min_d):
    """Record a bead chain: row ``r`` (NCOLS,) and its bead positions ``br`` (n, 2) [µm].

    ``pose`` is :func:`bead_pose` of (q, v); the angular velocity is that of the
    tail→head vector, the head speed that of bead n−1.
    """
    n = q.shape[0] // 2
    theta, xc, yc, vxc, vyc, com_speed, hx, hy, tx, ty, _, _, _, _ = pose
    ex = hx - tx
    ey = hy - ty
    om = (ex * (v[2 * n - 1] - v[1]) - ey * (v[2 * n - 2] - v[0])) / (ex * ex + ey * ey)
    write_row(
        r, t, xc, yc, theta, vxc, vyc, om, contact, cx, cy, min_d,
        math.hypot(v[2 * n - 2], v[2 * n - 1]), com_speed, hx, hy, tx, ty,
    )  # fmt: skip
    for i in range(n):
        br[i, 0] = q[2 * i]
        br[i, 1] = q[2 * i + 1]


@nb.njit(cache=True, inline="always")
def stop_test(p, t, finite, min_d, y_min, y_max, stopped, stopped_since, x_rear, t_tol):
    """The stop rule every integrator shares, on the state about to be recorded.

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
    # np.int64: plain (non-literal) integers, one type on every branch
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


def collect(
    advance: Callable[[np.ndarray, np.ndarray | None], tuple[int, int]], n_beads: int = 0
) -> tuple[np.ndarray, np.ndarray | None, int]:
    """Run an integrator chunk by chunk until it stops; its rows, bead positions and stop code.

    Parameters
    ----------
    advance : callable
        ``advance(rec, brec) -> (rows, code)``: fills ``rec`` (CHUNK, NCOLS) and, for a
        bead chain, ``brec`` (CHUNK, n_beads, 2) from row 0, carrying its own state
        from call to call; ``code`` is CHUNK_FULL while it goes on.
    n_beads : int
        Beads recorded per row (0: none, ``brec`` is None).

    Returns
    -------
    (rec, beads, code)
        Rows (m, NCOLS), bead positions (m, n_beads, 2) [µm] or None, stop code.
    """
    recs, brecs = [], []
    while True:
        rec = np.empty((CHUNK, NCOLS))
        brec = np.empty((CHUNK, n_beads, 2)) if n_beads else None
        rows, code = advance(rec, brec)
        recs.append(rec[:rows])
        if brec is not None:
            brecs.append(brec[:rows])
        if code != CHUNK_FULL:
            return np.concatenate(recs), np.concatenate(brecs) if n_beads else None, int(code)
