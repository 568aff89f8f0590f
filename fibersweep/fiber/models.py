"""Registry of the fiber models: name -> integrator (the keys of ``FiberSettings.model``)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from fibersweep.fiber import record as R
from fibersweep.fiber.beadspring import run_bead_spring
from fibersweep.fiber.bundles import Kernel
from fibersweep.fiber.implicit_beadspring import run_bead_spring_ros2
from fibersweep.fiber.rigid import run_rigid

__all__ = ["MODELS", "FiberModel"]


@dataclass(frozen=True)
class FiberModel:
    """One fiber model.

    Attributes
    ----------
    name : str
        Its ``FiberSettings.model`` value.
    integrate : callable
        ``(kernel, x0, y0, th0, beads0) -> (record rows, bead positions or None, stop code)``;
        (x0, y0) the centre [µm], th0 the axis angle [rad], beads0 (n, 2) optional
        start positions [µm].
    fixed_step : bool
        True when it steps with the fixed ``Params.dt`` (step count = t_end / dt);
        otherwise one record row per step.
    """

    name: str
    integrate: Callable[
        [Kernel, float, float, float, np.ndarray | None],
        tuple[np.ndarray, np.ndarray | None, int],
    ]
    fixed_step: bool

    def steps(self, k: Kernel, rec: np.ndarray) -> int:
        """Time steps a finished run took."""
        if self.fixed_step:
            return int(round(float(rec[-1, R.T]) / k.params.dt))
        return int(len(rec) - 1)


MODELS: dict[str, FiberModel] = {
    m.name: m
    for m in (
        FiberModel("rigid", run_rigid, fixed_step=False),
        FiberModel("bead-spring", run_bead_spring, fixed_step=True),
        FiberModel("bead-spring-ros2", run_bead_spring_ros2, fixed_step=False),
    )
}
