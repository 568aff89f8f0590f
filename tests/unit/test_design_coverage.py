"""Do the sort report's intervals hold the truth as often as they say?

Synthetic designs with a known truth, no simulation: the mean displacement
fraction of a fiber of length L at row shift ε is a sigmoid in L between two
plateaus (zigzag near 0, displacement 0.80 to 0.95), whose critical length (mean
f = 1/2) is a smooth, concave function of ε, as in docs/arrays.md (15, 28 and 38
µm at ε = 0.1, 0.15, 0.2). Each design draws its own truth: the critical length
at ε = 0.1, its slope and curvature, the sigmoid's width (from a step, 0.2 µm,
to a transition over two lengths, 2 µm) and the plateaus. It is sampled as the
report sees a sweep: lengths 4 µm apart (whole beads), 12 runs per length and
shift, each run displaced with the truth's probability or zigzagging (its f the
plateau plus a little scatter), and near the critical length up to 80 % of the
runs trapped (left out of f, as the report does).

Per design the report's pipeline runs unchanged (critical table, the curve
against ε, the answer for a target critical length drawn between the simulated
ones); the truth is then checked: each shift's true critical length against its
interval, and the true shift for the target (where the true curve reaches it)
against the answer's interval. Over ``DESIGNS`` designs the share inside must be
the nominal level within twice its binomial error, both ways (an interval that
holds the truth every time is too wide to be what it says). The error is taken
over designs, not intervals: the three critical lengths of one design share its
truth (width, plateaus, trapping), so they are not independent.

Measured (seed 0): see ``docs/arrays.md``, 'Design: a target critical length'.
Run as a script for the rates with more designs:
``python3 tests/unit/test_design_coverage.py 400``.
"""

from __future__ import annotations

import math
import sys

import numpy as np
import pandas as pd
import pytest

from fibersweep.sorting import design as sd
from fibersweep.sorting import report as sr
from fibersweep.sorting.interval import INTERVAL_LEVEL

FLOW = {"dx": 2.0, "array": {"pillar_shape": "triangle", "pillar_size": 40.0, "period_x": 80.0,
                             "period_y": 80.0, "shift": 0.1, "depth": 40.0}}  # fmt: skip
KEY = "flow.array.shift"
SHIFTS = np.array([0.1, 0.15, 0.2])
LENGTHS = np.arange(4.0, 52.0, 4.0)
RUNS = 12
DESIGNS = 200


def _expit(z):
    return 1.0 / (1.0 + np.exp(-z))


def design(rng: np.random.Generator, width: tuple[float, float] = (0.2, 2.0)):
    """One synthetic sweep: its migration table, the settings, the true critical length."""
    c0, slope = rng.uniform(12, 20), rng.uniform(150, 300)
    bend = -rng.uniform(0.0, 1.0) * 3.5 * slope  # concave, still rising at ε = 0.2

    def truth(eps):
        return c0 + slope * (eps - 0.1) + bend * (eps - 0.1) ** 2

    w = rng.uniform(*width)
    p0, p1 = rng.uniform(0.0, 0.05), rng.uniform(0.8, 0.95)
    mid = math.log((0.5 - p0) / (p1 - 0.5))  # the sigmoid is 1/2 at the critical length
    rows = []
    for s, eps in enumerate(SHIFTS):
        lc = truth(eps)
        for L in LENGTHS:
            p = _expit((L - lc) / w + mid)
            trap = rng.uniform(0.0, 0.8) * math.exp(-(((L - lc + 2.0) / 3.0) ** 2))
            trapped = rng.random(RUNS) < trap
            shown = rng.random(RUNS) < p
            f = np.where(shown, p1, p0) + rng.normal(0.0, 0.03, RUNS)
            moving = f[~trapped]
            n = moving.size
            std = float(moving.std(ddof=1)) if n > 1 else math.nan
            # the migration table's columns the intervals read (its own groupby is the
            # slow part of a pure-numbers test; tests/unit/test_array_modes.py covers it)
            rows.append({"setting": s, "length": L, "runs": RUNS, "moving": n,
                         "trapped": float(trapped.mean()),
                         "fraction_mean": float(moving.mean()) if n else math.nan,
                         "fraction_std": std,
                         "fraction_se": std / math.sqrt(n) if n > 1 else math.nan})  # fmt: skip
    settings = [{"values": {KEY: float(e)}, "flow": {**FLOW, "array": {**FLOW["array"],
                 "shift": float(e)}}, "label": f"shift = {e:g}"} for e in SHIFTS]  # fmt: skip
    return pd.DataFrame(rows), settings, truth


def true_shift(truth, target: float) -> float:
    """Where the true curve reaches ``target`` (it rises over the shifts)."""
    lo, hi = SHIFTS[0], SHIFTS[-1]
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if truth(mid) < target else (lo, mid)
    return 0.5 * (lo + hi)


def coverage(designs: int, seed: int = 0, width=(0.2, 2.0)) -> dict[str, tuple[int, int]]:
    """(inside, checked) for the critical lengths and the inverse answers over ``designs``."""
    rng = np.random.default_rng(seed)
    crit_in = crit_n = inv_in = inv_n = 0
    for _ in range(designs):
        table, settings, truth = design(rng, width)
        crit = sr.critical_table(table)
        curve = sd.critical_curve(crit, table, settings, KEY)
        for r in curve.itertuples():
            crit_n += 1
            crit_in += bool(r.ci_lo <= truth(r.value) <= r.ci_hi)
        target = rng.uniform(truth(SHIFTS[0]) + 1.0, truth(SHIFTS[-1]) - 1.0)
        (ga,) = sd.answers(curve, settings, KEY, target, 4.0, table=table)
        lo, hi = ga.answer.ci
        inv_n += 1
        inv_in += bool(lo <= true_shift(truth, target) <= hi)  # no answer: NaN, a miss
    return {"critical length": (crit_in, crit_n), "inverse answer": (inv_in, inv_n)}


def _within(inside: int, n: int, designs: int, z: float = 2.0) -> bool:
    """The share inside is the nominal level within ``z`` binomial errors over ``designs``."""
    se = math.sqrt(INTERVAL_LEVEL * (1 - INTERVAL_LEVEL) / designs)
    return abs(inside / n - INTERVAL_LEVEL) <= z * se


def test_intervals_hold_the_truth_at_their_stated_level():
    got = coverage(DESIGNS)
    for what, (inside, n) in got.items():
        assert _within(inside, n, DESIGNS), (
            f"{what}: {inside}/{n} = {inside / n:.3f}, nominal {INTERVAL_LEVEL}"
        )


def test_the_statistical_error_alone_misses_the_interpolation():
    """The old ± (standard errors through the linear interpolations) on the same designs:
    its 95 % band (1.96 se) holds the true critical length far less often than 95 %."""
    rng = np.random.default_rng(1)
    inside = n = 0
    for _ in range(60):
        table, settings, truth = design(rng)
        curve = sd.critical_curve(sr.critical_table(table), table, settings, KEY)
        for r in curve.itertuples():
            n += 1
            inside += bool(abs(r.critical - truth(r.value)) <= 1.96 * r.se)
    assert inside / n < 0.8, inside / n


@pytest.mark.parametrize("width", [(0.05, 0.3), (1.0, 2.0)])
def test_a_step_and_a_resolved_transition_are_both_covered(width):
    """The two ends of the model: a step inside one bracket (the runs cannot say where)
    and a transition over two lengths (they can)."""
    inside, n = coverage(60, seed=2, width=width)["critical length"]
    assert _within(inside, n, 60), f"{width}: {inside}/{n}"


if __name__ == "__main__":  # the rates, with more designs
    count = int(sys.argv[1]) if len(sys.argv) > 1 else DESIGNS
    width = tuple(float(w) for w in sys.argv[2].split(",")) if len(sys.argv) > 2 else (0.2, 2.0)
    for what, (inside, n) in coverage(count, width=width).items():
        se = math.sqrt(INTERVAL_LEVEL * (1 - INTERVAL_LEVEL) / count)
        print(
            f"widths {width} µm, {what}: {inside}/{n} = {inside / n:.3f} over {count} "
            f"designs (nominal {INTERVAL_LEVEL}, binomial error over designs ± {se:.3f})"
        )
