"""The array chronophotograph draws a flexible fiber's stored beads (its bent shape)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from matplotlib.collections import LineCollection

from fibersweep.config.flow import FlowSettings
from fibersweep.plots import array as pa
from fibersweep.plots.shapes import ShapeNotStored
from fibersweep.sorting.report import _beads


def test_stored_beads_come_back_as_samples_by_beads_by_two():
    rows = pd.Series([list(np.arange(8.0) + k) for k in range(3)])  # 3 samples, 4 beads
    b = _beads(rows)
    assert b.shape == (3, 4, 2)
    assert b[1, 2].tolist() == [5.0, 6.0]  # sample 1: 1 + (4, 5)
    assert _beads(pd.Series([None, None])) is None  # rigid runs store no beads


def test_a_bent_fiber_is_drawn_through_its_beads_not_as_a_rod():
    arr = FlowSettings.model_validate({"dx": 4.0, "array": {}}).array.to_array()
    t = np.linspace(0.0, 1.0, 5)
    s = np.linspace(-10.0, 10.0, 6)
    bent = np.stack([np.column_stack([s + 40 * k, 30 + 0.05 * s**2]) for k in range(5)])
    run = {
        "traj_t": t, "traj_xc": bent[:, :, 0].mean(1), "traj_yc": bent[:, :, 1].mean(1),
        "traj_th": np.zeros(5), "n_beads": 6, "mode": "displacement", "length": 24.0,
        "y0": 0.4, "theta0": 0.0, "traj_beads": bent,
    }  # fmt: skip
    fig = pa.chrono_figure(arr, [run], 2.0, frames=5)
    segs = [s for c in fig.axes[0].collections if isinstance(c, LineCollection)
            for s in c.get_segments()]  # fmt: skip
    assert len(segs) == 5 and all(len(s) == 6 for s in segs)  # 6 beads at every frame
    assert np.allclose(segs[0][:, 1], bent[0, :, 1])  # the parabola, not a rod
    rod = pa.chrono_figure(arr, [{**run, "traj_beads": None}], 2.0, frames=5)  # rigid: 2 ends
    segs = [s for c in rod.axes[0].collections if isinstance(c, LineCollection)
            for s in c.get_segments()]  # fmt: skip
    assert segs and all(len(s) == 2 for s in segs)
    # a bead-spring run must show its beads: without them nothing is drawn, and why is said
    with pytest.raises(ShapeNotStored, match="all_beads"):
        pa.chrono_figure(arr, [{**run, "traj_beads": None, "model": "bead-spring-ros2"}], 2.0)
    short = {**run, "model": "bead-spring-ros2", "traj_beads": bent[:, :5]}  # a bead missing
    with pytest.raises(ShapeNotStored, match="5 bead positions for a fiber of 6"):
        pa.chrono_figure(arr, [short], 2.0, frames=5)


def test_settings_are_labelled_with_their_unit_and_ordered_by_value():
    from fibersweep.sorting.report import _order, _value_label

    assert _value_label("fiber.young_modulus", 1e6) == "young_modulus = 1e+06 Pa"
    assert _value_label("flow.array.shift", 0.1) == "shift = 0.1"
    entries = [{"values": {"fiber.young_modulus": v}} for v in (1e6, 1e4, 1e5)]
    ordered = [e["values"]["fiber.young_modulus"] for e in sorted(entries, key=_order)]
    assert ordered == [1e4, 1e5, 1e6]  # by value, not as text
