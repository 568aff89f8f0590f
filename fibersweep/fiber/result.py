"""What one fiber run returns: a frozen record plus an optional trajectory.

This is the contract between the fiber dynamics (which fills it), the sweep
(which stores ``RunResult.row()`` in Parquet and the trajectory in a second
dataset) and the analysis (which re-classifies from the trajectory).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import Literal

from fibersweep.analysis.trajectory import CLASSES, Trajectory

__all__ = ["FiberStart", "Trajectory", "RunResult", "CLASSES", "STATUSES"]

STATUSES = ("ok", "failed")


@dataclass(frozen=True)
class FiberStart:
    """Initial condition of a run, in the model's normalised units.

    Attributes
    ----------
    theta0 : float
        Angle from +x, counter-clockwise [degrees].
    y0 : float
        Centre-of-mass lateral position from the pillar base / h_obs.
    length : float
        Fiber length L / l_obs.
    """

    theta0: float
    y0: float
    length: float


@dataclass(frozen=True)
class RunResult:
    """Outcome of one fiber run.

    Attributes
    ----------
    start : FiberStart
    status : {'ok', 'failed'}
    reason : str
        Why a run failed ('' when ok), e.g. 'nan', 'penetration', 'time limit'.
    cls : str
        One of CLASSES, or '' when failed.
    delta : float
        (y_f - y0) / h_obs far downstream; NaN for Trapping or failure.
    contact : bool
        Whether the contact force ever became non-zero.
    theta_c, y_c : float
        Fiber angle [deg] and contact point lateral position / h_obs at first
        contact (NaN without contact).
    t_contact, t_pass : float
        Time of first contact and time to pass the pillar [s] (NaN if none).
    x_f, y_f, theta_f : float
        Final centre of mass [µm] and angle [deg].
    n_steps : int
    wall_time : float
        Seconds of computation.
    model : str
    n_beads : int
        Beads of the fiber (0 when the run did not start).
    t_end : float
        Time at the end of the run [s].
    min_clearance : float
        Smallest bead-centre distance to the pillar outline minus a, over the run [µm].
    max_curvature : float
        Largest curvature of the fiber over the run [1/µm] (bead-spring models;
        NaN for rigid; :mod:`fibersweep.fiber.deformation`).
    min_end_to_end : float
        Smallest end-to-end distance over contour length over the run (NaN for rigid).
    max_tension : float
        Largest stretching-spring tension over the run [pN] (NaN for rigid).
    max_wrap : float
        Largest angle the fiber's tangent turns along its beads on the pillar [deg]
        (NaN for rigid).
    trajectory : Trajectory or None
    """

    start: FiberStart
    status: Literal["ok", "failed"]
    reason: str = ""
    cls: str = ""
    delta: float = math.nan
    contact: bool = False
    theta_c: float = math.nan
    y_c: float = math.nan
    t_contact: float = math.nan
    t_pass: float = math.nan
    x_f: float = math.nan
    y_f: float = math.nan
    theta_f: float = math.nan
    n_steps: int = 0
    wall_time: float = 0.0
    model: str = ""
    n_beads: int = 0
    t_end: float = math.nan
    min_clearance: float = math.nan
    max_curvature: float = math.nan
    min_end_to_end: float = math.nan
    max_tension: float = math.nan
    max_wrap: float = math.nan
    trajectory: Trajectory | None = field(default=None, compare=False, repr=False)

    def row(self) -> dict[str, object]:
        """Flat scalar columns for the results table (one row per run)."""
        # Not asdict(): it would deep-copy the trajectory only to drop it.
        d = {f.name: getattr(self, f.name) for f in fields(self)}
        d.pop("trajectory")
        start = d.pop("start")
        return {
            "theta0": start.theta0,
            "y0": start.y0,
            "length": start.length,
            "class": d.pop("cls"),
            **d,
        }
