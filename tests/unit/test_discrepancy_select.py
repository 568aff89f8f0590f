"""Forward selection's decision: a pair is named only when both members contribute and it fits."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from fibersweep.discrepancy.decide import SetHeldOut, decide, evaluate_heldout
from fibersweep.discrepancy.gap import assess_gap
from fibersweep.discrepancy.scores import boot_p


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


def test_pair_weights_add_what_the_first_effect_leaves():
    # baseline: a strong t_pass shift (Holm-significant) and a class-like moderate shift in
    # "delta" that Holm over the family may leave out; after the first effect the t_pass
    # gap is gone and "delta" is still shifted: the forward step must score "delta".
    from fibersweep.discrepancy.pairs import pair_weights

    rng = np.random.default_rng(8)
    n, m = 60, 6
    t = rng.standard_normal((n, m))
    d = rng.standard_normal((n, m))
    d[:, 0] += 0.6
    base = assess_gap({"t_pass": t + np.where(np.arange(m) == 0, 3.0, 0.0), "delta": d}, rng,
                      n_perm=999, n_boot=200)  # fmt: skip
    left = assess_gap({"t_pass": t, "delta": d}, rng, n_perm=999, n_boot=200)
    assert "t_pass" in base.flagged
    w = pair_weights({"t_pass": 2.0, "delta": 3.0, "class": 1.0}, base, left, 0.05)
    assert w["t_pass"] == 2.0  # flagged at baseline: kept
    g = left.gaps["delta"]
    assert (g.test.p_value <= 0.05 or min(g.bias_p) <= 0.05) and w["delta"] == 3.0
    assert w["class"] == 0.0  # never tested: no gap, no weight


class _PairModel:
    """Closed-form stand-in with two coupled effects (as friction and inlet_speed are).

    Copy k of fiber i: δ = x_i + 0.1 f + 0.01 z and t_pass = T_i (1 + 0.04 f) / (1 + s)
    e^{0.01 z'}: friction f moves δ and slows the pass a little, a faster inlet s only
    speeds it up. The t_pass gap of the pair alone points at s = 1.05 / 1.02 - 1 = 0.029.
    """

    def __init__(self, n: int):
        rng = np.random.default_rng(1)
        self.x = rng.uniform(0.0, 0.5, n)
        self.t = rng.uniform(0.5, 2.0, n)
        self.z = rng.standard_normal((2, 4, n))

    def copies(self, ks, effects=None, rows=None, desc=""):
        return [self.copy(k, effects, rows, desc) for k in ks]

    def copy(self, k, effects=None, rows=None, desc=""):
        e = effects or {}
        f, s = float(e.get("friction", 0.0)), float(e.get("inlet_speed", 0.0))
        idx = np.arange(len(self.x)) if rows is None else rows
        return pd.DataFrame(
            {
                "delta": self.x[idx] + 0.1 * f + 0.01 * self.z[0, k, idx],
                "t_pass": self.t[idx] * (1 + 0.04 * f) / (1 + s) * np.exp(0.01 * self.z[1, k, idx]),
            }
        )


def _pair_input(model, n, rounds):
    from fibersweep.discrepancy.pairs import SelectionInput

    observed = pd.DataFrame(
        {"delta": model.x + 0.05, "t_pass": model.t * 1.02 / 1.05}
    )  # truth: friction 0.5, inlet_speed 0.05, no noise
    return SelectionInput(
        observed=observed, folds=[np.arange(n)], fold_values={}, base_values={},
        single_values={}, weights={"delta": 1.0, "t_pass": 1.0}, observables=("delta", "t_pass"),
        copies=2, fit_copies=2, fit_evals=8, alpha=0.05, n_perm=99, rounds=rounds,
    )  # fmt: skip


def test_joint_fit_refits_the_first_member():
    # the first member (inlet_speed) starts at its single-effect value 0.029, which
    # absorbed the slowing by friction. Held there (1 round), friction is fitted and
    # inlet_speed stays 40 % off; refitted (2 rounds), both come within the stated
    # tolerances of the truth (friction 0.5 +- 0.05, inlet_speed 0.05 +- 0.006:
    # 8 Brent steps on [0, 1] and [0, 0.3], 2 copies with 1 % noise, 40 fibers).
    from fibersweep.discrepancy.candidates import LIBRARY
    from fibersweep.discrepancy.pairs import joint_fit

    n = 40
    model = _PairModel(n)
    start = {"inlet_speed": 1.05 / 1.02 - 1, "friction": 0.0}
    fits = []
    frozen = joint_fit(LIBRARY["inlet_speed"], LIBRARY["friction"], start, np.arange(n),
                       _pair_input(model, n, 1), model, fits.append)  # fmt: skip
    joint = joint_fit(LIBRARY["inlet_speed"], LIBRARY["friction"], start, np.arange(n),
                      _pair_input(model, n, 2), model, fits.append)  # fmt: skip
    assert frozen["inlet_speed"] == pytest.approx(start["inlet_speed"])
    assert abs(frozen["inlet_speed"] - 0.05) > 0.015
    assert joint["friction"] == pytest.approx(0.5, abs=0.05)
    assert joint["inlet_speed"] == pytest.approx(0.05, abs=0.006)
    assert [f.name for f in fits] == ["friction", "friction", "inlet_speed"]


def test_partners_are_ranked_by_the_gap_the_first_effect_leaves():
    # the gap left has a delta shift only: the effect whose signature shifts delta ranks
    # first, the one that moves t_pass the other way has no positive match, the first
    # effect itself is never its own partner
    from fibersweep.discrepancy.gap import feature_vector
    from fibersweep.discrepancy.signatures import Signature, rank_partners

    rng = np.random.default_rng(9)
    n, m = 60, 6
    z = {"t_pass": rng.standard_normal((n, m)), "delta": rng.standard_normal((n, m))}

    def gap(dt, dd):
        V = {k: v.copy() for k, v in z.items()}
        V["t_pass"][:, 0] += dt
        V["delta"][:, 0] += dd
        return assess_gap(V, np.random.default_rng(10), n_perm=999, n_boot=200)

    left = gap(0.0, 1.5)
    sig = [
        Signature("inlet_speed", -0.15, 0.9, 1.0, ((-0.15, feature_vector(gap(-2.0, 0.0))),)),
        Signature("friction", 0.5, 0.3, 1.0, ((0.5, feature_vector(gap(0.0, 1.5))),)),
        Signature("pillar_scale", 0.1, 0.2, 1.0, ((0.1, feature_vector(gap(0.3, 0.8))),)),
    ]
    order = rank_partners("inlet_speed", sig, left, 2)
    assert order[0] == "friction" and "inlet_speed" not in order
    assert rank_partners("inlet_speed", sig, left, 1) == ["friction"]


@pytest.mark.parametrize("finish_round", [False, True])
def test_forward_step_stops_at_the_first_pair_that_explains_the_gap(finish_round):
    # truth friction 0.5 + inlet_speed 0.05 (stand-in model, 1 % copy noise, 60 fibers):
    # the best-ranked partner (friction) explains the gap, so the next one (pillar_scale)
    # is never simulated, and the pair's p-values are Holm-adjusted over the 4 members
    # the step could have tried (the untried two counted with p = 1).
    from dataclasses import replace

    from fibersweep.discrepancy.candidates import LIBRARY
    from fibersweep.discrepancy.copies import crossfit_copies
    from fibersweep.discrepancy.gap import value_matrices
    from fibersweep.discrepancy.pairs import forward_pairs
    from fibersweep.discrepancy.scores import holm

    n = 60
    model = _PairModel(n)
    asked = []
    plain_copy = model.copy

    def copy(k, effects=None, rows=None, desc=""):
        asked.append(dict(effects or {}))
        return plain_copy(k, effects, rows, desc)

    model.copy = copy
    folds = [np.arange(0, n, 2), np.arange(1, n, 2)]
    inp = replace(_pair_input(model, n, 2), folds=folds, copies=4)
    obs = inp.observed
    base = [model.copy(k) for k in range(4)]
    single = {"inlet_speed": [1.05 / 1.02 - 1] * 2}
    cps = crossfit_copies(model, folds, [{"inlet_speed": v} for v in single["inlet_speed"]],
                          4, "held-out")  # fmt: skip
    inp = replace(
        inp,
        fold_values=single,
        base_values=value_matrices(obs, base, inp.observables),
        single_values={"inlet_speed": value_matrices(obs, cps, inp.observables)},
    )
    rng = np.random.default_rng(2)
    # one first member: one pair per round
    rounds = [[(LIBRARY["inlet_speed"], LIBRARY[b], inp)] for b in ("friction", "pillar_scale")]
    sets, _ = forward_pairs(rounds, model, rng)
    if finish_round:
        # a second first member in the first round (friction, its partner inlet_speed):
        # the round is finished after its first pair explains, the next round is not begun
        asked.clear()
        inp2 = replace(inp, fold_values={**single, "friction": [0.5, 0.5]})
        rounds = [
            [(LIBRARY["inlet_speed"], LIBRARY["friction"], inp),
             (LIBRARY["friction"], LIBRARY["inlet_speed"], inp2)],
            [(LIBRARY["inlet_speed"], LIBRARY["pillar_scale"], inp)],
        ]  # fmt: skip
        both, _ = forward_pairs(rounds, model, np.random.default_rng(2))
        assert [st.name for st in both] == ["inlet_speed + friction", "friction + inlet_speed"]
        assert all(st.explains(0.05) for st in both)
        assert not any("pillar_scale" in e for e in asked)
        return
    assert [st.name for st in sets] == ["inlet_speed + friction"]
    assert sets[0].explains(0.05)
    # the explaining pair was refitted on all fibers: each member's quoted value with
    # its score-test interval, which holds it
    assert set(sets[0].intervals) == {"inlet_speed", "friction"}
    for m, (lo, hi, _, _) in sets[0].intervals.items():
        assert lo <= sets[0].values[m] <= hi
    assert not any("pillar_scale" in e for e in asked)
    p = [sets[0].p_values[m] for m in ("inlet_speed", "friction")]
    want = holm(np.array(p + [1.0, 1.0]))[:2]
    assert [sets[0].p_holm[m] for m in ("inlet_speed", "friction")] == pytest.approx(want)


def test_an_unexplained_gap_gets_starts_that_test_its_best_candidate():
    # one candidate helped (not significantly), halves 0.3 and 0.35 (not weak): the
    # hypotheses are the model as it is and that candidate at its value
    from dataclasses import replace

    from fibersweep.discrepancy.decide import Verdict
    from fibersweep.discrepancy.followup import next_hypotheses

    rng = np.random.default_rng(8)
    ho = _single(rng, 0.02, 1.5)
    best = max(ho, key=lambda h: h.improvement[0])
    ho = [replace(h, value=0.0) for h in ho]  # no refit: the fold values are used
    un = Verdict("unexplained", {})
    a, b, why = next_hypotheses(un, ho, {best.name: [0.3, 0.35]})
    assert a == {} and b == {best.name: pytest.approx(0.325)} and "unexplained" in why
    # nothing helped anywhere (every value 0): nothing to test
    assert next_hypotheses(un, ho, {best.name: [0.0, 0.0]}) is None


def test_pair_values_are_not_brents_golden_section_points():
    # With the default plan's 5 Brent steps the best evaluated inlet_speed of the joint
    # fit is 0.0438, a golden-section point of [0, 0.3] (the pair reported
    # -0.0271 for -0.04, the same kind of point). The quoted value is the score test's
    # zero between the evaluated points: measured 0.0470 for the truth 0.05; tolerance
    # 0.004 (the golden point misses it by 0.0062).
    from dataclasses import replace

    from fibersweep.discrepancy.candidates import LIBRARY
    from fibersweep.discrepancy.pairs import joint_fit

    n = 40
    model = _PairModel(n)
    start = {"inlet_speed": 1.05 / 1.02 - 1, "friction": 0.0}
    inp = replace(_pair_input(model, n, 2), fit_evals=5)
    joint = joint_fit(LIBRARY["inlet_speed"], LIBRARY["friction"], start, np.arange(n), inp,
                      model)  # fmt: skip
    assert joint["inlet_speed"] == pytest.approx(0.05, abs=0.004)


def test_a_weaker_single_and_a_pair_that_both_explain_are_ambiguous():
    # the best single (largest held-out improvement) leaves a gap, a weaker one does
    # not, and a pair explains: the verdict lists the single and the pair (issue 30,
    # hidden friction + inlet_speed where pillar_hydro alone left no gap)
    rng = np.random.default_rng(9)
    n = 60
    ho = evaluate_heldout(
        {"friction": 0.26, "pillar_hydro": 0.45},
        {"delta": np.full(n, 1.0)},
        {
            "friction": {"delta": 1.0 - rng.normal(0.9, 0.3, n)},
            "pillar_hydro": {"delta": 1.0 - rng.normal(0.5, 0.3, n)},
        },
        {"friction": _gap(1.5, 1), "pillar_hydro": _gap(0.0, 2)},
        rng,
        alpha=0.05,
    )
    best = max(ho, key=lambda h: h.improvement[0])
    assert best.name == "friction" and not best.explains
    assert next(h for h in ho if h.name == "pillar_hydro").explains
    pair = _set(("friction", "inlet_speed"), (0.001, 0.002), 0.0, 17)
    v = decide(_gap(2.0, 18), ho, "R", rng, 0.05, [pair])
    assert v.kind == "ambiguous"
    assert v.alternatives == ({"pillar_hydro": 0.45}, {"friction": 0.1, "inlet_speed": 0.1})
    assert set(v.effects) == {"pillar_hydro", "friction", "inlet_speed"}
    assert "pillar_hydro = 0.45 and (friction = 0.1 + inlet_speed = 0.1)" in v.text
    # without the pair the weaker single is not named: the best one is partial
    v = decide(_gap(2.0, 18), ho, "R", rng, 0.05, [])
    assert v.kind == "unexplained" and v.effects == {}
    assert "pillar_hydro alone leaves no significant gap" in v.text


def test_pairs_are_taken_in_turn_from_each_first_member():
    # two first members with their ranked partners: the plan's pairs alternate
    # between them in rounds, and a set met twice (A + B, then B + A) is tried once
    from fibersweep.discrepancy.candidates import LIBRARY
    from fibersweep.discrepancy.pairs import pair_trials

    L = LIBRARY
    q1 = [(L["pillar_hydro"], L[b], "in1") for b in ("off_midplane", "inlet_speed", "friction")]
    q2 = [(L["inlet_speed"], L[b], "in2") for b in ("pillar_hydro", "friction")]

    def names(rounds):
        return [[(a.name, b.name, inp) for a, b, inp in rnd] for rnd in rounds]

    assert names(pair_trials([q1, q2], 2)) == [
        [("pillar_hydro", "off_midplane", "in1"), ("inlet_speed", "pillar_hydro", "in2")],
    ]
    assert names(pair_trials([q1, q2], 4)) == [
        [("pillar_hydro", "off_midplane", "in1"), ("inlet_speed", "pillar_hydro", "in2")],
        [("inlet_speed", "friction", "in2")],  # pillar_hydro + inlet_speed was tried
        [("pillar_hydro", "friction", "in1")],
    ]
    # one first member: its partners in order, one per round, as before
    assert names(pair_trials([q1], 2)) == [[t] for t in names([q1[:2]])[0]]
    assert pair_trials([], 2) == []
