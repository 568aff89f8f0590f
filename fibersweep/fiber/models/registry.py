"""Registry of the fiber models and their integrators (``fiber.model``, ``fiber.integrator``).

A model is the fiber's physics (rigid body, or bead-spring chain); each has
one or more integrators, the first its default. The pairs are those the
settings accept (:data:`fibersweep.config.fiber.INTEGRATORS`, held equal by
tests/unit/test_registries.py).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from fibersweep.config.fiber import FiberSettings, valid_pairs
from fibersweep.errors import InputError
from fibersweep.fiber.integrators.bdf2 import run_bdf2
from fibersweep.fiber.integrators.rosenbrock import run_rosenbrock
from fibersweep.fiber.kernel import record as R
from fibersweep.fiber.kernel.bundles import Kernel
from fibersweep.fiber.models.rigid import run_rigid

__all__ = ["MODELS", "FiberModel", "Integrator", "get_integrator", "integrator_of"]


@dataclass(frozen=True)
class Integrator:
    """One time integrator of a model.

    Attributes
    ----------
    name : str
        Its ``FiberSettings.integrator`` value.
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


@dataclass(frozen=True)
class FiberModel:
    """One fiber model: its ``FiberSettings.model`` name and its integrators (default first)."""

    name: str
    integrators: dict[str, Integrator] = field(default_factory=dict)

    @property
    def default(self) -> Integrator:
        """The integrator a run of this model gets when ``fiber.integrator`` is unset."""
        return next(iter(self.integrators.values()))


def _model(name: str, *integrators: Integrator) -> FiberModel:
    return FiberModel(name, {i.name: i for i in integrators})


MODELS: dict[str, FiberModel] = {
    m.name: m
    for m in (
        _model("rigid", Integrator("midpoint", run_rigid, fixed_step=False)),
        _model(
            "bead-spring",
            Integrator("bdf2", run_bdf2, fixed_step=True),
            Integrator("ros2", run_rosenbrock, fixed_step=False),
            Integrator("ros34pw2", run_rosenbrock, fixed_step=False),
        ),
    )
}


def get_integrator(model: str, integrator: str | None = None) -> Integrator:
    """The integrator ``integrator`` (None: the default) of ``model``.

    Raises
    ------
    InputError
        Not a valid pair; the message lists the valid ones.
    """
    m = MODELS.get(model)
    if m is None or (integrator is not None and integrator not in m.integrators):
        raise InputError(
            f"fiber.model {model!r}, fiber.integrator {integrator!r}: not a model and one of "
            f"its integrators; valid pairs (model: integrator): {valid_pairs()}"
        )
    return m.default if integrator is None else m.integrators[integrator]


def integrator_of(settings: FiberSettings) -> Integrator:
    """The integrator a run with these settings uses."""
    return get_integrator(settings.model, settings.integrator)
