"""End to end through the CLI on a tiny sweep (SPEC geometry, dx = 4 µm field from the shared
test cache): run, resume, interrupt (SIGINT) and worker crash (SIGKILL), Dask, classify
round trip, plots, config changes, failures and bad configs with their exit codes.

Equality of tables is exact on every physical column: the fiber simulation is deterministic,
so an interrupted-then-resumed sweep, or one run on Dask, must give bit-identical rows.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import psutil
import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from fibersweep.cli import app
from fibersweep.sweep.store import (
    RUNS_DIR,
    VOLATILE_COLUMNS,
    list_parts,
    read_runs,
    read_trajectories,
)

# Points around the separatrix (y/h ~ 0.32 on this grid, sub-grid pillar) plus far ones: all
# four classes appear on this grid (trapping at theta0 = 8, y0 = 0.30 and -8, 0.33;
# pole-vaulting at -8, 0.39).
SWEEP = """
sweep:
  theta0: [-8.0, 0.0, 8.0]
  y0: [0.2, 0.30, 0.33, 0.39, 0.6, 0.9]
  length: [1.0]
"""
# Columns that depend on when/where a run happened, not on its physics.

runner = CliRunner()


def _config(tmp: Path, cache: Path, name: str, extra: str = "", sweep: str = SWEEP) -> Path:
    text = (
        "flow:\n  dx: 4.0\n"
        "fiber:\n  record:\n    trajectories: true\n    samples: 100\n"
        + extra
        + sweep
        + f"run:\n  workers: 2\n  output: {tmp / name}\n  cache_dir: {cache}\n  flush_every: 1\n"
    )
    p = tmp / f"{name}.yaml"
    p.write_text(text)
    return p


def _physics(df: pd.DataFrame) -> pd.DataFrame:
    return df.drop(columns=list(VOLATILE_COLUMNS)).sort_values("id").reset_index(drop=True)


def _invoke(*args: str):
    res = runner.invoke(app, [str(a) for a in args])
    return res, res.output + (res.stderr if res.stderr_bytes is not None else "")


@pytest.fixture(scope="module")
def reference(tmp_path_factory, coarse_field, flow_cache_dir):
    """One uninterrupted local sweep: (config path, output dir, runs table)."""
    tmp = tmp_path_factory.mktemp("sweep")
    cfg = _config(tmp, flow_cache_dir, "ref")
    res, out = _invoke("run", cfg)
    assert res.exit_code == 0, out
    return cfg, tmp / "ref", read_runs(tmp / "ref")


def test_run_writes_complete_table_and_provenance(reference):
    _, out, df = reference
    assert len(df) == 18 and df["id"].is_unique
    assert (df["status"] == "ok").all(), df[["id", "reason"]]
    assert set(df["class"]) == {"Below", "Above", "Pole-vaulting", "Trapping"}
    man = json.loads((out / "manifest.json").read_text())
    assert man["state"] == "complete" and man["rows"] == 18
    prov = man["provenance"]
    assert prov["flow_key"] and prov["fibersweep"] and "numpy" in prov["libraries"]
    assert "git" in prov
    assert 0.25 < man["separatrix"] < 0.45, man["separatrix"]  # SPEC: ~1/3, 0.36 coarse BGK
    assert man["config"]["sweep"]["y0"] == [0.2, 0.30, 0.33, 0.39, 0.6, 0.9]
    meta = json.loads(pq.read_schema(list_parts(out / RUNS_DIR)[0]).metadata[b"fibersweep"])
    assert meta["flow_key"] == prov["flow_key"]
    traj = read_trajectories(out)
    assert set(traj["id"]) == set(df["id"])


def test_resume_does_nothing_and_dry_run_reports(reference):
    cfg, out, df = reference
    res, text = _invoke("run", cfg)
    assert res.exit_code == 0, text
    assert "to do now 0" in text
    pd.testing.assert_frame_equal(read_runs(out), df)
    res, text = _invoke("run", cfg, "--dry-run")
    assert res.exit_code == 0 and "done 18 ok, 0 failed; to do now 0" in text, text


def _wait_for_parts(out: Path, n: int, proc: subprocess.Popen, timeout: float = 120.0) -> None:
    t0 = time.monotonic()
    while len(list_parts(out / RUNS_DIR)) < n:
        assert proc.poll() is None, "the sweep ended before it could be interrupted"
        assert time.monotonic() - t0 < timeout, "no parts written"
        time.sleep(0.02)


def _cli(cfg: Path, *args: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "fibersweep.cli", "run", str(cfg), *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )


def test_ctrl_c_then_resume_equals_uninterrupted(reference, tmp_path, flow_cache_dir):
    cfg = _config(tmp_path, flow_cache_dir, "int")
    out = tmp_path / "int"
    proc = _cli(cfg)
    _wait_for_parts(out, 2, proc)
    proc.send_signal(signal.SIGINT)
    text = proc.communicate(timeout=60)[0]
    assert proc.returncode == 130, text
    partial = read_runs(out)
    assert 2 <= len(partial) < 18, "interrupted mid-sweep"
    assert json.loads((out / "manifest.json").read_text())["state"] == "interrupted"
    res, text = _invoke("run", cfg)
    assert res.exit_code == 0, text
    assert f"to do now {18 - len(partial)}" in text
    final = read_runs(out)
    assert final["id"].is_unique
    pd.testing.assert_frame_equal(_physics(final), _physics(reference[2]))


def test_worker_killed_mid_sweep_loses_nothing(reference, tmp_path, flow_cache_dir):
    cfg = _config(tmp_path, flow_cache_dir, "kill")
    out = tmp_path / "kill"
    proc = _cli(cfg)
    _wait_for_parts(out, 1, proc)
    workers = psutil.Process(proc.pid).children(recursive=True)
    pool = [w for w in workers if "resource_tracker" not in " ".join(w.cmdline())]
    assert pool, "no worker processes found"
    os.kill(pool[0].pid, signal.SIGKILL)
    text = proc.communicate(timeout=120)[0]
    assert proc.returncode == 0, text
    final = read_runs(out)
    assert len(final) == 18 and final["id"].is_unique
    assert (final["status"] == "ok").all(), final[["reason"]]
    assert final["attempts"].max() >= 2, "the killed worker's task was re-run"
    pd.testing.assert_frame_equal(_physics(final), _physics(reference[2]))


def test_dask_executor_gives_the_same_table(reference, tmp_path, flow_cache_dir):
    pytest.importorskip("distributed")
    cfg = _config(tmp_path, flow_cache_dir, "dask")
    res, text = _invoke("run", cfg, "--executor", "dask", "--workers", "2")
    assert res.exit_code == 0, text
    final = read_runs(tmp_path / "dask")
    pd.testing.assert_frame_equal(_physics(final), _physics(reference[2]))


def test_dask_worker_killed_mid_sweep_loses_nothing(reference, tmp_path, flow_cache_dir):
    pytest.importorskip("distributed")
    cfg = _config(tmp_path, flow_cache_dir, "dkill")
    out = tmp_path / "dkill"
    proc = _cli(cfg, "--executor", "dask")
    _wait_for_parts(out, 1, proc)
    workers = [
        w
        for w in psutil.Process(proc.pid).children(recursive=True)
        if "resource_tracker" not in " ".join(w.cmdline())
    ]
    assert workers, "no Dask worker processes found"
    os.kill(workers[0].pid, signal.SIGKILL)
    text = proc.communicate(timeout=180)[0]
    assert proc.returncode == 0, text
    final = read_runs(out)
    assert len(final) == 18 and final["id"].is_unique
    pd.testing.assert_frame_equal(_physics(final), _physics(reference[2]))


def test_classify_round_trip_and_plots(reference, tmp_path):
    import shutil

    out = tmp_path / "copy"
    shutil.copytree(reference[1], out)
    before = read_runs(out)
    # A trapping time longer than any run: no run is 'Trapping' any more.
    res, text = _invoke("classify", out, "--trap-time", "1000")
    assert res.exit_code == 0, text
    mid = read_runs(out)
    trapped = before["class"] == "Trapping"
    assert trapped.any() and not (mid["class"] == "Trapping").any()
    assert (mid.loc[~trapped, "class"] == before.loc[~trapped, "class"]).all()
    counts = pd.read_csv(out / "counts.csv")
    assert counts.set_index("class").loc["Trapping", "runs"] == 0
    # The runs stopped after the simulated 2 s trap window: the user is told why the
    # trapped runs are now unclassified and how to decide them.
    assert "warning: the runs were simulated with the trap stop rule trap_time = 2.0" in text
    assert "--no-resume" in text
    # Thresholds from a config file give the same answer as from the command line.
    thr = tmp_path / "thr.yaml"
    thr.write_text("fiber:\n  classify:\n    trap_time: 1000.0\n")
    res, text = _invoke("classify", out, "--config", thr)
    assert res.exit_code == 0 and "(0 changed)" in text, text
    res, text = _invoke("classify", out, "--trap-time", "2.0")
    assert res.exit_code == 0 and "warning" not in text, text
    after = read_runs(out)
    assert (after["class"] == before["class"]).all(), "same thresholds, same classes"
    assert len(list_parts(out / RUNS_DIR)) == 1

    res, text = _invoke("plot-phase", out, "--format", "png")
    assert res.exit_code == 0, text
    figs = sorted((out / "figures").glob("*.png"))
    assert [f.name for f in figs] == [
        "contact_map.png",
        "delta_hist.png",
        "phase.png",
        "phase_delta.png",
    ]
    for f in figs:
        assert f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and f.stat().st_size > 20_000
    res, text = _invoke("plot-phase", out, "--format", "svgz")
    assert res.exit_code == 2 and "'svgz' is not one of 'png', 'pdf', 'svg'" in text, text


def test_changed_settings_are_detected(reference, tmp_path):
    cfg, out, _ = reference
    changed = tmp_path / "changed.yaml"
    changed.write_text(cfg.read_text().replace("fiber:\n", "fiber:\n  contact:\n    chi: 1.2\n", 1))
    res, text = _invoke("run", changed, "--dry-run")
    assert res.exit_code == 2, text
    assert "fiber.contact.chi: 1.1 -> 1.2" in text
    assert "18 of the 18 stored runs" in text and "--no-resume" in text
    # --no-resume starts over on a copy, moving the old results aside (nothing deleted).
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(out, copy)
    res, text = _invoke("run", changed, "--no-resume", "-o", copy, "--workers", "1")
    assert res.exit_code == 0, text
    old = list(copy.glob("previous-*"))
    assert len(old) == 1 and read_runs(old[0]).equals(read_runs(out))
    new = read_runs(copy)
    assert len(new) == 18 and not set(new["id"]) & set(reference[2]["id"])
    # Classification thresholds do not change runs: only a note.
    thr = tmp_path / "thr.yaml"
    thr.write_text(
        cfg.read_text().replace("fiber:\n", "fiber:\n  classify:\n    trap_time: 3.0\n", 1)
    )
    res, text = _invoke("run", thr, "--dry-run")
    assert res.exit_code == 0 and "fibersweep classify" in text, text


def test_failed_runs_are_recorded_and_retried(tmp_path, coarse_field, flow_cache_dir):
    # A start that only fails at run time (bad starts are config errors, exit 2): with
    # trap_time beyond t_max the fiber trapped at (8°, 0.3) runs out of time ('time
    # limit'), while the one at y0/h = 0.9 passes Above. The failure must be recorded
    # and the sweep go on; --retry-failed re-runs only that run, without duplicates.
    extra = "  classify:\n    trap_time: 100.0\n  step:\n    t_max: 5.0\n"
    sweep = "sweep:\n  theta0: [8.0]\n  y0: [0.3, 0.9]\n  length: [1.0]\n"
    cfg = _config(tmp_path, flow_cache_dir, "fail", extra=extra, sweep=sweep)
    res, text = _invoke("run", cfg)
    assert res.exit_code == 1, text
    df = read_runs(tmp_path / "fail")
    bad = df[df["status"] == "failed"]
    assert len(df) == 2 and len(bad) == 1 and bad["y0"].iloc[0] == 0.3
    assert "time limit" in bad["reason"].iloc[0]
    assert (df[df["status"] == "ok"]["class"] == "Above").all()
    res, text = _invoke("run", cfg, "--retry-failed")
    assert res.exit_code == 1 and "to do now 1" in text, text
    assert len(read_runs(tmp_path / "fail")) == 2


def test_bad_config_and_arguments_exit_2(tmp_path):
    p = tmp_path / "bad.yaml"
    p.write_text("sweep:\n  theta0: [0]\n  yo: 0.3\nrun:\n  workers: -1\n")
    res, text = _invoke("run", p)
    assert res.exit_code == 2
    assert "sweep.yo (line 3): unknown key; did you mean 'y0'?" in text
    assert "run.workers (line 5)" in text
    ok = tmp_path / "ok.yaml"
    ok.write_text("sweep:\n  theta0: [0]\n")
    res, text = _invoke("run", ok, "--workers", "0")
    assert res.exit_code == 2 and "run.workers" in text, text
    res, text = _invoke("run", ok, "--executor", "slurm")
    assert res.exit_code == 2 and "'slurm' is not one of 'local', 'dask'" in text, text
    res, text = _invoke("run", tmp_path / "nope.yaml")
    assert res.exit_code == 2 and "cannot read config" in text


def test_classify_uses_the_speed_the_runs_moved_in(
    tmp_path, coarse_field, flow_cache_dir, monkeypatch
):
    """With inlet_speed the runs move in a slower flow; classify must judge them with the
    U_center the runs used (thresholds are fractions of it), not the nominal speed."""
    import fibersweep.analysis.classify as classify_module
    from fibersweep.config.fiber import ClassifySettings
    from fibersweep.sweep.reclassify import reclassify

    cfg = _config(tmp_path, flow_cache_dir, "slow", extra="  effects:\n    inlet_speed: -0.8\n")
    res, text = _invoke("run", cfg)
    assert res.exit_code == 0, text
    out = tmp_path / "slow"
    man = json.loads((out / "manifest.json").read_text())
    nominal = man["config"]["flow"]["fluid"]["u_center"]
    assert man["u_center_effective"] == pytest.approx(0.2 * nominal, rel=1e-12)
    seen = []
    real = classify_module.classify

    def spy(traj, geometry, u_center, thresholds, rule=None):
        seen.append(u_center)
        return real(traj, geometry, u_center, thresholds, rule)

    monkeypatch.setattr(classify_module, "classify", spy)
    before = read_runs(out)
    r = reclassify(out, ClassifySettings())
    assert r.n_changed == 0 and (read_runs(out)["class"] == before["class"]).all()
    # every run, under every rule, judged with the effective speed
    from fibersweep.analysis.classify import RULES
    from fibersweep.sweep.reclassify import rule_column

    assert len(seen) == len(RULES) * len(before) and set(seen) == {man["u_center_effective"]}
    after = read_runs(out)  # one class column per rule, 'class' the default rule's
    assert (after["class"] == after[rule_column("switch")]).all()
    assert {rule_column(r) for r in RULES} <= set(after.columns)
    res, text = _invoke("classify", out, "--rule", "head-speed")
    assert res.exit_code == 0 and "rule='head-speed'" in text, text
    assert (read_runs(out)["class"] == after[rule_column("head-speed")]).all()


def test_run_with_overrides_records_them(tmp_path, coarse_field, flow_cache_dir):
    cfg = _config(tmp_path, flow_cache_dir, "ov")
    res, text = _invoke("run", cfg, "sweep.y0=[0.9]", "sweep.theta0=0", "fiber.contact.chi=1.2")
    assert res.exit_code == 0, text
    man = json.loads((tmp_path / "ov" / "manifest.json").read_text())
    assert man["overrides"] == ["sweep.y0=[0.9]", "sweep.theta0=0", "fiber.contact.chi=1.2"]
    assert man["config"]["fiber"]["contact"]["chi"] == 1.2
    assert len(read_runs(tmp_path / "ov")) == 1
    res, text = _invoke("run", cfg, "fiber.contact.chii=1.2")
    assert res.exit_code == 2 and "(override fiber.contact.chii=1.2): unknown key" in text


def test_parquet_fields_carry_units_and_the_config(reference):
    """A runs part read outside fibersweep says what each column holds and how it was made."""
    _, out, _ = reference
    part = list_parts(out / RUNS_DIR)[0]
    schema = pq.read_schema(part)
    assert schema.field("y0").metadata == {
        b"unit": b"h_obs",
        b"doc": b"start lateral position of the centre of mass, from the pillar base line",
    }
    assert schema.field("y_f").metadata[b"unit"] == "µm".encode()
    meta = json.loads(schema.metadata[b"fibersweep"])
    assert meta["config"]["flow"]["dx"] == 4.0 and meta["overrides"] == []


def test_scheduler_alone_implies_dask(tmp_path, coarse_field, flow_cache_dir):
    """--scheduler without --executor selects Dask (a dry run connects to nothing)."""
    cfg = _config(tmp_path, flow_cache_dir, "sched")
    res, text = _invoke("run", cfg, "--scheduler", "tcp://127.0.0.1:9", "--dry-run")
    assert res.exit_code == 0, text
    res, text = _invoke("run", cfg, "--executor", "slurm", "--dry-run")
    assert res.exit_code == 2 and "'slurm' is not one of 'local', 'dask'" in text, text
