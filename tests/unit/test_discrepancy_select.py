"""Forward selection's decision: a pair is named only when both members contribute and it fits."""

from __future__ import annotations

import numpy as np

from fibersweep.discrepancy.decide import SetHeldOut, decide, evaluate_heldout
from fibersweep.discrepancy.gap import assess_gap
from fibersweep.discrepancy.select import boot_p


def _gap(shift: float, seed: int):
    """A real GapResult on 60 fibers x 5 members, observation shifted by ``shift`` sd."""
    rng = np.random.default_rng(seed)
    V = rng.standard_normal((60, 5))
    V[:, 0] += shift
    return assess_gap({"delta": V}, rng, n_perm=999, n_boot=200)


def _single(rng, improvement: float, residual_shift: float):
    """Both single effects improve significantly but each leaves a gap."""
    n = 60
    return evaluate_heldout(
        {"friction": 0.5, "inlet_speed": 0.05},
        {"delta": np.full(n, 1.0)},
        {
            "friction": {"delta": 1.0 - rng.normal(improvement, 0.3, n)},
            "inlet_speed": {"delta": 1.0 - rng.normal(improvement, 0.3, n)},
        },
        {"friction": _gap(residual_shift, 1), "inlet_speed": _gap(residual_shift, 2)},
        rng,
        alpha=0.05,
    )


def _set(names, p_holm, residual_shift, seed, gain=0.5):
    return SetHeldOut(
        values={n: 0.1 for n in names},
        fold_values={n: (0.1, 0.1) for n in names},
        gains={n: (gain, gain / 2, 1.5 * gain) for n in names},
        p_values=dict(zip(names, p_holm, strict=True)),
        p_holm=dict(zip(names, p_holm, strict=True)),
        improvement=(1.0, 0.8, 1.2),
        residual=_gap(residual_shift, seed),
    )


def test_pair_is_named_when_both_members_contribute_and_no_gap_is_left():
    rng = np.random.default_rng(0)
    ho = _single(rng, 0.6, 1.5)
    assert all(h.significant and not h.explains for h in ho)
    pair = _set(("friction", "inlet_speed"), (0.001, 0.002), 0.0, 3)
    v = decide(_gap(2.0, 4), ho, "y0 < 0.4", rng, 0.05, [pair])
    assert v.kind == "named" and set(v.effects) == {"friction", "inlet_speed"}
    assert v.alternatives == ({"friction": 0.1, "inlet_speed": 0.1},)
    assert "together explain" in v.text


def test_pair_with_one_insignificant_member_is_not_named():
    rng = np.random.default_rng(1)
    ho = _single(rng, 0.6, 1.5)
    pair = _set(("friction", "inlet_speed"), (0.001, 0.3), 0.0, 5)
    v = decide(_gap(2.0, 6), ho, "R", rng, 0.05, [pair])
    assert v.kind == "unexplained" and v.effects == {}


def test_pair_that_leaves_a_gap_is_not_named():
    rng = np.random.default_rng(2)
    ho = _single(rng, 0.6, 1.5)
    pair = _set(("friction", "inlet_speed"), (0.001, 0.001), 1.5, 7)
    v = decide(_gap(2.0, 8), ho, "R", rng, 0.05, [pair])
    assert v.kind == "unexplained"


def test_two_adequate_pairs_are_ambiguous_between_sets():
    rng = np.random.default_rng(3)
    ho = _single(rng, 0.6, 1.5)
    a = _set(("friction", "inlet_speed"), (0.001, 0.001), 0.0, 9)
    b = _set(("friction", "off_midplane"), (0.001, 0.001), 0.0, 14)
    assert a.explains(0.05) and b.explains(0.05)
    v = decide(_gap(2.0, 11), ho, "R", rng, 0.05, [a, b])
    assert v.kind == "ambiguous" and len(v.alternatives) == 2
    assert set(v.effects) == {"friction", "inlet_speed", "off_midplane"}


def test_a_single_effect_that_explains_wins_over_a_pair():
    rng = np.random.default_rng(4)
    ho = _single(rng, 0.6, 0.0)  # both explain -> the single-effect rule applies
    pair = _set(("friction", "inlet_speed"), (0.001, 0.001), 0.0, 12)
    v = decide(_gap(2.0, 13), ho, "R", rng, 0.05, [pair])
    assert len(v.alternatives) == 2 and all(len(a) == 1 for a in v.alternatives)


def test_bootstrap_p_is_calibrated_under_no_improvement():
    # zero-mean per-fiber gains: P(p <= 0.05) ~ 0.05; stated band [0.01, 0.10] over 400 draws
    rng = np.random.default_rng(5)
    ps = np.array([boot_p(rng.standard_normal(60), rng, n_boot=500) for _ in range(400)])
    assert 0.01 <= np.mean(ps <= 0.05) <= 0.10
    assert boot_p(rng.normal(1.0, 0.3, 60), rng) < 0.01


def test_pair_can_be_named_when_neither_effect_is_significant_alone():
    # each effect alone improves too little to pass Holm; together each member's own
    # contribution is significant and nothing is left: the set is named
    rng = np.random.default_rng(6)
    ho = _single(rng, 0.02, 1.5)
    assert not any(h.significant for h in ho)
    pair = _set(("friction", "inlet_speed"), (0.001, 0.002), 0.0, 15)
    v = decide(_gap(2.0, 16), ho, "R", rng, 0.05, [pair])
    assert v.kind == "named" and set(v.effects) == {"friction", "inlet_speed"}


def test_what_to_separate_next():
    from fibersweep.discrepancy.decide import Verdict
    from fibersweep.discrepancy.followup import next_hypotheses

    amb = Verdict("ambiguous", {"a": 1.0, "b": 2.0}, alternatives=({"a": 1.0}, {"b": 2.0}))
    assert next_hypotheses(amb, [], {})[:2] == ({"a": 1.0}, {"b": 2.0})
    rng = np.random.default_rng(7)
    ho = _single(rng, 0.6, 1.5)  # both significant, neither explains
    un = Verdict("unexplained", {})
    a, b, why = next_hypotheses(un, ho, {})
    assert {next(iter(a)), next(iter(b))} == {"friction", "inlet_speed"} and "two" in why
    # a named effect whose halves disagree by a factor 5 (the 0.53 vs 0.09)
    named = Verdict("named", {"friction": 0.3}, alternatives=({"friction": 0.3},))
    a, b, why = next_hypotheses(named, ho, {"friction": [0.53, 0.09]})
    assert a == {"friction": 0.53} and b == {"friction": 0.09}
    assert next_hypotheses(named, ho, {"friction": [0.5, 0.4]}) is None
