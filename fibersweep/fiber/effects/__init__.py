"""Optional effects on a fiber run: a registry of small frozen parameter objects.

Each effect is one module in this package defining an :class:`Effect`
subclass decorated with :func:`register`. Every module here is imported on
package import, so adding an effect means adding a module and nothing else.
``FiberSettings.effects`` maps a name to a float; 0 is the baseline, and an
effect at 0 is dropped before the run (no cost). An unknown name raises
:class:`~fibersweep.errors.InputError` listing the valid names.

Interface (see :class:`Effect`): override only the hooks you need.

- ``transform_flow(FlowSettings) -> FlowSettings``: the flow problem (callers
  that build the field apply it: ``build_effects(spec).flow(flow_settings)``).
- ``transform_field(FlowField) -> FlowField``: the field one run sees.
- ``transform_settings(FiberSettings) -> FiberSettings``: the run's settings.
- ``transform_start(FiberStart, rng) -> FiberStart``: the initial condition;
  ``rng`` is a ``numpy.random.Generator`` seeded from ``simulate(rng_seed=...)``.
- ``dynamics(DynamicsParams, DynamicsContext) -> DynamicsParams``: the floats
  the Numba kernels read (velocity scale, friction, near-pillar slow-down, kT).
- ``validate()``: range checks; raise InputError naming ``effects.<name>``.

Built-in dynamic effects: ``friction``, ``pillar_hydro``, ``off_midplane``,
``brownian`` (each module documents what its value means).
"""

from __future__ import annotations

import importlib
import pkgutil

from fibersweep.fiber.effects.base import DynamicsContext, DynamicsParams, Effect
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
    "DynamicsParams",
    "Effect",
    "EffectSet",
    "build_effects",
    "get_effect",
    "register",
]

for _mod in pkgutil.iter_modules(__path__):
    if _mod.name not in {"base", "registry"}:
        importlib.import_module(f"{__name__}.{_mod.name}")
