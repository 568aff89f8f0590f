"""run-array then sort-report on a tiny sweep with an array setting as an axis."""

from __future__ import annotations

import json

import pandas as pd
import pytest
from typer.testing import CliRunner

from fibersweep.cli import app


@pytest.mark.slow  # two fields, eight runs, the figures: ~40 s of CPU
def test_run_array_and_sort_report_with_a_shift_axis(tmp_path):
    out = tmp_path / "res"
    args = [
        "run-array",
        "configs/array.yaml",
        "flow.dx=4",
        "sweep.length=[12, 60]",
        "sweep.starts=2",
        "sweep.rows=3",
        "sweep.axes={shift: [0.1, 0.2]}",
        f"run.output={out}",
        f"run.cache_dir={tmp_path / 'cache'}",
        "--workers",
        "1",
    ]
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 0, res.output
    runs = pd.read_parquet(out / "runs.parquet")
    assert len(runs) == 2 * 2 * 2  # settings x lengths x starts
    assert set(runs["setting_label"]) == {"shift=0.1", "shift=0.2"}
    meta = json.loads((out / "array.json").read_text())
    assert [s["array"]["shift"] for s in meta["settings"]] == [0.1, 0.2]
    # the same config draws the same starts (seeded)
    again = CliRunner().invoke(app, [*args[:-2], "--workers", "1", f"run.output={out}2"])
    assert again.exit_code == 0, again.output
    runs2 = pd.read_parquet(out.parent / "res2" / "runs.parquet")
    assert runs2[["y0", "theta0"]].equals(runs[["y0", "theta0"]])
    rep = CliRunner().invoke(app, ["sort-report", str(out), "--outlets", "0.3,0.7"])
    assert rep.exit_code == 0, rep.output
    assert "critical length" in rep.output
    outlets = pd.read_csv(out / "outlets.csv")
    assert set(outlets["outlet"]) == {0, 1, 2}
    for name in ("cell-flow-0.png", "cell-flow-1.png", "chrono-0.png", "migration.png"):
        assert (out / name).stat().st_size > 1000
