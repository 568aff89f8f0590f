"""Declared candidates on data generated outside the library (synth with a changed
setting -> discrepancy with the setting declared), SPEC geometry at dx = 4 µm.

All slow (N = 100, the default plan). Seeds are fixed per case; the tolerances are
those of the workflow itself: a named candidate's 95 % interval must hold the truth,
no other candidate may be named, and without the candidate declared the verdict
names nothing (the library does not hold the truth). False alarms: 20 data sets
without any effect, N = 60, candidates declared; at most 3 named (P(X >= 4) = 1.6 %
for a binomial(20, 0.05): an alarm rate at alpha fails this test in 1.6 % of runs).

Each test makes its own data and runs on its own; select one with -k: E3e5, E1e5,
without_the_candidate, smooth_pillar, coarser_flow_grid, finer_flow_grid, false_alarms.
"""

from __future__ import annotations

import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.config.flow import FlowSettings
from fibersweep.discrepancy.declared import parse_candidate
from fibersweep.discrepancy.schema import validate_measured
from fibersweep.discrepancy.synth import STUDY_BOX as BOX
from fibersweep.discrepancy.synth import synthesize
from fibersweep.discrepancy.workflow import DiscrepancySettings, run_discrepancy

FIBER = FiberSettings()
STIFFNESS = "fiber.young_modulus=1e4..3e7"


def _analyse(field, flow, truth_fiber, n, seed, declared, cache=None, truth_field=None):
    table, _ = synthesize(truth_field or field, truth_fiber, BOX, n, seed=seed, workers=2,
                          progress=False)  # fmt: skip
    cands = tuple(parse_candidate(t, FIBER, flow) for t in declared)
    s = DiscrepancySettings(seed=seed, workers=2, declared=cands, power_fibers=0, next_copies=0)
    res = run_discrepancy(validate_measured(table), field, FIBER, s, progress=False,
                          flow=flow, cache_dir=cache)  # fmt: skip
    return res, {c.name: c for c in cands}


@pytest.mark.slow
@pytest.mark.parametrize(("E", "seed"), [(3e5, 9501), (1e5, 9502)], ids=["E3e5", "E1e5"])
def test_flexible_fibers_are_named_with_an_interval_holding_their_stiffness(
    coarse_field, coarse_settings, E, seed
):
    """E = 3e5 Pa (the issue's data) and 1e5 Pa: named, interval in Pa holds E."""
    truth = FiberSettings(model="bead-spring", integrator="ros2", young_modulus=E)
    res, cands = _analyse(coarse_field, coarse_settings, truth, 100, seed, [STIFFNESS])
    assert res.verdict.kind == "named", res.verdict.text
    assert list(res.verdict.effects) == ["fiber.young_modulus"], res.verdict.text
    lo, hi = res.extra["intervals"]["fiber.young_modulus"][:2]
    e_lo, e_hi = cands["fiber.young_modulus"].interval(lo, hi)
    assert e_lo <= E <= e_hi, (e_lo, e_hi)


@pytest.mark.slow
def test_without_the_candidate_flexible_data_name_no_library_effect(coarse_field, coarse_settings):
    truth = FiberSettings(model="bead-spring", integrator="ros2", young_modulus=3e5)
    res, _ = _analyse(coarse_field, coarse_settings, truth, 100, 9501, [])
    # a library effect named (alone or as an alternative) would be a wrong name
    assert res.verdict.kind not in ("named", "ambiguous"), res.verdict.text


@pytest.mark.slow
def test_a_smooth_pillar_is_named(coarse_field, coarse_settings):
    truth = FiberSettings(contact={"pillar": "smooth"})
    declared = ["fiber.contact.pillar=smooth"]
    res, _ = _analyse(coarse_field, coarse_settings, truth, 200, 9511, declared)
    assert res.verdict.kind == "named", res.verdict.text
    assert list(res.verdict.effects) == ["fiber.contact.pillar=smooth"]


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="a dx = 5 µm field is 1.3 % slower on average than the dx = 4 µm model's; at "
    "N = 100 and 200 the grid and a slower flow (inlet_speed, off_midplane) explain the "
    "data equally: ambiguous, not named (docs/validation/discrepancy.md)",
)
def test_a_coarser_flow_grid_is_named(coarse_field, coarse_settings, flow_cache_dir):
    from fibersweep.flow.cache import get_flow_field

    coarse5, _ = get_flow_field(FlowSettings(dx=5.0), flow_cache_dir)
    res, _ = _analyse(coarse_field, coarse_settings, FIBER, 100, 9521, ["flow.dx=5"],
                      cache=flow_cache_dir, truth_field=coarse5)  # fmt: skip
    assert res.verdict.kind == "named", res.verdict.text
    assert list(res.verdict.effects) == ["flow.dx=5"]


@pytest.mark.slow
def test_a_finer_flow_grid_is_named_after_the_follow_up_fibers(
    coarse_field, coarse_settings, flow_cache_dir
):
    """dx = 2 µm truth, dx = 4 µm model, ``flow.dx=2`` declared, seed 9522, N = 100.

    The first fibers leave the grid and a 1.7 % faster inlet equally good (the grid's
    field is 1.7 % faster on average, scripts/studies/discrepancy/grid_fields.py);
    what-to-measure-next proposes starts and a count. Twice that count (power about
    0.97 by its own estimate), kept by their measured start near the proposed starts,
    must reject the inlet and leave the grid named. A wrong pick has probability at
    most alpha = 0.05 (the follow-up test's size, tests/unit/test_discrepancy_settle.py).
    Measured (docs/validation/discrepancy.md): 191 asked for, 382 measured, the inlet
    rejected at p 5e-05, the grid at p 0.85; about 30 minutes on two cores.
    """
    import numpy as np

    from fibersweep.discrepancy.synth import synthesize_near
    from fibersweep.discrepancy.workflow import settle_result
    from fibersweep.flow.cache import get_flow_field

    fine, _ = get_flow_field(FlowSettings(dx=2.0), flow_cache_dir)
    table, _ = synthesize(fine, FIBER, BOX, 100, seed=9522, workers=2, progress=False)
    cands = (parse_candidate("flow.dx=2", FIBER, coarse_settings),)
    s = DiscrepancySettings(seed=9522, workers=2, declared=cands, power_fibers=0)
    res = run_discrepancy(validate_measured(table), coarse_field, FIBER, s, progress=False,
                          flow=coarse_settings, cache_dir=flow_cache_dir)  # fmt: skip
    assert res.verdict.kind in ("named", "ambiguous"), res.verdict.text
    assert {"flow.dx=2": 1.0} in [dict(a) for a in res.verdict.alternatives], res.verdict.text
    if res.verdict.kind == "ambiguous":
        nxt = res.extra["next"]
        need = nxt.fibers_to_settle
        assert need is not None and need <= 300, need
        centres = np.array([[b.theta0, b.y0, b.length] for b in nxt.best[:5]])
        more = synthesize_near(fine, FIBER, centres, 2 * nxt.fibers_to_settle, seed=10522,
                               workers=2)  # fmt: skip
        res = settle_result(res, validate_measured(more), coarse_field, FIBER, progress=False,
                            flow=coarse_settings, cache_dir=flow_cache_dir)  # fmt: skip
    assert res.verdict.kind == "named", res.verdict.text
    assert list(res.verdict.effects) == ["flow.dx=2"], res.verdict.text


@pytest.mark.slow
def test_false_alarms_stay_at_alpha_with_candidates_declared(coarse_field, coarse_settings):
    named = 0
    for k in range(20):
        res, _ = _analyse(coarse_field, coarse_settings, FIBER, 60, 9600 + k,
                          [STIFFNESS, "fiber.contact.pillar=smooth"])  # fmt: skip
        named += res.verdict.kind in ("named", "ambiguous")
    assert named <= 3, named
