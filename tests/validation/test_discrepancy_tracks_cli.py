"""``synth --tracks``, then ``discrepancy --trajectories`` end to end; the tracks' input errors."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
from typer.testing import CliRunner

from fibersweep.cli import app
from fibersweep.discrepancy.observables import track_observables


def test_synth_tracks_then_discrepancy_with_trajectories(tmp_path, config):
    runner = CliRunner()
    m, t = tmp_path / "m.parquet", tmp_path / "t.csv"
    r = runner.invoke(app, ["synth", str(config), "--n", "12", "--seed", "4", "-o", str(m),
                            "--tracks", str(t)])  # fmt: skip
    assert r.exit_code == 0, r.output
    truth = json.loads((tmp_path / "m.truth.json").read_text())
    assert truth["tracks"] == {"fps": 100.0, "sd_xy_um": 1.0, "sd_theta_deg": 1.5}
    tracks = pd.read_csv(t)
    table = pd.read_parquet(m)
    assert set(tracks["fiber_id"]) == set(table["fiber_id"])
    # frames at 100 per second from t = 0, in the channel frame: they start at x0 = L_ch / 4
    assert np.allclose(tracks.groupby("fiber_id")["x"].first(), 600.0, atol=5.0)  # 5 sd
    assert np.allclose(tracks.groupby("fiber_id")["t"].diff().dropna(), 0.01)
    # the fibers table is the one synth writes without --tracks (tracks use their own stream)
    m2 = tmp_path / "m2.parquet"
    r = runner.invoke(app, ["synth", str(config), "--n", "12", "--seed", "4", "-o", str(m2)])
    assert r.exit_code == 0, r.output
    pd.testing.assert_frame_equal(pd.read_parquet(m2), table)

    out = tmp_path / "report"
    r = runner.invoke(app, ["discrepancy", str(m), str(config), "--trajectories", str(t),
                            "-o", str(out), "--copies", "2", "--no-power"])  # fmt: skip
    assert r.exit_code == 0, r.output
    s = json.loads((out / "summary.json").read_text())
    assert s["observables"][-3:] == list(track_observables())
    assert s["verdict"]["kind"] == "no significant gap"
    assert "t_transit" in (out / "report.md").read_text()


def test_hidden_effect_with_tracks_runs_the_whole_workflow(tmp_path, coarse_field):
    """A small hidden-effect data set with tracks through gap, signatures and fit (reduced).

    The hidden effect is one every fiber's track shows: a 10 % faster flow shortens the
    transit past the pillar by about 9 % against 1 % timing noise, so t_transit's gap
    test sits at the smallest p its permutations can give on every seed tried (Holm
    0.024 with 999 permutations on seeds 1-3). (Friction 1.0, which acts only on the
    fibers that touch the pillar, put t_transit's Holm p at 0.024, 0.50, 0.044, 0.040
    and 0.56 on seeds 1, 2, 3, 5, 6: a verdict within its own noise of 0.05.) With 4999
    permutations that floor lies ten times below alpha."""
    from fibersweep.config.fiber import FiberSettings
    from fibersweep.discrepancy.measured import validate_trajectories, with_tracks
    from fibersweep.discrepancy.schema import validate_measured
    from fibersweep.discrepancy.synth import STUDY_BOX, synthesize_with_tracks
    from fibersweep.discrepancy.workflow import DiscrepancySettings, run_discrepancy

    table, tracks, _ = synthesize_with_tracks(
        coarse_field, FiberSettings(), STUDY_BOX, 16, {"inlet_speed": 0.1}, seed=1, workers=1,
        progress=False, fps=100.0,
    )  # fmt: skip
    data = validate_measured(table)
    data = with_tracks(data, validate_trajectories(tracks, data.table, "t"), coarse_field.geometry)
    settings = DiscrepancySettings(
        copies=2, fit_copies=2, candidates=1, fit_evals=3, refits=1, pairs=0, power_fibers=0,
        next_copies=0, workers=1, seed=1, effects=("friction", "inlet_speed"), n_perm=4999,
    )  # fmt: skip
    res = run_discrepancy(data, coarse_field, FiberSettings(), settings, progress=False)
    for name in track_observables():
        assert name in res.gap.gaps and res.gap.gaps[name].test.n > 0
    assert "t_transit" in res.gap.flagged, res.gap.flagged  # the track shows the faster flow
    assert set(res.verdict.effects) <= {"inlet_speed"}  # never the wrong name


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
