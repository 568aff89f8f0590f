"""Optional effects on a fiber run: a registry of small frozen parameter objects.

Each effect is one module in this package defining an :class:`Effect`
subclass decorated with :func:`register`. Every module here is imported on
package import, so adding an effect means adding a module and nothing else.
``FiberSettings.effects`` maps a name to a float; 0 is the baseline, and an
effect at 0 is dropped before the run (no cost). An unknown name raises
:class:`~fibersweep.errors.InputError` listing the valid names.

Interface (see :class:`Effect`): override only the hooks you need.

- ``transform_field(FlowField) -> FlowField``: the field one run sees.
- ``transform_start(FiberStart, rng) -> FiberStart``: the initial condition;
  ``rng`` is a ``numpy.random.Generator`` seeded from ``simulate(rng_seed=...)``.
- ``sample_flow(FlowArrays, bead_radius) -> FlowArrays``: the node velocities the
  beads' velocity is read from, once per run (a correction linear in the field).
- ``kernel(DynamicsContext) -> record``: for an effect acting inside the Numba
  integrators, its kernel record (a NamedTuple of floats); the module also
  implements the kernel stages for that record type
  (:mod:`fibersweep.fiber.kernel.hooks`), so the force or mobility change lives here,
  next to its parameter, and is compiled in only when the effect is on.
- ``transform_result(RunResult, FiberStart, Geometry) -> RunResult``: the report;
  an effect that changes units changes every reported quantity back here.
- ``validate()``: range checks; raise InputError naming ``effects.<name>``.

Built-in dynamic effects: ``friction``, ``pillar_hydro``, ``off_midplane``,
``brownian`` (each module documents what its value means). A fittable effect
also gets one line in :data:`fibersweep.discrepancy.candidates.LIBRARY`.
"""

from __future__ import annotations

import importlib
import pkgutil

from fibersweep.fiber.effects.base import DynamicsContext, Effect
from fibersweep.fiber.effects.registry import (
    EFFECTS,
    EffectSet,
    build_effects,
    get_effect,
    register,
)

__all__ = [
    "EFFECTS",
    "DynamicsContext",
    "Effect",
    "EffectSet",
    "build_effects",
    "get_effect",
    "register",
]

for _mod in pkgutil.iter_modules(__path__):
    if _mod.name not in {"base", "registry"}:
        importlib.import_module(f"{__name__}.{_mod.name}")
