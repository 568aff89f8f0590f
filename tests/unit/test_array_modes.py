"""Transport modes are a pure function of the trajectory (synthetic trajectories)."""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.analysis.modes import ModeSettings, row_crossings, summarise_rows

PX, SHIFT = 80.0, 8.0


def _traj(x, y, th=None, contact=None, speed=None):
    n = len(x)
    return {
        "t": np.arange(n, dtype=float),
        "xc": np.asarray(x, float),
        "yc": np.asarray(y, float),
        "th": np.zeros(n) if th is None else np.asarray(th, float),
        "contact": np.zeros(n) if contact is None else np.asarray(contact, float),
        "speed": np.full(n, 100.0) if speed is None else np.asarray(speed, float),
    }


def test_row_crossings_interpolate_at_whole_periods():
    x = np.linspace(0.0, 400.0, 41)
    y = 0.1 * x
    assert np.allclose(row_crossings(x, y, PX), [0.0, 8.0, 16.0, 24.0, 32.0, 40.0])


@pytest.mark.parametrize(
    ("slope", "mode"),
    [(0.0, "zigzag"), (SHIFT / PX, "displacement"), (0.5 * SHIFT / PX, "mixed")],
)
def test_mode_follows_the_displacement_fraction(slope, mode):
    x = np.linspace(0.0, 20 * PX, 401)
    s = summarise_rows(_traj(x, slope * x), PX, SHIFT)
    assert s.rows == 20
    assert s.mode == mode
    assert s.fraction == pytest.approx(slope * PX / SHIFT, abs=1e-9)


def test_trapped_when_the_record_ends_stopped_in_contact():
    x = np.linspace(0.0, 150.0, 20)
    c = np.zeros(20)
    c[-5:] = 1
    sp = np.full(20, 100.0)
    sp[-1] = 0.1
    assert summarise_rows(_traj(x, 0 * x, contact=c, speed=sp), PX, SHIFT).mode == "trapped"


def test_wrap_and_jump_needs_turns_in_contact():
    x = np.linspace(0.0, 10 * PX, 1001)
    y = 0.8 * SHIFT / PX * x
    th = np.zeros_like(x)
    c = np.zeros_like(x)
    for r in range(10):  # a 180° swing in contact in every row
        k = slice(r * 100 + 20, r * 100 + 60)
        c[k] = 1
        th[k] = np.linspace(0, np.pi, 40) + th[r * 100 + 19]
        th[r * 100 + 60 : (r + 1) * 100] = th[r * 100 + 59]
    s = summarise_rows(_traj(x, y, th, c), PX, SHIFT)
    assert s.wraps == 10
    assert s.mode == "wrap-and-jump"
    # the same path without turning is plain displacement
    assert summarise_rows(_traj(x, y, None, c), PX, SHIFT).mode == "displacement"
    # thresholds are parameters: a stricter displacement rule makes it mixed
    strict = ModeSettings(displacement_min=0.9)
    assert summarise_rows(_traj(x, y, None, c), PX, SHIFT, strict).mode == "mixed"


def test_refine_lengths_bisects_where_the_mean_fraction_crosses_one_half():
    """The lengths sort-report proposes: midpoints of neighbours bracketing f = 1/2."""
    import pandas as pd

    from fibersweep.sorting.report import migration_table, refine_lengths

    runs = pd.DataFrame(
        {
            "setting": [0] * 6 + [1] * 4,
            "setting_label": [""] * 10,
            "length": [4, 4, 20, 20, 40, 40, 4, 4, 20, 20],
            "fraction": [0.0, 0.1, 0.3, 0.9, 0.9, 1.0, 0.0, 0.0, 0.1, 0.2],
            "migration_angle": [0.0] * 10,
            "mode": ["zigzag"] * 10,
        }
    )
    # setting 0: means 0.05, 0.6, 0.95 -> bracket (4, 20); setting 1 never crosses
    assert refine_lengths(migration_table(runs)) == {0: [12.0], 1: []}
    # trapped runs do not count in the means
    runs.loc[3, "mode"] = "trapped"
    assert refine_lengths(migration_table(runs)) == {0: [30.0], 1: []}
