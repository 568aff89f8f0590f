"""The follow-up test of two hypotheses (fibersweep.discrepancy.settle), on Gaussian data.

With Gaussian components of known means and unit noise, the discriminant λ of one
fiber is N(+D²/2, D²) under A and N(-D²/2, D²) under B (D: the separation in noise
units), so the power of each one-sided test is known in closed form.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import norm

from fibersweep.discrepancy.decide import Verdict
from fibersweep.discrepancy.discriminant import (
    SettleTest,
    discriminant,
    fibers_to_settle,
    settle_test,
)
from fibersweep.discrepancy.gap import GapResult, assess_gap
from fibersweep.discrepancy.settle import Settlement, settled_verdict


def test_discriminant_is_the_gaussian_log_likelihood_ratio():
    x = np.array([[1.0, 2.0], [0.0, np.nan]])
    mu_a = np.array([[1.0, 2.0], [0.0, 0.0]])
    mu_b = np.array([[0.0, 0.0], [1.0, 5.0]])
    s = np.array([1.0, 2.0])
    lam = discriminant(x, mu_a, mu_b, s)
    # fiber 0: (1 - 0)²/2 + (2 - 0)²/(2·4) = 0.5 + 0.5; fiber 1: (0 - 1)²/2, the NaN adds 0
    np.testing.assert_allclose(lam, [1.0, 0.5], rtol=0, atol=1e-15)
    # copies broadcast over a leading axis
    assert discriminant(np.stack([x, x, x]), mu_a, mu_b, s).shape == (3, 2)
    with pytest.raises(ValueError, match="shapes differ"):
        discriminant(x, mu_a[:1], mu_b, s)
    with pytest.raises(ValueError, match="s must have shape"):
        discriminant(x, mu_a, mu_b, s[:1])


def _gaussian(rng, mu, k, sd=1.0):
    """k copies (k, n, c) around means mu (n, c)."""
    return mu + sd * rng.standard_normal((k,) + mu.shape)


def _trial(rng, mu_a, mu_b, truth, k_ref=200, k_null=400, n_draws=1999):
    x = _gaussian(rng, truth, 1)[0]
    return settle_test(
        x,
        _gaussian(rng, mu_a, k_ref),
        _gaussian(rng, mu_b, k_ref),
        _gaussian(rng, mu_a, k_null),
        _gaussian(rng, mu_b, k_null),
        rng,
        alpha=0.05,
        n_draws=n_draws,
    )


def test_power_matches_the_closed_form():
    """Under A, B is rejected with power Φ(√n D − z_{1−α}) (many copies: the limit).

    n = 9 fibers of separation D = 1 (one component): power Φ(3 − 1.645) = 0.912.
    300 trials: binomial sd 0.016; tolerance 0.05 (three sd, and the reference
    copies' finite means, k_ref = 200).
    """
    rng = np.random.default_rng(7)
    n, d, alpha, trials = 9, 1.0, 0.05, 300
    mu_a = np.zeros((n, 1))
    mu_b = np.full((n, 1), d)
    res = [_trial(rng, mu_a, mu_b, mu_a) for _ in range(trials)]
    power = np.mean([r.p_values[1] <= alpha for r in res])
    expected = norm.cdf(np.sqrt(n) * d - norm.ppf(1 - alpha))
    assert abs(power - expected) < 0.05, (power, expected)
    # Λ's moments under A: n D²/2 and √n D
    m_a = np.mean([r.expected[0] for r in res])
    sd_a = np.mean([r.spread[0] for r in res])
    assert abs(m_a - n * d**2 / 2) < 0.2 and abs(sd_a - np.sqrt(n) * d) < 0.2, (m_a, sd_a)
    # fibers for power 0.8 of each test at alpha, closed form: ((z_0.95 + z_0.8) / D)² =
    # 6.2 -> 7; the estimate from copies is within one fiber
    need = [r.fibers_to_settle for r in res[:20]]
    assert all(6 <= k <= 8 for k in need), need


@pytest.mark.parametrize("n", [1, 4, 9])
def test_size_holds_with_the_copies_the_workflow_uses(n):
    """The true hypothesis is rejected at most alpha of the time with 8 reference and
    16 null copies (the default 24), for one to nine fibers.

    4000 trials: binomial sd 0.0034; the size must be <= alpha + 3 sd = 0.060 (drawing
    from the 16 copies alone, the error the measured value in each pool removes,
    gives about 0.066 at n = 4 and 9; the exact size with it is at most 0.05).
    """
    rng = np.random.default_rng(100 + n)
    alpha, trials = 0.05, 4000
    mu_a = np.zeros((n, 1))
    mu_b = np.full((n, 1), 1.0)
    rejected = sum(
        _trial(rng, mu_a, mu_b, mu_a, k_ref=8, k_null=16, n_draws=199).p_values[0] <= alpha
        for _ in range(trials)
    )
    assert rejected / trials <= alpha + 3 * np.sqrt(alpha * (1 - alpha) / trials), rejected


def test_failed_copies_are_left_out_not_counted_as_zero():
    rng = np.random.default_rng(5)
    n = 6
    mu_a, mu_b = np.zeros((n, 1)), np.full((n, 1), 2.0)
    x = _gaussian(rng, mu_a, 1)[0]
    ref_a, ref_b = _gaussian(rng, mu_a, 8), _gaussian(rng, mu_b, 8)
    null_a, null_b = _gaussian(rng, mu_a, 16), _gaussian(rng, mu_b, 16)
    clean = settle_test(x, ref_a, ref_b, null_a, null_b, np.random.default_rng(1))
    # half of A's null copies of every fiber fail: the expected sum under A stays
    # n D²/2 = 12 (not halved towards 0), the count is reported
    ok = [np.ones(a.shape[:2], bool) for a in (ref_a, ref_b, null_a, null_b)]
    ok[2][:8] = False
    ok[0][0, 0] = False  # and one reference copy
    t = settle_test(x, ref_a, ref_b, null_a, null_b, np.random.default_rng(1), ok=tuple(ok))
    assert t.failed == 8 * n + 1 and clean.failed == 0
    assert abs(t.expected[0] - clean.expected[0]) < 0.3 * clean.expected[0], (t, clean)


def test_size_holds_when_outcomes_are_often_undefined():
    """An outcome undefined by its rule (no contact: NaN in every component) is an
    outcome, in the copies as in the measured fibers (λ = 0 in both), not a failure.

    20 fibers, one component (D = 1) undefined half the time under both hypotheses,
    A true, 8 reference and 16 null copies. 1000 trials: binomial sd 0.0069; the size
    must be <= alpha + 3 sd = 0.071 (dropping such copies as failed gives about 0.2).
    """
    rng = np.random.default_rng(17)
    n, alpha, trials = 20, 0.05, 1000

    def draw(mu, k):
        v = _gaussian(rng, mu, k)
        v[rng.random(v.shape) < 0.5] = np.nan
        return v

    mu_a, mu_b = np.zeros((n, 1)), np.full((n, 1), 1.0)
    rejected = 0
    for _ in range(trials):
        t = settle_test(draw(mu_a, 1)[0], draw(mu_a, 8), draw(mu_b, 8), draw(mu_a, 16),
                        draw(mu_b, 16), rng, alpha=alpha, n_draws=199)  # fmt: skip
        rejected += t.p_values[0] <= alpha
    assert rejected / trials <= alpha + 3 * np.sqrt(alpha * (1 - alpha) / trials), rejected


def test_the_count_it_gives_has_the_power_it_states():
    """Power 0.8 at the fibers it says are needed, with the workflow's 8 + 16 copies.

    One component, D = 0.5 per fiber. The count: the median of 60 estimates from
    10-fiber pilots (the reference means' noise and the measured value in each pool
    included; the closed form without either is 25). 300 trials at that count under
    each hypothesis: binomial sd 0.023; power within 0.8 ± 0.08 (three sd and the
    pilot median's own spread).
    """
    rng = np.random.default_rng(11)
    d = 0.5

    def trial(n, truth):
        mu = {"A": np.zeros((n, 1)), "B": np.full((n, 1), d)}
        return settle_test(_gaussian(rng, mu[truth], 1)[0], _gaussian(rng, mu["A"], 8),
                           _gaussian(rng, mu["B"], 8), _gaussian(rng, mu["A"], 16),
                           _gaussian(rng, mu["B"], 16), rng, n_draws=999)  # fmt: skip

    need = int(np.median([trial(10, "A").fibers_to_settle or 10**6 for _ in range(60)]))
    assert 25 < need < 120, need
    for truth, wrong in (("A", 1), ("B", 0)):
        power = np.mean([trial(need, truth).p_values[wrong] <= 0.05 for _ in range(300)])
        assert abs(power - 0.8) < 0.08, (truth, need, power)


def test_fibers_to_settle_is_none_without_a_separation():
    assert fibers_to_settle(0.0, 1.0, 1.0, 0.05) is None
    assert fibers_to_settle(1.0, np.nan, 1.0, 0.05) is None
    # closed form ((z_0.95 + z_0.8) / 1)² = 6.18 -> 7; 16 null copies: × (17/16)² -> 7
    assert fibers_to_settle(1.0, 1.0, 1.0, 0.05) == 7
    assert fibers_to_settle(0.5, 1.0, 1.0, 0.05, k_null=16) == 28


def test_outcomes():
    rng = np.random.default_rng(3)
    n = 8
    mu_a = np.zeros((n, 2))
    mu_b = np.full((n, 2), 2.0)
    assert _trial(rng, mu_a, mu_b, mu_a).outcome == "A"
    assert _trial(rng, mu_a, mu_b, mu_b).outcome == "B"
    # fibers half way between two well separated hypotheses: both rejected
    assert _trial(rng, mu_a, mu_b, np.full((n, 2), 1.0)).outcome == "neither"
    # the test looks along A - B only: fibers beyond A (away from B) are A's
    assert _trial(rng, mu_a, mu_b, np.full((n, 2), -1.0)).outcome == "A"
    # identical hypotheses: nothing separates them, and no number of fibers would
    same = _trial(rng, mu_a, mu_a, mu_a)
    assert same.outcome == "undecided"
    assert same.fibers_to_settle is None or same.fibers_to_settle > 1000


def test_shapes_are_checked():
    rng = np.random.default_rng(0)
    x = np.zeros((3, 2))
    ok = np.zeros((4, 3, 2))
    with pytest.raises(ValueError, match="null_b must have shape"):
        settle_test(x, ok, ok, ok, np.zeros((4, 2, 2)), rng)
    with pytest.raises(ValueError, match="at least 2 copies"):
        settle_test(x, ok[:1], ok, ok, ok, rng)
    with pytest.raises(ValueError, match="n >= 1"):
        settle_test(np.zeros((0, 2)), ok[:, :0], ok[:, :0], ok[:, :0], ok[:, :0], rng)
    with pytest.raises(ValueError, match="ok mask"):
        settle_test(x, ok, ok, ok, ok, rng, ok=(np.ones((4, 3), bool),) * 3 + (np.ones(3, bool),))


def _gap(left: bool) -> GapResult:
    """A real gap test on made-up values: the observed column 5 sd off, or not."""
    rng = np.random.default_rng(0)
    v = rng.standard_normal((10, 9))
    v[:, 0] += 5.0 if left else 0.0
    return assess_gap({"delta": v}, rng, n_perm=999)


def _settlement(outcome: str, hyps=({"a": 1.0}, {"b": 2.0}), gap_left=False) -> Settlement:
    p = {"A": (0.5, 0.001), "B": (0.001, 0.5), "neither": (0.001, 0.001)}.get(outcome, (0.5, 0.5))
    t = SettleTest(np.zeros(5), 0.0, (1.0, -1.0), (1.0, 1.0), p, outcome, 7)
    adequacy = _gap(gap_left) if outcome in ("A", "B") else None
    return Settlement(("a = 1", "b = 2"), hyps, "the verdict is ambiguous", 5, ("class",), t, 240,
                      adequacy)  # fmt: skip


def test_an_ambiguous_verdict_is_named_only_when_the_follow_up_settles_it():
    amb = Verdict("ambiguous", {"a": 1.0, "b": 2.0}, "delta", "everywhere", "Ambiguous …",
                  ({"a": 1.0}, {"b": 2.0}))  # fmt: skip
    named = settled_verdict(amb, _settlement("B"))
    assert named.kind == "named" and named.effects == {"b": 2.0}
    assert named.alternatives == ({"b": 2.0},)
    assert "reject a = 1" in named.text and "On the first fibers alone" in named.text
    # the winner leaves a gap on the follow-up fibers: not named
    left = _settlement("B", gap_left=True)
    assert not left.settled and settled_verdict(amb, left) is amb
    assert "leaves a significant gap in delta" in left.text()
    assert settled_verdict(amb, _settlement("A")).effects == {"a": 1.0}
    for outcome in ("neither", "undecided"):
        assert settled_verdict(amb, _settlement(outcome)) is amb
    # a settlement of other hypotheses, or an ambiguity among three, leaves it
    assert settled_verdict(amb, _settlement("A", ({"a": 1.0}, {"c": 0.1}))) is amb
    three = Verdict("ambiguous", {}, "", "", "", ({"a": 1.0}, {"b": 2.0}, {"c": 3.0}))
    assert settled_verdict(three, _settlement("A")) is three
    un = Verdict("unexplained", {}, "delta", "", "Unexplained")
    assert settled_verdict(un, _settlement("A")) is un
    assert "do not separate" in _settlement("undecided").text()
    assert "rejecting both" in _settlement("neither").text()

