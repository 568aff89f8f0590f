"""Declared candidates in the words of the report: the verdict, the follow-ups' reason
and labels, the figures' label, the advice and the power table quote a declared
candidate's value in its setting's unit, and an unexplained verdict says the declared
candidates were tried (no simulations)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.config.flow import FlowSettings
from fibersweep.discrepancy.advice import advice_lines
from fibersweep.discrepancy.candidates import show_values
from fibersweep.discrepancy.decide import Verdict, decide, evaluate_heldout
from fibersweep.discrepancy.declared import parse_candidate
from fibersweep.discrepancy.detection import EffectPower, limit_in_unit
from fibersweep.discrepancy.followup import next_hypotheses
from fibersweep.discrepancy.gap import assess_gap
from fibersweep.discrepancy.report_figures import fitted_label

STIFF = parse_candidate("fiber.young_modulus=1e4..3e7", FiberSettings(), FlowSettings(dx=4.0))


def _show(vals):
    return show_values(dict(vals), {STIFF.name: STIFF})


def _gap(shift: float, seed: int):
    """A real GapResult on 60 fibers x 5 members, observation shifted by ``shift`` sd."""
    rng = np.random.default_rng(seed)
    V = rng.standard_normal((60, 5))
    V[:, 0] += shift
    return assess_gap({"delta": V}, rng, n_perm=999, n_boot=200)


def _unhelpful(name: str, value: float):
    """A held-out candidate whose improvement is noise around 0 (not significant)."""
    rng = np.random.default_rng(4)
    n = 60
    base = {"delta": np.full(n, 1.0)}
    eff = {name: {"delta": 1.0 - rng.normal(0.0, 1.0, n)}}
    return evaluate_heldout({name: value}, base, eff, {name: _gap(2.0, 5)}, rng, alpha=0.05)


def test_an_unexplained_verdict_names_the_declared_candidates_it_tried():
    rng = np.random.default_rng(1)
    gap = _gap(2.0, 3)
    assert gap.any  # a 2-sd shift on 60 fibers is a gap
    ho = _unhelpful(STIFF.name, 1.8)
    assert not ho[0].significant
    plain = decide(gap, ho, "R", rng, 0.05)
    assert plain.kind == "unexplained" and "no effect of the library improves" in plain.text
    v = decide(gap, ho, "R", rng, 0.05, show=_show, declared=[STIFF.name])
    assert v.kind == "unexplained"
    assert "nor the declared candidate fiber.young_modulus improves" in v.text


def test_the_next_measurement_reason_quotes_a_stiffness_in_pa():
    ho = _unhelpful(STIFF.name, 1.8)
    verdict = Verdict("unexplained", {}, "contact", "R", "t")
    a, b, why = next_hypotheses(verdict, ho, {STIFF.name: [1.7, 1.9]}, _show)
    assert a == {} and b == {STIFF.name: 1.8}
    # E = 3e7 / (10**1.8 - 1) = 4.83e5 Pa, as the report would write it
    assert f"fiber.young_modulus = {STIFF.setting(1.8):.3g} Pa helped most" in why
    assert "1.8 helped" not in why
    # halves far apart: the reason quotes both halves' stiffness
    _, _, why2 = next_hypotheses(verdict, ho, {STIFF.name: [0.5, 2.2]}, _show)
    assert f"{STIFF.setting(0.5):.3g} Pa and " in why2 and f"{STIFF.setting(2.2):.3g} Pa" in why2


def test_the_figure_label_quotes_a_stiffness_in_pa():
    ho = _unhelpful(STIFF.name, 1.8)
    res = SimpleNamespace(
        verdict=Verdict("unexplained", {}, "contact", "R", "t"),
        settings=SimpleNamespace(declared=(STIFF,)),
        heldout=ho,
        sets=[],
    )
    key, label, _ = fitted_label(res)
    assert key == STIFF.name
    assert label == f"fiber.young_modulus = {STIFF.setting(1.8):.3g} Pa (best candidate, not named)"
    named = SimpleNamespace(
        verdict=Verdict("named", {STIFF.name: 1.8}, "contact", "R", "t", ({STIFF.name: 1.8},)),
        settings=SimpleNamespace(declared=(STIFF,)),
        heldout=ho,
        sets=[],
    )
    assert fitted_label(named)[1].startswith(f"fiber.young_modulus = {STIFF.setting(1.8):.3g} Pa")


def test_a_stiffness_limit_and_what_may_hide_are_in_pa():
    e = EffectPower(STIFF.name, STIFF.probes[0], (), 1.0, limit=0.935, limit_ci=(0.70, 1.36))
    out = limit_in_unit(STIFF, e)
    # a larger value is a softer fiber: the limit is the stiffest fiber detected, and its
    # interval's ends swap; what may hide is flexibility stiffer than the far end
    assert out["limit_setting"] == pytest.approx(STIFF.setting(0.935))
    lo, hi = out["limit_ci_setting"]
    assert lo == pytest.approx(STIFF.setting(1.36)) and hi == pytest.approx(STIFF.setting(0.70))
    assert out["setting"].startswith(
        f"flexibility detected for fiber.young_modulus <= {STIFF.setting(0.935):.3g} Pa"
    )
    assert out["unseen"] == f"flexibility of fiber.young_modulus >= {STIFF.setting(1.36):.3g} Pa"
    # power.json carries the probe in Pa too, not only the fit's log-scale value
    assert out["probe_setting"] == pytest.approx(STIFF.setting(STIFF.probes[0]))
    assert limit_in_unit(parse_candidate("fiber.contact.chi=1.05..3", FiberSettings(),
                                         FlowSettings(dx=4.0)), e)["unseen"].startswith(
        "fiber.contact.chi up to")  # fmt: skip


def test_advice_quotes_declared_values_in_their_unit_and_names_the_declared():
    v18 = STIFF.setting(1.8)
    s = {
        "verdict": {"kind": "unexplained"},
        "n_fibers": 100,
        "region": {"where": "y0 < 0.5", "n": 10, "share": 0.5},
        "declared": [{"name": STIFF.name}],
        "heldout": [
            {"effect": STIFF.name, "value": 1.8, "setting": STIFF.show(1.8),
             "significant": False},
        ],  # fmt: skip
        "sets": [],
        "next": None,
        "power": {
            "effects": [
                {"effect": "friction", "direction": "+", "limit": 0.15,
                 "limit_ci": [0.1, 0.28], "realistic": 0.5},
                {"effect": STIFF.name, "direction": "+", "limit": 0.935,
                 "limit_ci": [0.7, 1.36], "realistic": None,
                 "unseen": "flexibility of fiber.young_modulus >= 1.37e+06 Pa"},
            ],  # fmt: skip
            "leading": {"effect": STIFF.name, "value": 1.8, "setting": STIFF.show(1.8),
                        "fibers_to_detect": 27, "fibers_to_name": 606},  # fmt: skip
        },
    }
    text = "\n".join(advice_lines(s))
    assert "No library effect nor declared candidate (fiber.young_modulus) improved" in text
    assert "outside the library and the declared candidates" in text
    assert f"for fiber.young_modulus = {v18:.3g} Pa: about 27 fibers" in text
    assert "friction (+) up to 0.28" in text
    assert "flexibility of fiber.young_modulus >= 1.37e+06 Pa" in text
    assert "up to 1.36" not in text and "= 1.8:" not in text
    # without declared candidates the advice reads as before
    s2 = {**s, "declared": [], "heldout": [], "power": None}
    text2 = "\n".join(advice_lines(s2))
    assert "No library effect improved the held-out fibers significantly." in text2
