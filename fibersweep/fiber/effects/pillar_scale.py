"""``pillar_scale``: the real pillar is (1 + ε) times the nominal one (value = ε).

A nuisance calibration: the pillar was fabricated (or imaged) at a size
differing from the nominal h_obs, its centroid in place, while the measured
positions and lengths are normalised with the *nominal* size. Modelled as a
change of units only: in units of the real pillar the flow around it is the
nominal flow (this neglects the O(ε) change of the bead radius and channel
depth relative to the pillar). So the run starts at

    y0' = (y0 + ε/3) / (1 + ε),   L' = L / (1 + ε)     (centroid at y/h = 1/3)

and its report comes back to nominal units (:meth:`PillarScale.transform_result`):
the nominal start, δ x (1 + ε), y_c x (1 + ε) − ε/3. Positions in µm (x_f,
y_f, the trajectory) stay those of the simulation, i.e. of the real pillar
drawn at the nominal size.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from fibersweep.fiber.effects.base import Effect
from fibersweep.fiber.effects.registry import register

if TYPE_CHECKING:  # pragma: no cover
    from fibersweep.fiber.result import FiberStart, RunResult


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

    def transform_result(self, result: RunResult, start: FiberStart) -> RunResult:
        """Real-pillar units back to nominal ones: the asked start, δ and y_c."""
        s = 1.0 + self.value
        return replace(
            result, start=start, delta=result.delta * s, y_c=result.y_c * s - self.value / 3.0
        )
