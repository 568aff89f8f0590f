"""fibersweep.fiber: one fiber run past the pillar.

Public entry points: :func:`fibersweep.fiber.run.simulate`,
:func:`~fibersweep.fiber.run.simulate_reversible`, :func:`~fibersweep.fiber.run.simulate_for`.

Modules: ``mobility`` (RPY, rigid body mobility, cached per length), ``contact``
and ``bezier`` (rough / smooth pillar forces), ``rigid`` (rigid multiblob RK2
kernel), ``elastic`` and ``beadspring`` (the source's model, BDF2 kernel),
``setup`` (input checks, kernel parameters), ``effects`` (registry of optional
effects), ``record``/``kparams`` (kernel record layout and parameter vector),
``settings``/``result`` (contracts).
"""
