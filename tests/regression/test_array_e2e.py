"""An array sweep on the one run path: ``fibersweep run`` (array setting as an axis,
random starts, resume), ``classify`` and ``sort-report`` on the standard store."""

from __future__ import annotations

import pandas as pd
import pytest
from typer.testing import CliRunner

from fibersweep.cli import app
from fibersweep.sweep.manifest import read_manifest
from fibersweep.sweep.store import read_runs, read_trajectories


@pytest.mark.slow  # two cell fields, eight runs, the figures: ~40 s of CPU
def test_run_classify_and_sort_report_with_a_shift_axis(tmp_path):
    out = tmp_path / "res"
    args = [
        "run",
        "configs/array.yaml",
        "flow.dx=4",
        "sweep.length=[12, 60]",
        "sweep.random={count: 2, seed: 0}",
        "fiber.array_rows=3",
        "sweep.flow.array.shift=[0.1, 0.2]",
        "run.workers=1",
        f"run.cache_dir={tmp_path / 'cache'}",
    ]
    res = CliRunner().invoke(app, [*args, f"run.output={out}"])
    assert res.exit_code == 0, res.output
    runs = read_runs(out)
    assert len(runs) == 2 * 2 * 2  # settings x lengths x starts
    assert set(runs["flow.array.shift"]) == {0.1, 0.2}
    assert runs["mode"].notna().all() and (runs["rows"] >= 3).all()
    assert runs["class"].eq("").all()  # the channel's classes do not apply
    assert set(read_trajectories(out)["id"]) == set(runs["id"])  # always kept
    man = read_manifest(out)
    assert sorted(e["flow"]["array"]["shift"] for e in man["combinations"].values()) == [0.1, 0.2]
    # `fibersweep flow` reports the cached unit cells, no separatrix
    fl = CliRunner().invoke(app, ["flow", *args[1:]])
    assert fl.exit_code == 0, fl.output
    assert fl.output.count("cache: hit") == 2 and "unit cell of the pillar array" in fl.output
    # resume: nothing left to run
    again = CliRunner().invoke(app, [*args, f"run.output={out}"])
    assert again.exit_code == 0 and "nothing to run" in again.output, again.output
    # the same config draws the same starts (seeded), so the same run ids
    other = CliRunner().invoke(app, [*args, f"run.output={out}2"])
    assert other.exit_code == 0, other.output
    runs2 = read_runs(tmp_path / "res2")
    pd.testing.assert_frame_equal(
        runs2[["id", "y0", "theta0", "length"]], runs[["id", "y0", "theta0", "length"]]
    )
    # classify re-derives the same modes from the stored trajectories
    cls = CliRunner().invoke(app, ["classify", str(out)])
    assert cls.exit_code == 0, cls.output
    assert "(0 changed)" in cls.output
    rep = CliRunner().invoke(app, ["sort-report", str(out), "--outlets", "0.3,0.7"])
    assert rep.exit_code == 0, rep.output
    assert "critical length" in rep.output
    outlets = pd.read_csv(out / "outlets.csv")
    assert set(outlets["outlet"]) == {0, 1, 2}
    figs = out / "figures"
    for name in ("cell-flow-shift=0.1.png", "cell-flow-shift=0.2.png", "migration.png",
                 "outlets.png", "critical-shift.png"):  # fmt: skip
        assert (figs / name).stat().st_size > 1000
    assert list(figs.glob("chrono-*.png"))
