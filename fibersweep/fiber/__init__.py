"""fibersweep.fiber: one fiber run past the pillar.

Public entry points: :func:`fibersweep.fiber.run.simulate`,
:func:`~fibersweep.fiber.run.simulate_reversible`, :func:`~fibersweep.fiber.run.simulate_for`.

Modules: ``mobility`` (RPY, rigid body mobility, cached per length), ``contact``
and ``bezier`` (rough / smooth pillar forces), ``rigid`` (rigid multiblob RK2
kernel), ``elastic`` and ``beadspring`` (the source's model, BDF2 kernel),
``models`` (registry of the models), ``setup`` (input checks), ``bundles``
(the typed kernel inputs, built once per run by ``build_kernel``), ``hooks``
(the kernel stages effects implement, dispatched at compile time), ``effects``
(registry of optional effects; each dynamic one owns its kernel stages),
``wallhydro`` (pillar wall-drag law), ``record`` (record layout, stop codes,
the stop rule both integrators share), ``settings``/``result`` (contracts).
"""

from fibersweep.numba_cache import sync_kernel_cache

sync_kernel_cache()  # before any cached kernel loads: drop caches of older sources
