"""fibersweep.fiber: one fiber run past the pillar in its channel, or through a pillar array.

Public entry points: :func:`fibersweep.fiber.run.simulate`,
:func:`~fibersweep.fiber.run.simulate_reversible`, :func:`~fibersweep.fiber.run.simulate_for`.

Sub-packages, one concept each:

- ``models``: the fiber's body, the rigid model (with its adaptive midpoint stepping) and
  the bead-spring model with the elastic rod it stands for (``rod``: EA, EI), its
  forces, spacing and self-exclusion, the registry of models and integrators, and the
  deformation observables and elasto-viscous number of a run.
- ``integrators``: the bead-spring model's time steppers, fixed-step BDF2 and the
  adaptive Rosenbrock-W methods (ROS2, ROS34PW2) with their LU solve.
- ``contact``: the fiber-pillar repulsion, the soft-core pair law and the rough and
  smooth (Bézier) pillar outlines.
- ``hydro``: the beads' hydrodynamics, RPY and rigid-body mobility, and the sphere-wall
  resistances and first-reflection drag near the pillar.
- ``kernel``: what every Numba integrator shares, the typed input bundles built once per
  run, the compile-time stages the effects implement, and the record and stop rule.
- ``effects``: the registry of optional effects, each a small frozen parameter object
  that owns its kernel stages or its field, start or report hook.

Top-level modules, one run: ``run`` (the one run path: :func:`~.run.simulate` and its
fixed-duration and reversibility variants), ``case`` (what a case hands that path: its
placed run and its measurement), ``channel`` (the single-pillar case), ``array_run``
(the pillar-array case) and ``rows`` (the array's kernel assembly), ``setup`` (a channel
start's checks), ``frame`` (velocity and contact through one pillar or a lattice of
them), ``result`` (the run record, the one schema of the per-run columns).
"""

from fibersweep.numba_cache import sync_kernel_cache

sync_kernel_cache()  # before any cached kernel loads: drop caches of older sources
