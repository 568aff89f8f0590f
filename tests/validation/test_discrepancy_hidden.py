"""The discrepancy workflow on data with a hidden effect (synth -> discrepancy), coarse grid.

The fast tests (CI) use 24 fibers and a reduced plan; the slow ones use the
default plan (8 copies) on 60 fibers (100 for friction, see ``FIBERS``) and every
library effect at a realistic magnitude.
The label is never given to the workflow: it only sees the synthesised table.
"""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.config import Config, load_config
from fibersweep.config.fiber import ContactSettings, FiberSettings
from fibersweep.discrepancy.candidates import LIBRARY
from fibersweep.discrepancy.report import write_report
from fibersweep.discrepancy.schema import validate_measured
from fibersweep.discrepancy.synth import STUDY_BOX as BOX
from fibersweep.discrepancy.synth import synthesize
from fibersweep.discrepancy.workflow import DiscrepancySettings, run_discrepancy

FAST = dict(
    copies=3, fit_copies=2, candidates=2, fit_evals=4, refits=1, n_perm=1999,
    power_fibers=0, next_copies=0,
)  # fmt: skip


def _run(field, hidden, n, seed, fiber_truth=None, workers=2, theta_bias=0.0, **kw):
    truth_fiber = fiber_truth or FiberSettings()
    table, _ = synthesize(
        field, truth_fiber, BOX, n, hidden, seed=seed, workers=workers, progress=False
    )
    table["theta0"] -= theta_bias  # a systematic error of the reported angle (not in the library)
    data = validate_measured(table)
    settings = DiscrepancySettings(seed=seed, workers=workers, **kw)
    return run_discrepancy(data, field, FiberSettings(), settings, progress=False)


def test_no_effect_gives_no_significant_gap(coarse_field):
    res = _run(coarse_field, {}, 24, seed=11, workers=1, **FAST)  # in-process: no pool start
    assert res.verdict.kind == "no significant gap", res.verdict.text
    assert res.verdict.effects == {}
    # nothing beyond the noise floor: only the baseline copies were simulated
    assert res.simulations == 24 * 3


def test_hidden_inlet_speed_is_named_recovered_and_closes_the_gap(coarse_field, tmp_path):
    # 8 % faster flow: t_pass shorter by 7 %, against 1 % timing noise.
    res = _run(
        coarse_field,
        {"inlet_speed": 0.08},
        20,
        seed=12,
        effects=("inlet_speed", "friction", "pillar_scale"),
        **FAST,
    )
    assert res.verdict.kind == "named", res.verdict.text
    assert list(res.verdict.effects) == ["inlet_speed"]
    # fit on 10 fibers x 2 copies, 4 Brent steps: within 0.02 of the truth (25 %)
    assert res.verdict.effects["inlet_speed"] == pytest.approx(0.08, abs=0.02)
    h = next(h for h in res.heldout if h.name == "inlet_speed")
    before = res.gap.gaps["t_pass"].excess[0]
    after = h.residual.gaps["t_pass"].excess[0]
    assert before > 0 and after <= 0.5 * before
    assert res.simulations <= res.plan.total(20)
    # the report: JSON for scripts, the updated config loads and carries the effect
    s = write_report(res, tmp_path, Config().model_dump(mode="json"))
    assert s["verdict"]["kind"] == "named" and s["simulations"] == res.simulations
    cfg = load_config(tmp_path / "updated_config.yaml")
    assert cfg.fiber.effects == pytest.approx({"inlet_speed": res.verdict.effects["inlet_speed"]})
    for fig in ("phase_before_after.png", "residual_map.png", "gap_before_after.png"):
        assert (tmp_path / fig).stat().st_size > 0


# ----------------------------------------------------------------------------- slow


#: Effects recovered at their realistic magnitude (LIBRARY[name].realistic, the one
#: source of these magnitudes; brownian and off_midplane have tests of their own below).
NAMED = ("friction", "inlet_speed", "start_noise", "pillar_scale", "pillar_hydro")
# Stated recovery tolerances (relative to the truth), from the fit resolution of
# 30 fibers x 2 copies per fold: speed scales are read off every fiber's time,
# contact effects only off the ~40 % of fibers that touch the pillar.
TOLERANCE = {
    "friction": 0.5,
    "inlet_speed": 0.3,
    "start_noise": 0.5,
    "pillar_scale": 0.5,
    "pillar_hydro": 0.5,
}


def _gap_shrink(res, name: str) -> tuple[float, float]:
    """Out-of-sample (cross-fitted) gap before / after, over the flagged observables.

    The sum of each observable's mean excess score in units of the copies' score
    spread (the README's "gap after/before"): 0 on average for a model as good as its
    own copies, positive for a gap of either kind (a shift raises the score too).
    """
    h = next(h for h in res.heldout if h.name == name)
    w = res.weights
    flagged = res.gap.flagged
    before = sum(w[o] * res.gap.gaps[o].excess[0] for o in flagged)
    after = sum(w[o] * h.residual.gaps[o].excess[0] for o in flagged)
    return before, after


#: Fibers per case: 60, or more where the realistic magnitude sits too close to the
#: naming power at 60. Friction 0.5 at N = 60 is 2.2 times its detection limit (the
#: median N = 100 limit 0.18, times sqrt(100 / 60)) and was detected but not named
#: (seed 21: halves 0.595 and 0.259; the report's own power reading: about 362 fibers
#: to name 0.43). At N = 100 it is 2.8 times the limit, where the validation report's
#: study named 15 of 15 single effects above twice theirs (docs/validation/discrepancy.md).
FIBERS = {"friction": 100}


@pytest.mark.slow
@pytest.mark.parametrize("name", NAMED)
def test_library_effect_is_named_and_recovered(coarse_field, name):
    value = LIBRARY[name].realistic
    res = _run(coarse_field, {name: value}, FIBERS.get(name, 60), seed=21)
    assert res.verdict.kind == "named", res.verdict.text
    assert list(res.verdict.effects) == [name]
    assert res.verdict.effects[name] == pytest.approx(value, rel=TOLERANCE[name])
    # the out-of-sample gap over the observables that had one shrinks by at least half
    before, after = _gap_shrink(res, name)
    # pillar_scale at seed 21 once shrank only to 0.60 of its gap (one fold
    # under-corrected its half); on 479c9f0 it halves: 0.349 before, -0.044 after
    assert after <= 0.5 * before, (before, after)


@pytest.mark.slow
def test_brownian_motion_at_room_temperature_is_below_the_noise_floor(coarse_field):
    # Brownian motion at 295 K in the glycerol-ethanol mix moves a fiber by < 0.1 µm and
    # < 0.5° over a pass: the honest answer is "no significant gap"; any name must be
    # the true one.
    v = _run(coarse_field, {"brownian": 1.0}, 60, seed=61).verdict
    assert v.kind in ("no significant gap", "named"), v.text
    if v.kind == "named":
        assert list(v.effects) == ["brownian"]


@pytest.mark.slow
def test_false_alarm_rate_over_seeds(coarse_field):
    # alpha = 0.05 family-wise over 20 no-effect data sets (new seeds, forward selection
    # on): at most 3 alarms (P(>= 4 of 20) = 1.6 % if calibrated), and never a name.
    kinds = [_run(coarse_field, {}, 40, seed=s, **FAST).verdict for s in range(300, 320)]
    assert sum(v.kind != "no significant gap" for v in kinds) <= 3, [v.text for v in kinds]
    assert all(v.effects == {} for v in kinds), [v.text for v in kinds]


@pytest.mark.slow
@pytest.mark.parametrize("change", ["chi", "theta_bias"])
def test_effect_outside_the_library_is_not_named(coarse_field, change):
    # a larger contact cutoff (chi 1.5 instead of 1.1), or reported angles 3 deg too
    # small, are no library effect: never a name. (Seed 41 with the angle bias once named
    # start_noise = 1.6: extra zero-mean start noise widens the copies around a shifted
    # theta_c; the signed-residual test in the adequacy check now catches the shift left.)
    if change == "chi":
        fiber = FiberSettings(contact=ContactSettings(chi=1.5))
        res = _run(coarse_field, {}, 60, seed=41, fiber_truth=fiber)
    else:
        res = _run(coarse_field, {}, 60, seed=41, theta_bias=3.0)
    assert res.verdict.kind in ("unexplained", "no significant gap"), res.verdict.text


@pytest.mark.slow
def test_look_alike_effects_are_never_one_wrong_name(coarse_field):
    # off_midplane and inlet_speed < 0 both slow the fiber uniformly
    res = _run(coarse_field, {"off_midplane": 0.15}, 60, seed=51)
    v = res.verdict
    # look-alikes: "ambiguous" (or the true name), never another name alone
    assert v.kind in ("named", "ambiguous"), v.text
    if v.kind == "named":
        assert list(v.effects) == ["off_midplane"]
    else:
        assert "off_midplane" in v.effects
    assert np.isfinite(list(v.effects.values())).all()


@pytest.mark.slow
def test_two_hidden_effects_are_never_a_wrong_name(coarse_field, tmp_path):
    # friction (the class gap) and a faster inlet (the t_pass gap) together: the
    # verdict names the pair, or one of its members (incomplete), never another effect;
    # a named pair goes into the updated config whole
    res = _run(coarse_field, {"friction": 0.5, "inlet_speed": 0.05}, 60, seed=71)
    v = res.verdict
    assert set(v.effects) <= {"friction", "inlet_speed"}, v.text
    if v.kind == "named" and len(v.effects) == 2:
        write_report(res, tmp_path, Config().model_dump(mode="json"))
        cfg = load_config(tmp_path / "updated_config.yaml")
        assert set(cfg.fiber.effects) == {"friction", "inlet_speed"}


@pytest.mark.slow
def test_realistic_hidden_pair_is_named_as_a_pair(coarse_field, tmp_path):
    # the realistic pair (friction 0.5 + inlet_speed 0.05) on 40 fibers, both
    # effects and a third (pillar_scale) in the library, a reduced plan (4 copies).
    # The faster inlet's t_pass gap hides friction's class gap at baseline (Holm); the
    # forward step scores what inlet_speed leaves and fits the pair jointly, so the pair
    # is named. Tolerances: friction within 0.25 and inlet_speed within 0.02 of the truth
    # (a fit on 20 fibers x 2 copies with 4 Brent steps), and both go into the config.
    res = _run(
        coarse_field,
        {"friction": 0.5, "inlet_speed": 0.05},
        40,
        seed=1,
        effects=("friction", "inlet_speed", "pillar_scale"),
        copies=4, fit_evals=4, refits=1, power_fibers=0, next_copies=0,
    )  # fmt: skip
    v = res.verdict
    assert v.kind == "named" and set(v.effects) == {"friction", "inlet_speed"}, v.text
    assert v.effects["friction"] == pytest.approx(0.5, abs=0.25)
    assert v.effects["inlet_speed"] == pytest.approx(0.05, abs=0.02)
    write_report(res, tmp_path, Config().model_dump(mode="json"))
    cfg = load_config(tmp_path / "updated_config.yaml")
    assert cfg.fiber.effects == pytest.approx(v.effects)
