"""Every registry, one contract: entries named by their key, unknown names refused listing the
valid ones, settings' choices equal to the registry; and per-entry checks of each registry.

Registries: effects, fiber models and their integrators, executors, observables, the
discrepancy library, LBM steppers, collision schemes, pillar-wall schemes, classification
rules. The
physics of each entry is validated in its own tests; here every entry is held to the
interface its registry promises, so a new entry is checked without a new test.
"""

from __future__ import annotations

import typing

import numpy as np
import pytest

from fibersweep.analysis.classify import RULES
from fibersweep.config.fiber import INTEGRATORS, FiberSettings
from fibersweep.config.flow import FlowSettings
from fibersweep.discrepancy.candidates import LIBRARY, get_candidates
from fibersweep.discrepancy.observables import OBSERVABLES
from fibersweep.errors import InputError
from fibersweep.fiber.effects import EFFECTS, build_effects, get_effect
from fibersweep.fiber.models.registry import MODELS, get_integrator
from fibersweep.flow.schemes import COLLISIONS, WALL_SCHEMES, get_collision, get_wall_scheme
from fibersweep.flow.steppers import STEPPERS, make_stepper
from fibersweep.sweep.executors import EXECUTORS, make_executor

# (registry, how its entries name themselves, a lookup that must refuse an unknown name)
REGISTRIES = {
    "effects": (EFFECTS, lambda e: e.name, lambda n: get_effect(n)),
    "models": (MODELS, lambda m: m.name, lambda n: get_integrator(n)),
    "executors": (EXECUTORS, lambda c: c.name, lambda n: make_executor(n, 1)),
    "observables": (OBSERVABLES, lambda o: o.name, None),
    "library": (LIBRARY, lambda c: c.name, lambda n: get_candidates([n])),
    "steppers": (STEPPERS, None, lambda n: make_stepper(n)),
    "collisions": (COLLISIONS, lambda c: c.name, get_collision),
    "wall schemes": (WALL_SCHEMES, lambda w: w.name, get_wall_scheme),
    "rules": (RULES, lambda r: r.name, None),
}


@pytest.mark.parametrize("registry", sorted(REGISTRIES))
def test_entries_are_named_by_their_key_and_unknown_names_list_the_valid_ones(registry):
    entries, name_of, lookup = REGISTRIES[registry]
    assert entries, f"{registry}: empty"
    if name_of is not None:
        for key, entry in entries.items():
            assert name_of(entry) == key, (registry, key)
    if lookup is not None:
        with pytest.raises((InputError, ValueError)) as ei:
            lookup("no-such-entry")
        first = next(iter(entries))
        assert first in str(ei.value), f"{registry}: the message lists the valid names"


def _choices(field: str) -> set[str]:
    return set(typing.get_args(FlowSettings.model_fields[field].annotation))


@pytest.mark.parametrize("model", sorted(MODELS))
def test_each_model_registers_exactly_the_integrators_the_settings_offer(model):
    """``fiber.integrator`` is checked against :data:`INTEGRATORS`, the registry runs
    ``MODELS``: the same pairs, the same default (first), entries named by their key, and
    an unknown integrator refused with the valid pairs listed."""
    entry = MODELS[model]
    assert tuple(entry.integrators) == INTEGRATORS[model]
    assert entry.default is get_integrator(model) is entry.integrators[INTEGRATORS[model][0]]
    for name, integrator in entry.integrators.items():
        assert integrator.name == name and get_integrator(model, name) is integrator
    with pytest.raises(InputError) as ei:
        get_integrator(model, "no-such-integrator")
    assert all(i in str(ei.value) for i in INTEGRATORS[model])


def test_fiber_settings_offer_exactly_the_registered_models_and_integrators():
    """A new model or integrator is its registry entry plus its names in the settings."""
    model = FiberSettings.model_fields["model"].annotation
    assert set(typing.get_args(model)) == set(MODELS) == set(INTEGRATORS)
    integrator = FiberSettings.model_fields["integrator"].annotation
    names = {a for arg in typing.get_args(integrator) for a in typing.get_args(arg)}
    assert names == {i for m in MODELS.values() for i in m.integrators}


def test_flow_settings_offer_exactly_the_registered_schemes():
    """A new scheme is its registry entry plus its name in the settings' Literal."""
    assert _choices("collision") == set(COLLISIONS)
    assert _choices("pillar_boundary") == set(WALL_SCHEMES)


@pytest.mark.parametrize("name", sorted(COLLISIONS))
@pytest.mark.parametrize("tau", [0.55, 0.8, 1.5])
def test_every_collision_scheme_sets_the_viscosity_by_tau_and_is_stable(name, tau):
    """ω+ = 1/τ fixes ν = (τ − ½)/3 for every scheme; ω− in (0, 2) keeps it stable
    (exact equalities: one division each)."""
    magic = 3.0 / 16.0
    wp, wm = COLLISIONS[name].rates(tau, magic)
    assert wp == 1.0 / tau and 0.0 < wm < 2.0
    lam = (1.0 / wp - 0.5) * (1.0 / wm - 0.5)
    if name == "bgk":
        assert wm == wp
    elif name == "trt":
        assert lam == pytest.approx(magic, rel=1e-12)  # the magic parameter Λ


@pytest.mark.parametrize("stepper", sorted(STEPPERS))
@pytest.mark.parametrize("name", sorted(COLLISIONS))
def test_every_collision_scheme_and_stepper_reach_the_array_cell(name, stepper):
    """The unit cell is stepped with the scheme's own rates (the report's ω− is the
    registry's), and the flow it reaches conserves mass: every x-section clear of the
    pillar carries the same flux, 1e-4 of the mean at the stop at a change of 1e-5
    per 100 steps (measured 1e-5 to 6e-5)."""
    from fibersweep.flow.cell import cell_solution

    s = FlowSettings.model_validate(
        {"dx": 4.0, "collision": name, "tolerance": 1e-5, "array": {"mean_flow": "force"}}
    )
    sol = cell_solution(s, kernel=stepper)
    assert sol.report.converged
    assert sol.report.omega_minus == COLLISIONS[name].rates(sol.report.tau, s.magic)[1]
    flux = sol.u[0].sum(axis=(0, 1))
    x0, _, x1, _ = s.array.to_array().shape.bounds
    xs = (np.arange(flux.size) + 0.5) * s.dx
    clear = (xs < x0 - s.dx) | (xs > x1 + s.dx)
    assert np.ptp(flux[clear]) < 1e-4 * flux.mean()


@pytest.mark.parametrize("name", sorted(WALL_SCHEMES))
def test_every_wall_scheme_builds_its_lattice_and_links(name):
    """A sub-grid scheme closes the outline and cuts links at fractions q in (0, 1];
    a staircase one keeps the open lattice and no cut links."""
    from fibersweep.flow.cuts import pillar_cuts
    from fibersweep.flow.lbm import lattice_of

    s = FlowSettings(dx=4.0, pillar_boundary=name)
    scheme = WALL_SCHEMES[name]
    grid = lattice_of(s)
    cuts = pillar_cuts(grid, s.geometry.to_geometry().shape, name)
    if not scheme.sub_grid:
        assert cuts is None
        return
    assert cuts is not None and cuts.scheme == scheme.links
    q = cuts.q[np.isfinite(cuts.q)]
    assert q.size and np.all((q > 0.0) & (q <= 1.0))


@pytest.mark.parametrize("name", sorted(LIBRARY))
def test_every_library_candidate_is_an_effect_with_a_valid_range(name):
    c = LIBRARY[name]
    assert name in EFFECTS
    assert c.lo <= c.realistic <= c.hi and all(c.lo <= p <= c.hi for p in c.probes)
    assert build_effects({name: c.realistic}).effects, "the realistic magnitude is valid and on"


@pytest.mark.parametrize("name", sorted(RULES))
def test_every_rule_is_a_documented_pure_function(name):
    r = RULES[name]
    assert r.description and callable(r.vaulted)
