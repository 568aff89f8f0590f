"""Layout of the per-step record the integrators write and the stop codes they return."""

from __future__ import annotations

__all__ = ["COLS", "NCOLS", "STOP_REASONS"]

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
