"""``start_noise``: extra error on the starting conditions (value = k, noise k x reference).

A nuisance effect: the fiber really starts from the nominal start plus
Gaussian noise of standard deviation k x (1°, 0.01 h_obs, 0.01 l_obs) on
(θ0, y0/h_obs, L/l_obs) — the discrepancy workflow's default measurement
noise (:class:`fibersweep.discrepancy.copies.NoiseModel`) — drawn from the
run's seeded generator. With measurements that already carry that noise, the
total start error is sqrt(1 + k²) times the assumed one.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from fibersweep.fiber.effects.base import Effect
from fibersweep.fiber.effects.registry import register

if TYPE_CHECKING:  # pragma: no cover
    from fibersweep.fiber.result import FiberStart

#: Reference standard deviations (θ0 [deg], y0 [/h_obs], L [/l_obs]) for k = 1.
REFERENCE_SD = (1.0, 0.01, 0.01)
MIN_LENGTH = 0.05  # L / l_obs floor (a fiber of at least one bead)


@register
@dataclass(frozen=True)
class StartNoise(Effect):
    name = "start_noise"
    unit = "multiple k >= 0 of the reference start noise (1 deg, 0.01 h, 0.01 l)"

    def validate(self) -> None:
        self._require(self.value >= 0.0, "must be >= 0")

    def transform_start(self, start: FiberStart, rng: np.random.Generator) -> FiberStart:
        from fibersweep.fiber.result import FiberStart

        z = rng.standard_normal(3) * self.value * np.asarray(REFERENCE_SD)
        return FiberStart(
            theta0=start.theta0 + float(z[0]),
            y0=start.y0 + float(z[1]),
            length=max(MIN_LENGTH, start.length + float(z[2])),
        )
