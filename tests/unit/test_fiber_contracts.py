"""Contracts every registered effect and fiber model keeps (parametrised over the registries)."""

from __future__ import annotations

import math
import typing

import numpy as np
import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.errors import InputError
from fibersweep.fiber.effects import EFFECTS, DynamicsContext, build_effects
from fibersweep.fiber.kernel import hooks
from fibersweep.fiber.models.registry import MODELS
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate_for

CTX = DynamicsContext(bead_radius=2.0, dx=4.0, depth=40.0)
# Values a range check may reject; every effect must reject at least one finite one.
PROBES = (-1e9, -1.0, -0.6, 0.6, 1.0, 1e9)
# A fiber that meets the pillar apex within the first 0.05 s (x0 close to the pillar).
CONTACT_START = FiberStart(8.0, 0.351, 0.5)
STAGE_MODELS = {
    "background": {"rigid", "bead-spring"},
    "rigid_mobility": {"rigid"},
    "rigid_contact": {"rigid"},
    "rigid_noise": {"rigid"},
    # every bead-spring integrator evaluates f(q) with the model's bead_velocity
    "bead_forces": {"bead-spring"},
    "bead_mobility": {"bead-spring"},
}
# every (model, integrator) pair of the registry
PAIRS = [(m, i) for m, model in MODELS.items() for i in model.integrators]


@pytest.mark.parametrize("name", sorted(EFFECTS))
def test_range_check_names_the_effect(name):
    """Non-finite values and at least one finite value are rejected, naming effects.<name>."""
    for bad in (math.nan, math.inf):
        with pytest.raises(InputError, match=f"effects.{name}"):
            build_effects({name: bad})
    rejected = 0
    for value in PROBES:
        try:
            build_effects({name: value})
        except InputError as exc:
            assert f"effects.{name}" in str(exc)
            rejected += 1
    assert rejected > 0, f"{name} has no range check"


@pytest.mark.parametrize("name", sorted(EFFECTS))
def test_kernel_stages_cover_the_declared_models(name):
    """An effect with a kernel record implements a stage in every model it lists and none
    outside them; an effect without one has no stages."""
    cls = EFFECTS[name]
    assert set(cls.models) <= set(MODELS)
    value = next(v for v in (0.1, 1.0, -0.1) if _valid(name, v))
    rec = cls(value).kernel(CTX)
    if rec is None:
        return
    stages = hooks.stages_of(type(rec))
    assert stages, f"{name} hands the kernel a record but implements no stage"
    covered = set().union(*(STAGE_MODELS[s] for s in stages))
    assert covered == set(cls.models)


def _valid(name: str, value: float) -> bool:
    try:
        build_effects({name: value})
    except InputError:
        return False
    return True


def test_model_registry_is_the_settings_choice():
    literal = FiberSettings.model_fields["model"].annotation
    assert set(typing.get_args(literal)) == set(MODELS)


@pytest.mark.parametrize(("model", "integrator"), PAIRS)
@pytest.mark.parametrize("name", sorted(EFFECTS))
def test_effect_at_zero_is_bit_identical_to_none(coarse_field, model, integrator, name):
    """A fiber meeting the pillar (0.05 s from x0 = 1150 µm): the trajectory with the effect
    at 0 equals the one without it, bit for bit, with every integrator."""
    base = FiberSettings(model=model, integrator=integrator, x0=1150.0)
    runs = [
        simulate_for(coarse_field, st, CONTACT_START, 0.05, rng_seed=1)
        for st in (base, base.model_copy(update={"effects": {name: 0.0}}))
    ]
    (a, ra), (b, rb) = runs
    assert ra == rb == ""
    for key, col in a.columns().items():
        assert np.array_equal(col, b.columns()[key]), key
    if a.beads is not None:
        assert np.array_equal(a.beads, b.beads)


def test_stage_implementations_must_match_the_stage_signature():
    class Rec(typing.NamedTuple):
        x: float

    with pytest.raises(ValueError, match="unknown kernel stage"):
        hooks.implements("nonsense", Rec)
    with pytest.raises(TypeError, match="takes \\(e, w, u\\)"):

        @hooks.implements("background", Rec)
        def wrong(e, velocities):  # pragma: no cover - never called
            return None

    assert hooks.stages_of(Rec) == frozenset()


def test_kernel_records_live_in_the_effects_package():
    """The disk cache of the integrators names record types by module; a record defined
    elsewhere (a module that may be missing in another process) is refused."""

    class Outside(typing.NamedTuple):
        x: float

    with pytest.raises(TypeError, match="fibersweep.fiber.effects"):

        @hooks.implements("background", Outside)
        def background(e, w, u):  # pragma: no cover - never called
            return None

    for cls in EFFECTS.values():
        assert cls.__module__.startswith("fibersweep.fiber.effects.")
