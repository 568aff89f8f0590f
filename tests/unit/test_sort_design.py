"""Critical lengths with their errors, and the inverse answer of a sorter design."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from fibersweep.sorting import design as sd
from fibersweep.sorting.report import check_edges, critical_table

FLOW = {"dx": 2.0, "array": {"pillar_shape": "triangle", "pillar_size": 40.0, "period_x": 80.0,
                             "period_y": 80.0, "shift": 0.1, "depth": 40.0}}  # fmt: skip


def _table(L, f, se, setting=0):
    return pd.DataFrame({"setting": setting, "length": L, "fraction_mean": f, "fraction_se": se})


def test_critical_length_interpolates_and_propagates_the_standard_errors():
    t = _table([10.0, 20.0], [0.2, 0.8], [0.05, 0.05])
    c = critical_table(t).iloc[0]
    assert c["critical"] == pytest.approx(15.0)  # halfway: w = 1/2
    # sigma = dL / |df| sqrt((1-w)^2 se0^2 + w^2 se1^2) = 10 / 0.6 * sqrt(2) * 0.025
    assert c["se"] == pytest.approx(10 / 0.6 * math.sqrt(2) * 0.025)
    assert (c["lo"], c["hi"], bool(c["rising"])) == (10.0, 20.0, True)
    # a band-pass: f rises, then falls through 1/2
    band = critical_table(_table([10.0, 20.0, 30.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]))
    assert band["critical"].tolist() == [15.0, 25.0] and band["rising"].tolist() == [True, False]


def _curve(values, crit, se, lo, hi, rising=True):
    return pd.DataFrame({"setting": range(len(values)), "value": values, "group": "",
                         "critical": crit, "se": se, "lo": lo, "hi": hi,
                         "rising": rising})  # fmt: skip


def test_the_curve_takes_a_falling_crossing_where_f_never_rises_through_one_half():
    # three stiffnesses: a high-pass (f rises through 1/2 at 15 µm), a low-pass (f falls
    # from 0.8 to 0.0: its critical length is where it falls, 54 µm, not "f > 1/2 at
    # every length"), and one above 1/2 everywhere (a bound, no critical length)
    t = pd.concat(
        [
            _table([10.0, 20.0, 40.0, 80.0], [0.2, 0.8, 0.9, 0.9], [0.05] * 4, 0),
            _table([10.0, 20.0, 40.0, 80.0], [0.8, 0.8, 0.7, 0.0], [0.05] * 4, 1),
            _table([10.0, 20.0, 40.0, 80.0], [0.8, 0.9, 0.7, 0.6], [0.05] * 4, 2),
        ]
    )
    settings = [{"values": {"fiber.young_modulus": e}} for e in (1e5, 1e4, 3e4)]
    cur = sd.critical_curve(critical_table(t), t, settings, "fiber.young_modulus")
    assert cur["critical"].iloc[0] == pytest.approx(15.0) and cur["rising"].iloc[0]
    assert cur["critical"].iloc[1] == pytest.approx(40.0 + 0.2 / 0.7 * 40.0)
    assert cur["rising"].iloc[1] is False or not cur["rising"].iloc[1]
    assert (cur["lo"].iloc[1], cur["hi"].iloc[1]) == (40.0, 80.0)
    assert math.isnan(cur["critical"].iloc[2]) and cur["hi"].iloc[2] == 10.0
    assert math.isnan(cur["lo"].iloc[2]) and cur["rising"].iloc[2] is None
    # a lower edge and an upper edge are not interpolated into one answer
    a = sd.answer(cur.iloc[:2], "fiber.young_modulus", 30.0, FLOW, bead=4.0)
    assert a.value is None and "not one curve" in a.text
    # two upper edges are
    two = _curve([1e4, 2e4], [54.0, 30.0], [1.0, 1.0], [40.0, 20.0], [80.0, 40.0], False)
    b = sd.answer(two, "fiber.young_modulus", 42.0, FLOW, bead=4.0)
    assert b.value == pytest.approx(1.5e4)


def test_the_setting_for_a_target_critical_length_is_interpolated_and_snapped_to_the_lattice():
    cur = _curve([0.1, 0.15, 0.2], [15.0, 28.4, 37.8], [0.3, 0.1, 1.5],
                 [12.0, 24.0, 32.0], [16.0, 32.0, 40.0])  # fmt: skip
    a = sd.answer(cur, "flow.array.shift", 22.0, FLOW, bead=4.0)
    w = (22.0 - 15.0) / (28.4 - 15.0)
    assert a.value == pytest.approx(0.1 + w * 0.05)
    # the statistical error alone, kept apart: it leaves the interpolation out
    assert a.se == pytest.approx(0.05 / 13.4 * math.hypot((1 - w) * 0.3, w * 0.1))
    # the interval holds the interpolation between lengths (brackets 12-16, 24-32 µm):
    # far wider than the statistical error, and inside the model-free span
    lo, hi = a.ci
    assert 0.1 < lo < a.value < hi < 0.15 and hi - lo > 10 * a.se
    assert a.level == 0.95 and "95 % interval: shift = " in a.text
    assert f"the statistical error alone: ± {a.se:.2g}" in a.text
    assert a.span == (0.1, 0.15)  # both brackets exclude 22 µm: decided whatever the curve
    assert a.lattice == (0.125, 0.15)  # ε λy whole cells of 2 µm: steps of 0.025
    assert a.add[0].startswith("shift = 0.125")  # the check, at the allowed value
    assert any("28 µm" in line for line in a.add)  # the 24-32 µm bracket is two beads wide
    # a bracket that holds the target: not decided yet
    b = sd.answer(cur, "flow.array.shift", 34.0, FLOW, bead=4.0)
    assert all(np.isnan(b.span)) and "not yet decided" in b.text
    # the lattice value nearest the answer was simulated: what its bracket says
    d = sd.answer(cur, "flow.array.shift", 30.0, FLOW, bead=4.0)
    assert "0.15, the value the lattice allows nearest, is simulated" in d.text
    assert "narrow the bracket" in d.text and any("28 µm" in line for line in d.add)
    # beyond the simulated critical lengths: no interpolation, the direction to go
    c = sd.answer(cur, "flow.array.shift", 50.0, FLOW, bead=4.0)
    assert c.value is None and "beyond 0.2" in c.add[0]


def test_a_categorical_setting_answers_with_the_nearest_simulated_value():
    cur = _curve(["triangle", "circle"], [15.0, 30.0], [1.0, 1.0], [12.0, 24.0], [16.0, 32.0])
    a = sd.answer(cur, "flow.array.pillar_shape", 27.0, FLOW, bead=4.0)
    assert a.value == "circle" and "not interpolated" in a.text


def test_design_key_is_the_swept_array_setting():
    st = [{"values": {"flow.array.shift": 0.1, "fiber.young_modulus": 1e4}},
          {"values": {"flow.array.shift": 0.2, "fiber.young_modulus": 1e4}}]  # fmt: skip
    assert sd.design_key(st) == "flow.array.shift"
    from fibersweep.errors import InputError

    with pytest.raises(InputError, match="valid: flow.array.shift"):
        sd.design_key(st, "flow.array.period_x")


@pytest.mark.parametrize("edges", [[1.5], [0.0], [-0.2], [0.5, 0.5], [], [math.nan]])
def test_outlet_edges_out_of_range_are_refused(edges):
    from fibersweep.errors import InputError

    with pytest.raises(InputError, match="--outlets"):
        check_edges(edges)
    assert check_edges([0.7, 0.3]) == [0.3, 0.7]


def test_the_interval_of_a_critical_length_holds_the_bracket_of_a_step():
    """A step between two lengths (plateaus on both sides): the runs cannot say where in
    the bracket the crossing is, so the interval spans most of it, not the ± of the
    statistical error. A transition over several lengths, with enough runs, pins it
    closer than the bracket."""
    L = [4.0, 8.0, 12.0, 16.0, 20.0, 24.0, 28.0]

    def table(f, n):
        return _table(L, f, [0.01] * 7).assign(moving=n, fraction_std=0.03, runs=n, trapped=0.0)

    step = critical_table(table([0.0, 0.0, 0.0, 0.9, 0.9, 0.9, 0.9], 12)).iloc[0]
    assert (step["lo"], step["hi"]) == (12.0, 16.0) and step["se"] < 0.1
    assert step["ci_lo"] < 12.5 and step["ci_hi"] > 15.5  # nearly the whole bracket
    ramp = critical_table(table([0.0, 0.0, 0.3, 0.6, 0.9, 0.9, 0.9], 48)).iloc[0]
    assert ramp["ci_lo"] < ramp["critical"] < ramp["ci_hi"]
    assert ramp["ci_hi"] - ramp["ci_lo"] < 0.6 * (step["ci_hi"] - step["ci_lo"])
    # the same tables, the same intervals (seeded)
    again = critical_table(table([0.0, 0.0, 0.0, 0.9, 0.9, 0.9, 0.9], 12)).iloc[0]
    assert (again["ci_lo"], again["ci_hi"]) == (step["ci_lo"], step["ci_hi"])


def test_a_length_with_few_moving_runs_that_decides_a_crossing_is_named():
    from fibersweep.sorting.report import thin_crossings

    L = [16.0, 20.0, 24.0]
    t = _table(L, [0.0, 0.05, 0.81], [0.01, 0.0, 0.03]).assign(
        moving=[12, 2, 12], fraction_std=[0.02, 0.0, 0.1], runs=12, trapped=[0.0, 10 / 12, 0.0]
    )
    crit = critical_table(t)
    settings = [{"label": "shift = 0.125", "array": FLOW["array"]}]
    (line,) = thin_crossings(t, crit, settings)[0]
    assert "shift = 0.125" in line and "20 µm" in line and "2 moving runs" in line
    assert "10 of 12 trapped" in line and "between 20 and 24 µm" in line
    # a length whose runs were all trapped, inside a bracket: named too
    gap = _table([16.0, 24.0], [0.0, 0.81], [0.01, 0.03]).assign(
        moving=[12, 12], fraction_std=[0.02, 0.1], runs=12, trapped=[0.0, 0.0]
    )
    gap = pd.concat([gap, pd.DataFrame([{"setting": 0, "length": 20.0, "fraction_mean": np.nan,
                                         "fraction_se": np.nan, "moving": 0, "runs": 12,
                                         "fraction_std": np.nan, "trapped": 1.0}])])  # fmt: skip
    (line,) = thin_crossings(gap, critical_table(gap), settings)[0]
    assert "no f at 20 µm (all 12 runs trapped)" in line


def test_the_answer_names_the_few_runs_it_rests_on_and_its_interval_the_curvature():
    cur = _curve([0.1, 0.125, 0.15], [15.0, 22.4, 28.4], [0.3, 0.1, 0.1],
                 [12.0, 20.0, 24.0], [16.0, 24.0, 32.0])  # fmt: skip
    caveats = {1: ["shift = 0.125: f at 20 µm rests on 2 moving runs"]}
    a = sd.answer(cur, "flow.array.shift", 22.0, FLOW, bead=4.0, caveats=caveats)
    assert a.caveats == ("shift = 0.125: f at 20 µm rests on 2 moving runs",)
    assert "0.125, the value the lattice allows nearest, is simulated" in a.text
    assert "between simulated values of shift" in a.text
    # two values only: the curvature between them is not estimated, and it says so
    b = sd.answer(cur.iloc[:2], "flow.array.shift", 20.0, FLOW, bead=4.0)
    assert "not the curvature between the two simulated values" in b.text
    # a target beyond what most draws reach: the interval is open on that side
    c = sd.answer(cur, "flow.array.shift", 28.0, FLOW, bead=4.0)
    assert c.ci[1] == math.inf and "beyond 0.15, the largest simulated" in c.text


def test_a_curve_without_the_rising_column_reads_as_rising():
    # a critical.csv written before the column existed, read back
    cur = _curve([0.1, 0.15], [15.0, 28.4], [0.3, 0.1], [12.0, 24.0], [16.0, 32.0])
    a = sd.answer(cur.drop(columns="rising"), "flow.array.shift", 22.0, FLOW, bead=4.0)
    assert a.value == pytest.approx(0.1 + 7.0 / 13.4 * 0.05)
