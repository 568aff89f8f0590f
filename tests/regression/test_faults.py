"""Fault injection: kill a sweep's main process (SIGKILL, SIGTERM, SIGINT) or a worker at
random moments; no process may outlive it, and resuming must give the uninterrupted table.

CI runs one kill of each kind; the slow suite (`pytest -m slow`) runs 24 kills at random
moments, start-up included, on one folder. Tables are compared exactly on every physical
column (the simulation is deterministic).
"""

from __future__ import annotations

import json
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import psutil
import pytest

from fibersweep.sweep.lock import LOCK_FILE
from fibersweep.sweep.store import (
    RUNS_DIR,
    VOLATILE_COLUMNS,
    list_parts,
    read_runs,
    read_trajectories,
)

SWEEP = """
sweep:
  theta0: [-8.0, 0.0, 8.0]
  y0: [0.2, 0.33, 0.36, 0.42, 0.6, 0.9]
  length: [0.8, 1.0]
"""
N_RUNS = 36
EXIT = {"SIGKILL": -signal.SIGKILL, "SIGTERM": 143, "SIGINT": 130}


def _config(tmp: Path, cache: Path, name: str) -> Path:
    text = (
        "flow:\n  dx: 4.0\n"
        "fiber:\n  record:\n    trajectories: true\n    samples: 50\n"
        + SWEEP
        + f"run:\n  workers: 2\n  output: {tmp / name}\n  cache_dir: {cache}\n"
        "  flush_every: 4\n  flush_seconds: 1\n"
    )
    p = tmp / f"{name}.yaml"
    p.write_text(text)
    return p


def _default_signals() -> None:
    # A signal ignored in the test process (SIG_IGN) stays ignored across exec, and
    # Python then keeps ignoring SIGINT: start every sweep as a shell would.
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _run(cfg: Path) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "fibersweep.cli", "run", str(cfg)],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        preexec_fn=_default_signals,
    )


def _physics(df: pd.DataFrame) -> pd.DataFrame:
    return df.drop(columns=list(VOLATILE_COLUMNS)).sort_values("id").reset_index(drop=True)


def _pool(proc: subprocess.Popen) -> list[psutil.Process]:
    try:
        return psutil.Process(proc.pid).children(recursive=True)
    except psutil.Error:  # the main process just ended
        return []


def _is_worker(p: psutil.Process) -> bool:
    try:
        return "resource_tracker" not in " ".join(p.cmdline())
    except psutil.Error:  # gone, or a zombie not yet reaped
        return False


def _wait_for_workers(proc: subprocess.Popen, timeout: float = 60.0) -> list[psutil.Process]:
    t0 = time.monotonic()
    while True:
        kids = [p for p in _pool(proc) if _is_worker(p)]
        if kids or proc.poll() is not None:
            return kids
        assert time.monotonic() - t0 < timeout, "no worker started"
        time.sleep(0.05)


def _kill(proc: subprocess.Popen, sig: str, target: str, delay: float) -> tuple[int, int, str]:
    """Signal the main process or a worker after ``delay`` s.

    Returns (exit code, orphans, the run's output).
    """
    workers = _wait_for_workers(proc)
    time.sleep(delay)
    family = _pool(proc) if proc.poll() is None else []
    if proc.poll() is None:
        if target == "worker":
            live = [w for w in workers if w.is_running()]
            if live:
                live[0].send_signal(getattr(signal, sig))
        else:
            proc.send_signal(getattr(signal, sig))
    text, _ = proc.communicate(timeout=180)
    # Every process of the sweep must be gone a few seconds after its main process.
    _, alive = psutil.wait_procs(family, timeout=10)
    for p in alive:
        p.kill()
    return proc.returncode, len(alive), text


@pytest.fixture(scope="module")
def reference(tmp_path_factory, coarse_field, flow_cache_dir):
    tmp = tmp_path_factory.mktemp("faults")
    proc = _run(_config(tmp, flow_cache_dir, "ref"))
    text = proc.communicate(timeout=300)[0]
    assert proc.returncode == 0, text
    return read_runs(tmp / "ref")


def _resume_and_compare(cfg: Path, out: Path, reference: pd.DataFrame) -> None:
    proc = _run(cfg)
    text = proc.communicate(timeout=300)[0]
    assert proc.returncode == 0, text
    final = read_runs(out)
    assert final["id"].is_unique and len(final) == N_RUNS
    pd.testing.assert_frame_equal(_physics(final), _physics(reference))
    traj = read_trajectories(out)
    assert set(traj["id"]) == set(final["id"])
    assert not traj.duplicated(["id", "sample"]).any()
    assert not (out / LOCK_FILE).exists()


@pytest.mark.parametrize(
    "sig, target",
    [("SIGKILL", "main"), ("SIGTERM", "main"), ("SIGINT", "main"), ("SIGKILL", "worker")],
)
def test_kill_then_resume_equals_uninterrupted(reference, tmp_path, flow_cache_dir, sig, target):
    cfg = _config(tmp_path, flow_cache_dir, "k")
    out = tmp_path / "k"
    for _attempt in range(3):
        proc = _run(cfg)
        if target == "main":  # mid-sweep: after the first part
            t0 = time.monotonic()
            while not list_parts(out / RUNS_DIR) and proc.poll() is None:
                assert time.monotonic() - t0 < 120
                time.sleep(0.02)
        code, orphans, text = _kill(proc, sig, target, delay=0.0)
        assert orphans == 0, "processes outlived the sweep"
        if not (target == "main" and code == 0 and f"ran {N_RUNS} runs" in text):
            break
        # The whole sweep finished before the signal landed (a busy machine can
        # stall the first part's write): nothing was interrupted; start over.
        shutil.rmtree(out)
    if target == "main":
        assert code == EXIT[sig], text
        if sig != "SIGKILL":  # clean stop: saved and said so
            man = json.loads((out / "manifest.json").read_text())
            assert man["state"] == "interrupted"
            assert 1 <= man["rows"] < N_RUNS
            assert not (out / LOCK_FILE).exists()
    else:
        assert code == 0, text  # a dead worker is replaced; its runs are re-run
    _resume_and_compare(cfg, out, reference)


@pytest.mark.slow
def test_random_kills_soak(reference, tmp_path, flow_cache_dir):
    """24 kills at random moments (start-up included) on one folder, resumed each time."""
    rng = random.Random(20261123)
    cfg = _config(tmp_path, flow_cache_dir, "soak")
    out = tmp_path / "soak"
    kinds = [("SIGKILL", "main"), ("SIGTERM", "main"), ("SIGINT", "main"), ("SIGKILL", "worker")]
    survived = 0
    for k in range(24):
        if out.exists() and len(read_runs(out)) == N_RUNS:
            # Finished: start over so every kill hits a running sweep.
            for p in [out / "runs", out / "trajectories"]:
                for f in p.glob("*"):
                    f.unlink()
        sig, target = kinds[k % 4]
        code, orphans, text = _kill(_run(cfg), sig, target, delay=rng.uniform(0.0, 4.0))
        assert orphans == 0, f"kill {k} ({sig} {target}): orphans"
        assert code in (EXIT[sig], 0), f"kill {k} ({sig} {target}): exit {code}\n{text}"
        survived += 1
    _resume_and_compare(cfg, out, reference)
    assert survived == 24
