"""fibersweep.fiber: one fiber run past the pillar.

Public entry points: :func:`fibersweep.fiber.run.simulate`,
:func:`~fibersweep.fiber.run.simulate_reversible`, :func:`~fibersweep.fiber.run.simulate_for`.

Modules, by concept:

- physics: ``mobility`` (RPY, rigid body mobility, cached per length),
  ``pairlaw`` (the soft-core pair law, written once), ``contact`` and ``bezier``
  (rough / smooth pillar forces), ``exclusion`` (a fiber's self-exclusion),
  ``elastic`` (spring energy, forces, Jacobian), ``beadspring`` (the bead-spring
  model: bead velocities and force Jacobians), ``wallhydro`` (pillar wall-drag law);
- integrators: ``rigid`` (the rigid model and its midpoint stepping), ``bdf2``
  (bead-spring, fixed step), ``rosenbrock`` with ``rosw`` and ``lu`` (bead-spring,
  adaptive Rosenbrock-W: ROS2 or ROS34PW2), ``models`` (the registry of models and
  their integrators), ``record`` (record layout, the pose of a bead chain, stop
  codes, the stop rule every integrator shares);
- a run: ``setup`` (input checks), ``bundles`` (the typed kernel inputs, built
  once per run by ``build_kernel``), ``frame`` (one pillar or an array),
  ``hooks`` (the kernel stages effects implement, dispatched at compile time),
  ``effects`` (registry of optional effects; each dynamic one owns its kernel
  stages), ``run`` / ``array_run`` / ``rows`` (channel and array runs),
  ``deformation`` (bead-spring observables), ``settings`` / ``result`` (contracts).
"""

from fibersweep.numba_cache import sync_kernel_cache

sync_kernel_cache()  # before any cached kernel loads: drop caches of older sources
