"""``pillar_scale``: the real pillar is (1 + ε) times the nominal one (value = ε).

A nuisance calibration: the pillar was fabricated (or imaged) at a size
differing from the nominal h_obs, its centroid in place, while the measured
positions and lengths are normalised with the *nominal* size. Modelled as a
change of units only: in units of the real pillar the flow around it is the
nominal flow (this neglects the O(ε) change of the bead radius and channel
depth relative to the pillar). So the run starts at

    y0' = (y0 + ε/3) / (1 + ε),   L' = L / (1 + ε)     (centroid at y/h = 1/3)

and its lengths come back to nominal units with :meth:`PillarScale.transform_outcome`
(δ x (1 + ε), y_c x (1 + ε) − ε/3). The run itself reports real-pillar units;
the discrepancy workflow (``fibersweep synth`` / ``discrepancy``) applies the
conversion, through the optional ``transform_outcome`` hook it looks for.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from fibersweep.fiber.effects.base import Effect
from fibersweep.fiber.effects.registry import register

if TYPE_CHECKING:  # pragma: no cover
    from fibersweep.fiber.result import FiberStart


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

    def transform_outcome(self, row: dict[str, Any]) -> dict[str, Any]:
        """Real-pillar units back to nominal ones (δ, y_c); other columns unchanged."""
        s = 1.0 + self.value
        out = dict(row)
        if "delta" in out:
            out["delta"] = out["delta"] * s
        if "y_c" in out:
            out["y_c"] = out["y_c"] * s - self.value / 3.0
        return out
