"""Naming a random effect by its held-out spread (issue 30), on a Gaussian stand-in.

The stand-in replaces the simulator only: the workflow's own stages (noise floor,
ranking, cross-fitting, refit) and decision run unchanged on it. One observable, δ,
of 60 fibers; copy k of fiber i is x_i + 0.2 v_inlet + 0.02 sqrt(1 + v_sn^2) z_ik,
so start_noise (v_sn, a random effect) widens the outcome and inlet_speed (v_inlet)
shifts it. On it the gap family detects start_noise in 80 % of data sets near
v_sn = 0.95 (measured 57, 87, 96 of 100 at 0.75, 1.0, 1.25): twice that limit is
about 2.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from fibersweep.discrepancy.candidates import get_candidates
from fibersweep.discrepancy.decide import decide
from fibersweep.discrepancy.dispersion import shift_test, spread_test
from fibersweep.discrepancy.settings import DiscrepancySettings, plan_budget
from fibersweep.discrepancy.stages import Run, cross_fit, noise_floor, rank, refit

SIGMA = 0.02  # sd of δ of a copy without start noise
SHIFT = 0.2  # δ shift per unit of inlet_speed
BOTH = ["start_noise", "inlet_speed"]


class _Model:
    """Copies of the stand-in; the draws z_ik are fixed per data set (common random
    numbers across values, as the copy maker's seeds are)."""

    def __init__(self, x: np.ndarray, rng: np.random.Generator, m: int = 40):
        self.x = x
        self.z = rng.standard_normal((m, len(x)))

    def copies(self, ks, effects=None, rows=None, desc=""):
        return [self.copy(k, effects, rows, desc) for k in ks]

    def copy(self, k, effects=None, rows=None, desc=""):
        e = effects or {}
        sn, sh = float(e.get("start_noise", 0.0)), float(e.get("inlet_speed", 0.0))
        idx = np.arange(len(self.x)) if rows is None else np.asarray(rows)
        d = self.x[idx] + SHIFT * sh + SIGMA * np.sqrt(1.0 + sn**2) * self.z[k, idx]
        return pd.DataFrame({"delta": d})


def _verdict(hidden: dict, library: list[str], seed: int, n: int = 60):
    """The workflow's stages (no pairs) on one stand-in data set: (Verdict, State)."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(0.0, 0.5, n)
    model = _Model(x, rng)
    sn, sh = float(hidden.get("start_noise", 0.0)), float(hidden.get("inlet_speed", 0.0))
    d = x + SHIFT * sh + SIGMA * np.sqrt(1.0 + sn**2) * rng.standard_normal(n)
    obs = pd.DataFrame({"delta": d, "theta0": rng.uniform(-90, 90, n), "y0": x,
                        "length": np.ones(n), "contact": np.zeros(n)})  # fmt: skip
    s = DiscrepancySettings(n_perm=499, pairs=0, seed=seed)
    cands = get_candidates(library)
    run_rng = np.random.default_rng([seed, 11])
    perm = run_rng.permutation(n)
    folds = [np.sort(perm[: n // 2]), np.sort(perm[n // 2 :])]
    run = Run(s, plan_budget(n, s, cands), cands, obs, ("delta",), folds, run_rng, model)
    st = noise_floor(run)
    if st.gap.any:
        st = refit(cross_fit(rank(st)))
    return decide(st.gap, list(st.heldout), st.region_text, run_rng, s.alpha, []), st


def _count(hidden: dict, library: list[str], seeds: range) -> dict:
    out = {"named sn": 0, "spread route": 0, "score route": 0, "named other": 0, "gap": 0}
    for seed in seeds:
        v, st = _verdict(hidden, library, seed)
        out["gap"] += st.gap.any
        out["named sn"] += v.kind == "named" and list(v.effects) == ["start_noise"]
        out["named other"] += v.kind == "named" and "start_noise" not in v.effects
        h = {x.name: x for x in st.heldout}.get("start_noise")
        if h is not None:
            out["spread route"] += h.spread_significant and h.explains
            out["score route"] += h.significant and h.explains
    return out


@pytest.mark.parametrize("value", [2.0, 2.5])
def test_random_effect_twice_the_limit_is_named(value):
    # 100 data sets each (seeds 2000-2099): start_noise named in >= 90 % (measured
    # 2.0: 92 of 100, 2.5: 94; over seeds 2000-2199: 190 and 192 of 200, i.e. 0.95
    # with a binomial sd of 0.015). The spread route alone names it in >= 85 %
    # (measured 90 and 88 of 100); the score route alone would in 57 and 78.
    c = _count({"start_noise": value}, BOTH, range(2000, 2100))
    assert c["named sn"] >= 90
    assert c["spread route"] >= 85
    assert c["named other"] == 0


def test_detection_near_the_stated_limit():
    # the gap family at start_noise = 1.0, just above the limit 0.95: detected in
    # 70-97 of 100 data sets (measured 87; binomial 3 sd of 100 draws at 0.85 is 11)
    c = _count({"start_noise": 1.0}, BOTH, range(1000, 1100))
    assert 70 <= c["gap"] <= 97


@pytest.mark.parametrize("library", [BOTH, ["start_noise"]], ids=["both", "sn-only"])
@pytest.mark.parametrize("shift", [0.05, 0.1])
def test_a_shift_is_never_named_a_spread(shift, library):
    # shift-only data (0.5 and 1 sd of δ; gap detected in 95 and 100 of 100), 100
    # data sets each (seeds 4000-4099): start_noise never named (measured 0 of 400;
    # 0 of 400 more on seeds 4000-4099 / 5000-5099 before). With inlet_speed in the
    # library the shift itself is named in 16 and 92 of 100.
    c = _count({"inlet_speed": shift}, library, range(4000, 4100))
    assert c["named sn"] == 0


def test_null_names_nothing_and_false_alarms_at_most_alpha():
    # 200 no-effect data sets (seeds 3000-3199): nothing named (measured 0); the gap
    # family's false alarms <= 0.05 + 3 binomial sd (0.046) (measured 10 of 200)
    c = _count({}, BOTH, range(3000, 3200))
    assert c["named sn"] == 0 and c["named other"] == 0
    assert c["gap"] / 200 <= 0.05 + 0.046


def _values(n: int, m: int, s_obs: float, mu: float, rng: np.random.Generator) -> dict:
    x = rng.uniform(0.0, 0.5, n)
    obs = x + SIGMA * (mu + s_obs * rng.standard_normal(n))
    return {"delta": np.column_stack([obs, x[:, None] + SIGMA * rng.standard_normal((n, m))])}


def test_shift_test_ignores_a_widening_and_sees_a_shift():
    # 300 data sets of 60 fibers x 16 copies, observation 2x as spread as the copies and
    # not shifted: rejections at 0.05 in 0.05 +- 0.038 (3 binomial sd of 300); shifted by
    # 1 sd (no widening): rejected in >= 95 % (t about 1 / sqrt(1/12 ... ) x sqrt(60) > 5)
    rng = np.random.default_rng(8)
    wide = [shift_test(_values(60, 16, 2.0, 0.0, rng), rng) <= 0.05 for _ in range(300)]
    assert abs(np.mean(wide) - 0.05) <= 0.038
    moved = [shift_test(_values(60, 16, 1.0, 1.0, rng), rng) <= 0.05 for _ in range(100)]
    assert np.mean(moved) >= 0.95


def test_spread_test_false_alarms_at_most_alpha():
    # 300 no-effect data sets (60 fibers, 8 baseline and 16 'effect' copies, both
    # exchangeable with the observation): the intersection-union p <= 0.05 in at most
    # 0.05 + 0.038 (3 binomial sd of 300); it is conservative (max of two p values)
    rng = np.random.default_rng(9)
    hits = 0
    for _ in range(300):
        v = _values(60, 24, 1.0, 0.0, rng)["delta"]
        t = spread_test({"delta": v[:, :9]}, {"delta": v[:, [0, *range(9, 25)]]}, rng, 499)
        hits += t.p <= 0.05
    assert hits / 300 <= 0.05 + 0.038


def test_a_barely_visible_shift_is_named_a_spread_at_most_alpha():
    # shift 0.2 sd of δ (gap detected in 24 of 100): the data sets where the spread
    # route names start_noise are ones the sample drew over-dispersed by chance (mean
    # dispersion score 1.29 and 1.39, where a 0.2 sd shift gives about 1.02): false
    # alarms of the spread test, bounded by its alpha. Measured 2 of 100 (seeds
    # 4000-4099); stated: at most 5 of 100.
    c = _count({"inlet_speed": 0.02}, BOTH, range(4000, 4100))
    assert c["named sn"] <= 5


def test_report_states_the_spread_test():
    # the report's line for a random effect gives both mean dispersion scores and the
    # Holm-adjusted p of its spread test
    from fibersweep.discrepancy.report import _spread_dict
    from fibersweep.discrepancy.report_text import _spread_lines

    v, st = _verdict({"start_noise": 2.5}, BOTH, 2000)
    rows = [{"effect": h.name, "spread": _spread_dict(h)} for h in st.heldout]
    text = "\n".join(_spread_lines(rows))
    h = {x.name: x for x in st.heldout}["start_noise"]
    assert f"{h.spread.base_mean:.2f} against the baseline" in text
    assert "inlet_speed" not in text  # not a random effect: no spread test
