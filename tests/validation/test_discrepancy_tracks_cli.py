"""``synth --tracks``, then ``discrepancy --trajectories`` end to end; the tracks' input errors."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from fibersweep.cli import app
from fibersweep.discrepancy.observables import track_observables
from fibersweep.discrepancy.schema import load_measured
from fibersweep.units import Geometry


@pytest.fixture()
def config(tmp_path, flow_cache_dir, coarse_field):
    # coarse_field makes sure the SPEC field at dx = 4 µm is in the shared test cache
    p = tmp_path / "cfg.yaml"
    p.write_text(
        "sweep:\n"
        "  theta0: {start: -10, stop: 10, num: 3}\n"
        "  y0: {start: 0.15, stop: 0.65, num: 3}\n"
        "  length: {start: 0.5, stop: 1.4, num: 3}\n"
        f"run:\n  cache_dir: {flow_cache_dir}\n  workers: 1\n"
    )
    return p


def test_hidden_friction_with_tracks_end_to_end(tmp_path, config):
    runner = CliRunner()
    m, t = tmp_path / "m.parquet", tmp_path / "t.csv"
    r = runner.invoke(app, ["synth", str(config), "--n", "16", "--seed", "4", "-o", str(m),
                            "--effect", "friction=0.5", "--tracks", str(t)])  # fmt: skip
    assert r.exit_code == 0, r.output
    truth = json.loads((tmp_path / "m.truth.json").read_text())
    assert truth["tracks"] == {"fps": 100.0, "sd_xy_um": 1.0, "sd_theta_deg": 1.5}
    tracks = pd.read_csv(t)
    table = pd.read_parquet(m)
    assert set(tracks["fiber_id"]) == set(table["fiber_id"])
    # frames at 100 per second from t = 0, in the channel frame: they start at x0 = L_ch / 4
    first = tracks.groupby("fiber_id")["x"].first()
    assert np.allclose(first, 600.0, atol=5.0)  # 1 µm frame noise, 5 sd
    data = load_measured(m, t, geometry=Geometry())
    assert set(track_observables()) <= set(data.observed)
    # the synthetic tables without tracks are those synth writes without --tracks
    m2 = tmp_path / "m2.parquet"
    r = runner.invoke(app, ["synth", str(config), "--n", "16", "--seed", "4", "-o", str(m2),
                            "--effect", "friction=0.5"])  # fmt: skip
    assert r.exit_code == 0, r.output
    pd.testing.assert_frame_equal(pd.read_parquet(m2), table)

    out = tmp_path / "report"
    r = runner.invoke(app, ["discrepancy", str(m), str(config), "--trajectories", str(t),
                            "-o", str(out), "--copies", "2", "--no-power", "--no-next",
                            "--effect", "friction"])  # fmt: skip
    assert r.exit_code == 0, r.output
    s = json.loads((out / "summary.json").read_text())
    for name in track_observables():
        assert name in s["observables"]
    assert "t_transit" in (out / "report.md").read_text()


def test_tracks_for_only_some_fibers_exit_2_naming_the_field(tmp_path, config):
    runner = CliRunner()
    m, t = tmp_path / "m.csv", tmp_path / "t.csv"
    r = runner.invoke(app, ["synth", str(config), "--n", "8", "--seed", "2", "-o", str(m),
                            "--tracks", str(t)])  # fmt: skip
    assert r.exit_code == 0, r.output
    tracks = pd.read_csv(t)
    first = tracks["fiber_id"].iloc[0]
    tracks[tracks["fiber_id"] == first].to_csv(t, index=False)
    r = runner.invoke(app, ["discrepancy", str(m), str(config), "--trajectories", str(t),
                            "-o", str(tmp_path / "r")])  # fmt: skip
    assert r.exit_code == 2 and "trajectories.fiber_id: no track for" in r.output
    r = runner.invoke(app, ["synth", str(config), "--n", "8", "-o", str(m), "--tracks", "t.txt"])
    assert r.exit_code == 2 and "--tracks" in r.output
