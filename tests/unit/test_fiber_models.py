"""Model and integrator: two settings, two results columns; the former model name still read."""

from __future__ import annotations

import logging

import pytest
from pydantic import ValidationError

from fibersweep.config.fiber import FiberSettings
from fibersweep.errors import InputError
from fibersweep.fiber.models.registry import get_integrator, integrator_of
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate
from fibersweep.sweep.ids import fiber_result_settings, run_id
from fibersweep.sweep.store import PartWriter, read_runs

SHORT = FiberStart(8.0, 0.351, 0.5)  # 0.5 l_obs meeting the pillar apex from x0 = 1100 µm


def test_the_integrator_column_tells_ros2_from_ros34pw2_in_the_store(coarse_field, tmp_path):
    """Two runs of the same model with the two Rosenbrock-W methods, stored and read back:
    same ``model``, their own ``integrator``; the former spelling (model bead-spring-ros2,
    step.rosenbrock) stores the same columns."""
    runs = {
        "ros2": FiberSettings(model="bead-spring", integrator="ros2", x0=1100.0),
        "ros34pw2": FiberSettings(model="bead-spring", integrator="ros34pw2", x0=1100.0),
        "legacy": FiberSettings(
            model="bead-spring-ros2", x0=1100.0, step={"rosenbrock": "ros34pw2"}
        ),
    }
    with PartWriter(tmp_path) as w:
        for name, st in runs.items():
            r = simulate(coarse_field, st, SHORT)
            assert r.status == "ok", r
            w.add({"id": name, **r.row()}, None)
    df = read_runs(tmp_path).set_index("id")
    assert set(df["model"]) == {"bead-spring"}
    assert df.loc["ros2", "integrator"] == "ros2"
    assert df.loc["ros34pw2", "integrator"] == df.loc["legacy", "integrator"] == "ros34pw2"
    assert df.loc["ros2", "n_steps"] != df.loc["ros34pw2", "n_steps"]  # two methods ran


def test_rigid_and_bdf2_dumps_and_ids_are_as_before_the_integrator_setting():
    """The integrator at the model's default is not written (so the run ids of rigid runs
    and of ``model: bead-spring`` runs stay those of configs written before it existed);
    an explicit default is the same settings; another integrator is written."""
    start = FiberStart(0.0, 0.4, 1.0)
    for model in ("rigid", "bead-spring"):
        implicit = FiberSettings(model=model)
        explicit = FiberSettings(model=model, integrator=integrator_of(implicit).name)
        assert "integrator" not in fiber_result_settings(implicit)
        assert explicit == implicit
        assert run_id(start, explicit, "k") == run_id(start, implicit, "k")
    ros = FiberSettings(model="bead-spring", integrator="ros2")
    assert fiber_result_settings(ros)["integrator"] == "ros2"
    assert FiberSettings.model_validate(ros.model_dump()) == ros
    assert run_id(start, ros, "k") != run_id(start, FiberSettings(model="bead-spring"), "k")


def test_the_former_model_name_reads_as_the_pair_with_a_logged_deprecation(caplog):
    """``model: bead-spring-ros2`` with ``step.rosenbrock`` is the pair (bead-spring, method):
    equal settings, equal run ids, a warning naming the new spelling; so is the new spelling
    with a ``step.rosenbrock`` that agrees."""
    start = FiberStart(0.0, 0.4, 1.0)
    for method in ("ros2", "ros34pw2"):
        with caplog.at_level(logging.WARNING, logger="fibersweep.config.fiber"):
            old = FiberSettings(model="bead-spring-ros2", step={"rosenbrock": method})
        assert f"integrator: {method}" in caplog.text and "deprecated" in caplog.text
        new = FiberSettings(model="bead-spring", integrator=method)
        both = FiberSettings(model="bead-spring", integrator=method, step={"rosenbrock": method})
        assert old == new == both and run_id(start, old, "k") == run_id(start, new, "k")
        assert integrator_of(old).name == method
    # with the rigid model or BDF2, step.rosenbrock keeps its old meaning (none) and dump
    for model in ("rigid", "bead-spring"):
        st = FiberSettings(model=model, step={"rosenbrock": "ros34pw2"})
        assert st.integrator is None and st.step.rosenbrock == "ros34pw2"


@pytest.mark.parametrize(
    ("settings", "match"),
    [
        ({"integrator": "bdf2"}, "not an integrator of the rigid model"),
        ({"model": "bead-spring", "integrator": "midpoint"}, "bead-spring: bdf2, ros2, ros34pw2"),
        ({"model": "bead-spring-ros2", "integrator": "bdf2"}, "contradicts"),
        (
            {"model": "bead-spring", "integrator": "ros2", "step": {"rosenbrock": "ros34pw2"}},
            "step.rosenbrock",
        ),
    ],
)
def test_pairs_that_are_not_one_are_refused_naming_the_valid_ones(settings, match):
    with pytest.raises(ValidationError, match=match):
        FiberSettings(**settings)


def test_the_registry_refuses_an_unknown_pair_listing_the_valid_ones():
    """What a copy made without validation may hold is refused when a run looks it up."""
    st = FiberSettings().model_copy(update={"integrator": "ros2"})
    with pytest.raises(InputError, match="rigid: midpoint; bead-spring: bdf2, ros2, ros34pw2"):
        integrator_of(st)
    with pytest.raises(InputError, match="valid pairs"):
        get_integrator("bead-spring-ros2")
