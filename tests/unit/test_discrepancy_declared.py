"""Candidates from any setting: parsing, refusals, the simulator's per-batch settings,
a categorical fit, and a whole (tiny) workflow with a declared candidate."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.config.flow import FlowSettings
from fibersweep.discrepancy.candidates import LIBRARY, show_values
from fibersweep.discrepancy.declared import FLEXIBLE_MODEL, apply_values, parse_candidate
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.errors import InputError
from fibersweep.flow.field import FlowField
from fibersweep.units import Geometry

FIBER, FLOW = FiberSettings(), FlowSettings(dx=4.0)


@pytest.fixture(scope="module")
def uniform_field():
    return FlowField.from_function(lambda X, Y: (600.0 + 0 * X, 0 * X), Geometry(), 8.0)


def test_a_stiffness_of_a_rigid_config_is_a_model_switch_with_the_rigid_limit():
    c = parse_candidate("fiber.young_modulus=1e4..3e7", FIBER, FLOW)
    assert c.scale == "rigid"
    assert dict(c.switch) == {"fiber.model": FLEXIBLE_MODEL, "fiber.integrator": "ros2"}
    assert c.overrides(0.0) == {} and math.isinf(c.setting(0.0))  # 0: the rigid baseline
    # E = hi / (10**u - 1): the range's stiffest at log10 2, its softest at c.hi
    assert c.setting(math.log10(2.0)) == pytest.approx(3e7)
    assert c.setting(c.hi) == pytest.approx(1e4)
    assert c.lo == 0.0 and 0.0 < c.probes[0] < c.hi
    lo, hi = c.interval(0.0, c.hi)  # the scale runs backwards: ends swap
    assert lo == pytest.approx(1e4) and math.isinf(hi)
    fiber, flow = apply_values({c.name: c}, {c.name: c.hi}, FIBER, FLOW)
    assert fiber.model == FLEXIBLE_MODEL and fiber.integrator == "ros2"
    assert fiber.young_modulus == pytest.approx(1e4)
    assert flow == FLOW
    assert c.show(c.hi) == "fiber.young_modulus = 1e+04 Pa"
    assert c.show(0.0) == "fiber.young_modulus = ∞ (rigid)"


def test_ranges_are_log_over_decades_linear_otherwise_and_hold_the_config_value():
    explicit = parse_candidate(
        "fiber.model=bead-spring,fiber.young_modulus=1e5..1e8", FIBER, FLOW
    )
    assert explicit.scale == "rigid" and dict(explicit.switch) == {"fiber.model": "bead-spring"}
    flex = FiberSettings(model="bead-spring", integrator="ros2", young_modulus=1e6)
    log = parse_candidate("fiber.young_modulus=1e4..1e8", flex, FLOW)
    assert log.scale == "log" and log.lo == pytest.approx(-2) and log.hi == pytest.approx(2)
    assert log.setting(1.0) == pytest.approx(1e7) and log.signed and len(log.probes) == 2
    lin = parse_candidate("fiber.contact.chi=1.05..1.5", FIBER, FLOW)
    assert lin.scale == "linear" and lin.setting(0.0) == pytest.approx(1.1)
    assert lin.setting(lin.hi) == pytest.approx(1.5)


def test_an_alternative_is_compared_never_scanned():
    c = parse_candidate("fiber.contact.pillar=smooth", FIBER, FLOW)
    assert c.categorical and (c.lo, c.hi, c.probes) == (0.0, 1.0, (1.0,))
    assert c.overrides(1.0) == {"fiber.contact.pillar": "smooth"} and c.overrides(0.0) == {}
    assert show_values({c.name: 1.0, "friction": 0.25}, {c.name: c}) == (
        "fiber.contact.pillar=smooth + friction = 0.25"
    )
    dx = parse_candidate("flow.dx=5", FIBER, FLOW)
    assert apply_values({dx.name: dx}, {dx.name: 1.0}, FIBER, FLOW)[1].dx == 5.0


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("friction=0..1", "friction is a library effect of the discrepancy workflow"),
        ("fiber.effects.pillar_hydro=0.5", "consider it with --effect pillar_hydro"),
        ("flow.dx=2..5", "flow setting: each value is its own flow field"),
        ("fiber.contact.chi=1.2..1.5", "must hold the config's fiber.contact.chi = 1.1"),
        ("fiber.contact.pillar=rough", "is the config's own fiber.contact.pillar"),
        ("fiber.youngs_modulus=1..3", "did you mean 'young_modulus'"),
        ("fiber.contact.chi=0.5", "fiber.contact.chi: Input should be greater than 1"),
        ("flow.dx=3", "not a whole number of dx"),
        ("run.workers=3", "do not change a run's result"),
        ("fiber.contact.chi=3..1", "finite LO < HI"),
        ("fiber.contact.pillar=a..b", "two numbers"),
        ("fiber.young_modulus=0..1e5", "needs a positive range"),
        ("fiber.young_modulus=-1e4..1e5", "needs a positive range"),
        ("fiber.model=bead-spring", None),  # an alternative model: allowed
    ],
)
def test_bad_candidates_are_refused_naming_the_option(text, message):
    if message is None:
        assert parse_candidate(text, FIBER, FLOW).categorical
        return
    with pytest.raises(InputError, match="--candidate") as exc:
        parse_candidate(text, FIBER, FLOW)
    assert message in str(exc.value)


def test_a_declared_library_name_is_refused_by_the_settings():
    from fibersweep.discrepancy.settings import DiscrepancySettings

    with pytest.raises(InputError, match="library effect"):
        DiscrepancySettings(declared=(LIBRARY["friction"],))


def test_a_candidate_value_runs_as_the_config_with_that_override(uniform_field):
    """A batch at a declared value equals a batch of a simulator whose config carries the
    override (same starts and seeds), for a setting that changes the outcome; the pool
    is not restarted for it (one executor, the setting travels with the batch)."""
    c = parse_candidate("fiber.contact.chi=2.5", FIBER, FLOW)
    starts = np.array([[0.0, -0.3, 1.0], [5.0, 0.2, 0.8], [-4.0, -0.1, 1.2]])
    seeds = np.arange(3)
    with Simulator(uniform_field, FIBER, workers=1, progress=False, candidates=[c],
                   flow=FLOW) as sim:  # fmt: skip
        got = sim.run(starts, {c.name: 1.0}, seeds)
        base = sim.run(starts, {}, seeds)
        assert sim.variant({c.name: 1.0})[1].contact.chi == 2.5
        assert sim.variant({c.name: 0.0})[0] is None  # 0: the config's own setting
    changed = FIBER.model_copy(update={"contact": FIBER.contact.model_copy(update={"chi": 2.5})})
    with Simulator(uniform_field, changed, workers=1, progress=False) as sim:
        want = sim.run(starts, {}, seeds)
    assert got.equals(want)
    assert not got["delta"].equals(base["delta"])  # the candidate changes the outcome


def test_a_categorical_fit_evaluates_the_alternative_once(uniform_field):
    from fibersweep.discrepancy.copies import CopyMaker, NoiseModel
    from fibersweep.discrepancy.fit import fit_effect

    c = parse_candidate("fiber.contact.chi=2.5", FIBER, FLOW)
    rng = np.random.default_rng(4)
    starts = np.column_stack(
        [rng.uniform(-8, 8, 8), rng.uniform(-0.4, 0.4, 8), rng.uniform(0.8, 1.2, 8)]
    )
    with Simulator(uniform_field, FIBER, workers=1, progress=False, candidates=[c],
                   flow=FLOW) as sim:  # fmt: skip
        maker = CopyMaker(starts, NoiseModel(), 5, sim)
        observed = maker.copy(9, {c.name: 1.0})  # "measured" with the alternative on
        base = maker.copies(range(2), None)
        used = sim.used
        fit = fit_effect(c, maker, observed, base, np.arange(8), ("delta",), {"delta": 1.0}, 5)
        assert sim.used - used == 2 * 8  # one evaluation (value 1) of 2 copies, no scan
    assert [v for v, _ in fit.evaluations] == [0.0, 1.0]
    assert fit.value in (0.0, 1.0)
    assert fit.value == (1.0 if fit.evaluations[1][1] < fit.evaluations[0][1] else 0.0)


def test_a_tiny_workflow_with_a_declared_candidate_writes_its_report(uniform_field, tmp_path):
    """The whole workflow with a declared candidate besides a library effect (12 fibers,
    uniform flow): it runs, and the report lists the candidate with its range in its unit."""
    from fibersweep.discrepancy.measured import load_measured
    from fibersweep.discrepancy.report import write_report
    from fibersweep.discrepancy.schema import write_table
    from fibersweep.discrepancy.synth import synthesize
    from fibersweep.discrepancy.workflow import DiscrepancySettings, run_discrepancy

    c = parse_candidate("fiber.contact.chi=1.05..3", FIBER, FLOW)
    box = {"theta0": (-8.0, 8.0), "y0": (-0.4, 0.4), "length": (0.8, 1.2)}
    table, _ = synthesize(uniform_field, FIBER, box, 12, seed=3, workers=1, progress=False)
    write_table(table, tmp_path / "m.parquet")
    data = load_measured(tmp_path / "m.parquet")
    s = DiscrepancySettings(
        copies=2, fit_evals=1, candidates=1, tied=0, refits=1, pairs=0, power_fibers=0,
        next_copies=0, n_perm=99, workers=1, effects=("friction",), declared=(c,),
    )  # fmt: skip
    res = run_discrepancy(data, uniform_field, FIBER, s, progress=False, flow=FLOW)
    summ = write_report(res, tmp_path / "r", {"fiber": FIBER.model_dump(mode="json")})
    assert summ["declared"][0]["name"] == "fiber.contact.chi"
    assert summ["declared"][0]["range"] == pytest.approx([1.05, 3.0])
    saved = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert saved["declared"][0]["scale"] == "linear"
    assert res.verdict.kind == "no significant gap"  # data from the model itself
