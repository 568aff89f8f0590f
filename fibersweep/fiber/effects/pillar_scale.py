"""``pillar_scale``: the real pillar is (1 + ε) times the nominal one (value = ε).

A nuisance calibration: the pillar was fabricated (or imaged) at a size
differing from the nominal h_obs, its centroid in place, while the measured
positions and lengths are normalised with the *nominal* size. Modelled as a
change of units only: in units of the real pillar the flow around it is the
nominal flow (this neglects the O(ε) change of the bead radius and channel
depth relative to the pillar). So the run starts at

    y0' = (y0 + ε/3) / (1 + ε),   L' = L / (1 + ε)     (centroid at y/h = 1/3)

and its report comes back to nominal units (:meth:`PillarScale.transform_result`),
every unit change in this one place: the nominal start, δ x (1 + ε),
y_c x (1 + ε) − ε/3, and every position in µm (x_f, y_f, the trajectory's
centre, ends, beads and speeds) stretched by (1 + ε) about the pillar centroid
(:func:`scaled_track`), as a camera that images the real pillar sees them. Times
and angles are unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from fibersweep.analysis.trajectory import Trajectory
from fibersweep.fiber.effects.base import Effect
from fibersweep.fiber.effects.registry import register

if TYPE_CHECKING:  # pragma: no cover
    from fibersweep.fiber.result import FiberStart, RunResult
    from fibersweep.units import Geometry


def scaled_track(traj: Trajectory, centre: tuple[float, float], scale: float) -> Trajectory:
    """Positions of a run in units of a pillar ``scale`` times the nominal one, in µm.

    The ``pillar_scale`` effect runs the nominal flow in units of the real pillar
    (its centroid in place); a camera sees those positions stretched by ``scale``
    about the centroid. Times and angles are unchanged.

    Parameters
    ----------
    traj : Trajectory
        Run in the simulation's units [µm].
    centre : (float, float)
        Pillar centroid [µm].
    scale : float
        Real / nominal pillar size, 1 + ε.
    """
    c = np.asarray(centre, dtype=np.float64)

    def s(p: np.ndarray) -> np.ndarray:
        return c + scale * (p - c)

    return replace(
        traj,
        x=c[0] + scale * (traj.x - c[0]),
        y=c[1] + scale * (traj.y - c[1]),
        head=s(traj.head),
        tail=s(traj.tail),
        head_speed=scale * traj.head_speed,
        com_speed=scale * traj.com_speed,
        beads=None if traj.beads is None else s(traj.beads),
    )


@register
@dataclass(frozen=True)
class PillarScale(Effect):
    name = "pillar_scale"
    unit = "relative size error ε of the pillar, real = (1 + ε) nominal, in (-0.5, 0.5)"

    def validate(self) -> None:
        self._require(-0.5 < self.value < 0.5, "must be in (-0.5, 0.5)")

    def transform_start(self, start: FiberStart, rng: np.random.Generator) -> FiberStart:
        from fibersweep.fiber.result import FiberStart

        s = 1.0 + self.value
        return FiberStart(
            theta0=start.theta0,
            y0=(start.y0 + self.value / 3.0) / s,
            length=start.length / s,
        )

    def transform_result(
        self, result: RunResult, start: FiberStart, geometry: Geometry
    ) -> RunResult:
        """Real-pillar units back to nominal ones: the asked start, δ, y_c and positions [µm]."""
        s = 1.0 + self.value
        cx, cy = geometry.centroid
        traj = result.trajectory
        return replace(
            result,
            start=start,
            delta=result.delta * s,
            y_c=result.y_c * s - self.value / 3.0,
            x_f=cx + s * (result.x_f - cx),
            y_f=cy + s * (result.y_f - cy),
            trajectory=None if traj is None else scaled_track(traj, geometry.centroid, s),
        )
