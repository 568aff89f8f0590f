"""Nothing lost, nothing silent: locks, unreadable parts, failed writes, timed flushes, configs.

Each test asserts the exact message a user sees, since the message is the feature.
"""

from __future__ import annotations

import errno
import json
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from fibersweep.config import ConfigError, load_config
from fibersweep.config.fiber import ClassifySettings
from fibersweep.errors import ResultsError
from fibersweep.sweep import store
from fibersweep.sweep.check import check_folder
from fibersweep.sweep.lock import LOCK_FILE, FolderLocked, lock_holder, output_lock
from fibersweep.sweep.reclassify import reclassify
from fibersweep.sweep.starts import PHYSICS, grid_starts
from fibersweep.sweep.store import (
    RUNS_DIR,
    TRAJ_DIR,
    PartWriter,
    list_parts,
    read_runs,
    read_trajectories,
    unreadable_parts,
)


def _row(i: int) -> dict:
    return {"id": f"r{i:03d}", "status": "ok", "class": "Below", "theta0": 0.0,
            "y0": 0.1 + 0.01 * i, "length": 1.0, "delta": 0.0}  # fmt: skip


def _traj(n: int = 5) -> dict:
    t = [0.1 * k for k in range(n)]
    return {"t": t, "x": t, "y": t, "theta": t}


def _folder(tmp_path: Path, parts: int = 3, per: int = 4) -> Path:
    """An output folder with ``parts`` runs parts (and trajectories) and a manifest."""
    out = tmp_path / "out"
    w = PartWriter(out, flush_every=per)
    for i in range(parts * per):
        w.add(_row(i), {k: pd.Series(v).to_numpy() for k, v in _traj().items()})
    w.close()
    man = {"state": "complete", "config": {"fiber": {"record": {"trajectories": True}}}}
    (out / "manifest.json").write_text(json.dumps(man))
    return out


def _truncate(p: Path) -> None:
    data = p.read_bytes()
    p.write_bytes(data[: len(data) // 2])


# ----------------------------------------------------------------------------- locks


def test_second_writer_is_refused_naming_the_holder(tmp_path):
    with output_lock(tmp_path / "o", "run"):
        with pytest.raises(FolderLocked) as exc:
            with output_lock(tmp_path / "o", "classify"):
                pass
    host = socket.gethostname()
    assert str(exc.value).startswith(
        f"{tmp_path / 'o'} is in use by `fibersweep run` (PID {os.getpid()} on {host}, since "
    )
    assert "wait for it to finish or stop it, or write to another folder (-o)." in str(exc.value)
    assert not (tmp_path / "o" / LOCK_FILE).exists(), "released on exit"


def test_stale_lock_of_a_dead_process_is_taken_over(tmp_path):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()  # its PID is now free (not reused this quickly)
    out = tmp_path / "o"
    out.mkdir()
    stale = {"host": socket.gethostname(), "pid": dead.pid, "command": "run", "started": "x"}
    (out / LOCK_FILE).write_text(json.dumps(stale))
    with output_lock(out, "run") as me:
        assert lock_holder(out) == me


def test_lock_of_another_host_says_what_to_remove(tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    other = {"host": "node-17", "pid": 1, "command": "run", "started": "x"}
    (out / LOCK_FILE).write_text(json.dumps(other))
    with pytest.raises(FolderLocked, match=r"PID 1 on node-17.*if that process is gone, remove"):
        with output_lock(out, "run"):
            pass
    assert (out / LOCK_FILE).exists(), "never removed from here"


# ----------------------------------------------------------------------------- unreadable


def test_unreadable_runs_part_is_an_error_naming_it_and_nothing_is_deleted(tmp_path):
    out = _folder(tmp_path)
    broken = list_parts(out / RUNS_DIR)[1]
    _truncate(broken)
    before = sorted(p.name for p in (out / RUNS_DIR).iterdir())
    with pytest.raises(ResultsError, match=rf"^{broken}: unreadable result part"):
        read_runs(out)
    with pytest.raises(ResultsError, match=rf"^{broken}: unreadable result part"):
        reclassify(out, ClassifySettings())
    assert sorted(p.name for p in (out / RUNS_DIR).iterdir()) == before


def test_single_merged_part_truncated_is_not_an_empty_folder(tmp_path):
    out = _folder(tmp_path, parts=1)
    _truncate(list_parts(out / RUNS_DIR)[0])
    with pytest.raises(ResultsError, match="unreadable result part"):
        reclassify(out, ClassifySettings())


def test_unreadable_trajectory_part_is_an_error(tmp_path):
    out = _folder(tmp_path)
    broken = list_parts(out / TRAJ_DIR)[0]
    _truncate(broken)
    with pytest.raises(ResultsError, match=rf"^{broken}: unreadable"):
        read_trajectories(out)
    assert [p for p, _ in unreadable_parts(out)] == [broken]


def test_check_reports_unreadable_parts_and_missing_trajectories(tmp_path):
    out = _folder(tmp_path)
    assert check_folder(out).healthy
    broken = list_parts(out / TRAJ_DIR)[0]
    _truncate(broken)
    rep = check_folder(out)
    assert not rep.healthy
    assert rep.rows == 12 and rep.missing_trajectories == 4
    text = "\n".join(rep.lines())
    assert f"UNREADABLE {broken}: " in text and text.count(str(broken)) == 1
    assert "MISSING the trajectory of 4 ok run(s)" in text and text.endswith("NOT ok")
    assert "  repair: `fibersweep run CONFIG -o " in text  # no command line recorded here


# ----------------------------------------------------------------------------- writes


def test_failed_write_keeps_runs_and_retries(tmp_path, monkeypatch):
    real = store.write_table_atomic
    fails = {"n": 3}

    def flaky(table, path):
        if fails["n"] > 0:
            fails["n"] -= 1
            raise OSError(errno.ENOSPC, "No space left on device", str(path))
        return real(table, path)

    monkeypatch.setattr(store, "write_table_atomic", flaky)
    w = PartWriter(tmp_path / "o", flush_every=2)
    for i in range(4):
        w.add(_row(i), None)
    assert w.pending == 4 and isinstance(w.error, OSError)  # three failed flushes, all kept
    w.close()  # the disk has room again
    assert sorted(read_runs(tmp_path / "o")["id"]) == [f"r{i:03d}" for i in range(4)]


def test_persistent_write_failure_is_reported_with_the_count(tmp_path, monkeypatch):
    def full(table, path):
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(store, "write_table_atomic", full)
    w = PartWriter(tmp_path / "o", flush_every=10)
    for i in range(3):
        w.add(_row(i), None)
    with pytest.raises(ResultsError) as exc:
        w.close()
    assert str(exc.value).startswith(f"3 finished runs could not be saved in {tmp_path / 'o'}: ")
    assert "No space left on device" in str(exc.value)


def test_a_finished_run_is_written_within_flush_seconds_without_new_runs(tmp_path):
    w = PartWriter(tmp_path / "o", flush_every=100, flush_seconds=0.3)
    w.start_timer()
    w.add(_row(0), None)
    t0 = time.monotonic()
    while not list_parts(tmp_path / "o" / RUNS_DIR):
        assert time.monotonic() - t0 < 3.0, "the timer never flushed"
        time.sleep(0.05)
    w.close()
    assert len(read_runs(tmp_path / "o")) == 1


# ----------------------------------------------------------------------------- config


def _cfg(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "c.yaml"
    p.write_text(text)
    return p


def test_duplicate_yaml_key_names_both_lines(tmp_path):
    with pytest.raises(ConfigError) as exc:
        load_config(_cfg(tmp_path, "flow:\n  dx: 4\n  dx: 2\n"))
    assert exc.value.problems == ["flow.dx: key written twice (lines 2 and 3); keep one"]


@pytest.mark.parametrize("text", ["sweep:\n  y0: 3e-1\n", "sweep:\n  y0: [3e-1]\n"])
def test_exponent_numbers_are_numbers_alone_or_in_lists(tmp_path, text):
    assert grid_starts(load_config(_cfg(tmp_path, text)).sweep)[0].y0 == pytest.approx(0.3)


def test_booleans_are_not_numbers_in_axes(tmp_path):
    with pytest.raises(ConfigError) as exc:
        load_config(_cfg(tmp_path, "sweep:\n  theta0: [0, true]\n"))
    assert exc.value.problems == [
        "sweep.theta0.1 (line 2): Input should be a valid number; given True"
    ]


def test_non_finite_and_non_positive_values_at_the_axis_line(tmp_path):
    text = "sweep:\n  y0: 0.9\n  theta0: [0, .nan]\n  length: [1, -0.5, 0]\n"
    with pytest.raises(ConfigError) as exc:
        load_config(_cfg(tmp_path, text))
    assert exc.value.problems == [
        "sweep.theta0 (line 3): values must be finite; got nan; given [0, nan]",
        "sweep.length (line 4): lengths must be positive; got -0.5, 0; given [1, -0.5, 0]",
    ]


def test_huge_sweep_is_refused_at_once_with_its_count(tmp_path, monkeypatch):
    from fibersweep.config import SweepSettings

    def never(self):
        raise AssertionError("the points were listed")

    monkeypatch.setattr(SweepSettings, "grid", never)  # counted, never listed
    monkeypatch.setattr("fibersweep.sweep.starts.grid_starts", never)
    text = (
        "sweep:\n  y0: {start: 0.6, stop: 0.9, num: 1000}\n"
        "  theta0: {start: -10, stop: 10, num: 1000}\n  length: [1, 1.2, 1.4]\n"
    )
    with pytest.raises(
        ConfigError,
        match=r"sweep \(line 1\): 3,000,000 points, more than run.max_points \(200,000\);",
    ):  # with the physics checks too: they make no point of a sweep over the limit
        load_config(_cfg(tmp_path, text), physics=PHYSICS)
    with pytest.raises(ConfigError, match=r"sweep.y0 \(line 2\): range has 900,000,001 values"):
        load_config(_cfg(tmp_path, "sweep:\n  y0: {start: 0.1, stop: 1, step: 1e-9}\n"))


def test_max_points_option_allows_a_larger_sweep(tmp_path):
    text = "sweep:\n  y0: [0.6, 0.7, 0.8]\n  theta0: [0, 1]\n"
    with pytest.raises(
        ConfigError, match=r"sweep \(line 1\): 6 points, more than run.max_points \(5\)"
    ):
        load_config(_cfg(tmp_path, text + "run:\n  max_points: 5\n"))
    assert load_config(_cfg(tmp_path, text + "run:\n  max_points: 5\n"), max_points=6).sweep
