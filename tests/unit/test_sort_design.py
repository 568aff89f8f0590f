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
    t = pd.concat([_table([10.0, 20.0, 40.0, 80.0], [0.2, 0.8, 0.9, 0.9], [0.05] * 4, 0),
                   _table([10.0, 20.0, 40.0, 80.0], [0.8, 0.8, 0.7, 0.0], [0.05] * 4, 1),
                   _table([10.0, 20.0, 40.0, 80.0], [0.8, 0.9, 0.7, 0.6], [0.05] * 4, 2)])
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
    assert a.se == pytest.approx(0.05 / 13.4 * math.hypot((1 - w) * 0.3, w * 0.1))
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


def test_a_curve_without_the_rising_column_reads_as_rising():
    # a critical.csv written before the column existed, read back
    cur = _curve([0.1, 0.15], [15.0, 28.4], [0.3, 0.1], [12.0, 24.0], [16.0, 32.0])
    a = sd.answer(cur.drop(columns="rising"), "flow.array.shift", 22.0, FLOW, bead=4.0)
    assert a.value == pytest.approx(0.1 + 7.0 / 13.4 * 0.05)
