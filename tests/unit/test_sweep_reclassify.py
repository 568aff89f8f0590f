"""Re-classification needs stored trajectories; without them it says so (exit code 2 path)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from fibersweep.analysis.tables import trajectory_from_frame
from fibersweep.config import parse_config
from fibersweep.config.fiber import ClassifySettings
from fibersweep.errors import InputError
from fibersweep.sweep.manifest import write_manifest
from fibersweep.sweep.reclassify import class_counts, reclassify, thresholds_for
from fibersweep.sweep.store import PartWriter


def test_no_trajectories_is_an_input_error(tmp_path):
    write_manifest(tmp_path, {"config": parse_config({}).model_dump(mode="json")})
    with PartWriter(tmp_path) as w:
        w.add({"id": "a", "status": "ok", "class": "Below", "theta0": 0.0, "y0": 0.1,
               "length": 1.0}, None)  # fmt: skip
    with pytest.raises(InputError, match="no trajectories were recorded"):
        reclassify(tmp_path, ClassifySettings())
    with pytest.raises(InputError, match="no sweep results"):
        reclassify(tmp_path / "empty", ClassifySettings())


def test_thresholds_layering(tmp_path):
    cfg = parse_config({"fiber": {"classify": {"trap_time": 3.0}}})
    write_manifest(tmp_path, {"config": cfg.model_dump(mode="json")})
    th = thresholds_for(tmp_path, head_blocked_speed=0.05, trap_time=None)
    assert (th.trap_time, th.head_blocked_speed) == (3.0, 0.05)
    with pytest.raises(InputError, match="trap_time"):
        thresholds_for(tmp_path, trap_time=-1.0)


def test_trajectory_frame_round_trip():
    m = 5
    df = pd.DataFrame(
        {
            "t": np.arange(m, dtype=float),
            "x": np.linspace(0, 1, m),
            "y": np.ones(m),
            "theta": np.zeros(m),
            "head_x": np.arange(m, dtype=float),
            "head_y": np.zeros(m),
            "tail_x": -np.arange(m, dtype=float),
            "tail_y": np.zeros(m),
            "head_speed": np.full(m, 2.0),
            "com_speed": np.full(m, 3.0),
            "contact": [False, True, True, False, False],
        }
    )
    tr = trajectory_from_frame(df)
    assert tr.head.shape == (m, 2) and tr.contact.dtype == bool and tr.beads is None
    cols = tr.columns()
    for k in df:
        np.testing.assert_array_equal(cols[k], df[k].to_numpy())


def test_class_counts_adds_up():
    runs = pd.DataFrame(
        {"status": ["ok", "ok", "ok", "failed"], "class": ["Below", "Below", "", ""]}
    )
    c = class_counts(runs).set_index("class")["runs"]
    assert (c["Below"], c["unclassified"], c["failed"], c.sum()) == (2, 1, 1, 4)
