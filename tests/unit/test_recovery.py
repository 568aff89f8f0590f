"""A results folder that lost data says so, and the same ``fibersweep run`` repairs it.

Two tiny pillar-array sweeps (dx = 4 µm, 2 rows, 4 runs each): rigid fibers, and
bead-spring fibers with every bead kept (``fiber.record.all_beads``, as
``configs/array-flexible.yaml``). Each test copies one, damages a part (cut short,
deleted, or its bead column dropped) and checks that ``fibersweep check`` says NOT ok
naming the part and the repair command, that the same ``fibersweep run`` re-runs
exactly the runs that lost data (no duplicate id, in the table or in its parts), that
``check`` is then ok, and that the commands that read trajectories work again.
A reading command given a broken part exits 2 and names it once.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from fibersweep.cli import app
from fibersweep.sweep.store import (
    RUNS_DIR,
    TRAJ_DIR,
    VOLATILE_COLUMNS,
    list_parts,
    read_runs,
    read_trajectories,
    repair_command,
)

SMALL = ["flow.dx=4", "fiber.array_rows=2", "run.workers=1"]
RIGID = ["configs/array.yaml", *SMALL, "sweep.length=[12, 40]", "sweep.random={count: 2, seed: 0}"]
FLEXIBLE = [
    "configs/array-flexible.yaml",
    *SMALL,
    "sweep.fiber.young_modulus=[1.0e+4]",
    "sweep.length=[20, 40]",
    "sweep.random={count: 2, seed: 0}",
]


def _invoke(*args: object):
    res = CliRunner().invoke(app, [str(a) for a in args])
    return res, res.output


def _command(kind: list[str], out: Path, cache: Path) -> list[str]:
    return ["run", *kind, f"run.cache_dir={cache}", f"run.output={out}"]


def _sweep(tmp_path_factory, flow_cache_dir, kind: list[str], name: str) -> Path:
    out = tmp_path_factory.mktemp(name) / "res"
    res, text = _invoke(*_command(kind, out, flow_cache_dir))
    assert res.exit_code == 0, text
    return out


@pytest.fixture(scope="module")
def rigid(tmp_path_factory, flow_cache_dir):
    return _sweep(tmp_path_factory, flow_cache_dir, RIGID, "rigid")


@pytest.fixture(scope="module")
def flexible(tmp_path_factory, flow_cache_dir):
    return _sweep(tmp_path_factory, flow_cache_dir, FLEXIBLE, "flexible")


def _truncate(p: Path) -> None:
    data = p.read_bytes()
    p.write_bytes(data[: len(data) // 2])


def _physics(df):
    return df.drop(columns=list(VOLATILE_COLUMNS)).sort_values("id").reset_index(drop=True)


def _damage_check_repair(src: Path, tmp_path: Path, cache: Path, kind: list[str], damage):
    """Copy ``src``, damage it, and go through check, run, check; the check's text."""
    out = tmp_path / "res"
    shutil.copytree(src, out)
    before = read_runs(out)
    named = damage(out)
    res, text = _invoke("check", out)
    assert res.exit_code == 1, text
    assert text.rstrip().endswith("NOT ok"), text
    if named is not None:
        assert text.count(str(named)) == 1, text  # the part, named once
    # the repair command: `fibersweep run` with the sweep's overrides (CONFIG: no command
    # line was recorded from inside pytest)
    repair = next(line for line in text.splitlines() if line.startswith("  repair: "))
    assert "`fibersweep run CONFIG flow.dx=4 fiber.array_rows=2 run.workers=1 " in repair, text
    assert f" -o {out}` (CONFIG: " in repair, text  # the copy, not the folder it came from

    res, ran = _invoke(*_command(kind, out, cache))  # the same command repairs it
    assert res.exit_code == 0, ran
    assert "nothing to run" not in ran, ran
    res, again = _invoke("check", out)
    assert res.exit_code == 0 and again.rstrip().endswith("ok"), again
    assert "MISSING" not in again and "UNREADABLE" not in again, again

    after = read_runs(out)
    assert after["id"].is_unique and set(after["id"]) == set(before["id"])
    stored = pq.read_table(out / RUNS_DIR).column("id").to_pylist()  # every part, raw
    assert len(stored) == len(set(stored)) == len(before), "no duplicate row on disk"
    assert set(read_trajectories(out)["id"]) == set(before["id"])
    # the same physics as before the damage (the runs are deterministic)
    assert _physics(after).equals(_physics(before))
    return text, ran


def _only_part(out: Path, sub: str) -> Path:
    parts = list_parts(out / sub)
    assert len(parts) == 1, parts  # compacted at the end of the sweep
    return parts[0]


# ----------------------------------------------------------------------------- rigid


def test_truncated_trajectories_part_is_reported_and_repaired(rigid, tmp_path, flow_cache_dir):
    """The user's case: the trajectories were lost while every row stayed 'ok'."""

    def damage(out):
        p = _only_part(out, TRAJ_DIR)
        _truncate(p)
        return p

    text, ran = _damage_check_repair(rigid, tmp_path, flow_cache_dir, RIGID, damage)
    assert "UNREADABLE " in text and "MISSING the trajectory of 4 ok run(s)" in text, text
    assert "to do now 4" in ran and "4 ok run(s) lost their stored trajectory" in ran, ran
    out = tmp_path / "res"
    assert list(out.glob(f"quarantine-*/{TRAJ_DIR}/part-*.parquet")), "moved aside, not deleted"
    for args in (["classify", out], ["sort-report", out, "--no-figures"]):
        res, said = _invoke(*args)
        assert res.exit_code == 0, said


def test_deleted_trajectories_part_is_reported_and_repaired(rigid, tmp_path, flow_cache_dir):
    def damage(out):
        _only_part(out, TRAJ_DIR).unlink()
        return None

    text, ran = _damage_check_repair(rigid, tmp_path, flow_cache_dir, RIGID, damage)
    assert "MISSING the trajectory of 4 ok run(s)" in text and "UNREADABLE" not in text, text
    assert "to do now 4" in ran, ran
    res, said = _invoke("classify", tmp_path / "res")
    assert res.exit_code == 0, said


@pytest.mark.parametrize("how", ["truncated", "deleted"])
def test_lost_runs_part_is_reported_and_repaired(rigid, tmp_path, flow_cache_dir, how):
    def damage(out):
        p = _only_part(out, RUNS_DIR)
        if how == "deleted":
            p.unlink()
            return None
        _truncate(p)
        return p

    text, ran = _damage_check_repair(rigid, tmp_path, flow_cache_dir, RIGID, damage)
    assert "MISSING 4 run(s): the manifest counted 4" in text, text
    assert "to do now 4" in ran, ran
    res, said = _invoke("sort-report", tmp_path / "res", "--no-figures")
    assert res.exit_code == 0, said


@pytest.mark.parametrize("command", ["classify", "sort-report", "plot-tracks"])
def test_a_reading_command_given_a_broken_part_exits_2_naming_it_once(rigid, tmp_path, command):
    out = tmp_path / "res"
    shutil.copytree(rigid, out)
    part = _only_part(out, TRAJ_DIR if command != "classify" else RUNS_DIR)
    _truncate(part)
    res, text = _invoke(command, out)
    assert res.exit_code == 2, text
    assert text.startswith(f"error: {part}: unreadable result part ("), text
    assert text.count(str(part)) == 1, text
    assert "runs its runs again: `fibersweep run " in text, text
    assert part.exists(), "a reading command moves nothing"


# ----------------------------------------------------------------------------- beads


def test_truncated_bead_part_of_flexible_fibers_is_repaired(flexible, tmp_path, flow_cache_dir):
    def damage(out):
        p = _only_part(out, TRAJ_DIR)
        assert "beads" in pq.read_schema(p).names
        _truncate(p)
        return p

    text, _ = _damage_check_repair(flexible, tmp_path, flow_cache_dir, FLEXIBLE, damage)
    assert "MISSING the trajectory of 4 ok run(s)" in text, text
    traj = read_trajectories(tmp_path / "res")
    assert traj["beads"].notna().all()
    for args in (["classify", tmp_path / "res"], ["sort-report", tmp_path / "res", "--no-figures"]):
        res, said = _invoke(*args)
        assert res.exit_code == 0, said


def test_bead_positions_dropped_from_a_part_are_reported_and_repaired(
    flexible, tmp_path, flow_cache_dir
):
    def damage(out):
        p = _only_part(out, TRAJ_DIR)
        t = pq.read_table(p)
        pq.write_table(t.drop_columns(["beads"]), p)
        return p

    text, ran = _damage_check_repair(flexible, tmp_path, flow_cache_dir, FLEXIBLE, damage)
    assert "MISSING the bead positions of 4 ok run(s)" in text, text
    assert "4 ok run(s) lost their stored trajectory or beads" in ran, ran
    assert read_trajectories(tmp_path / "res")["beads"].notna().all()


# ----------------------------------------------------------------------------- the command


def test_repair_command_is_the_recorded_run_line(tmp_path):
    out = tmp_path / "res"
    man = {
        "overrides": ["flow.dx=4", "sweep.length=[12, 60]"],
        "config": {"run": {"output": "results/array"}},
        "provenance": {
            "argv": ["/usr/bin/fibersweep", "run", "-w", "3", "configs/array.yaml",
                     "flow.dx=4", "sweep.length=[12, 60]", "--no-resume", "-o", "x"],
        },
    }  # fmt: skip
    assert repair_command(out, man) == (
        f"`fibersweep run configs/array.yaml flow.dx=4 'sweep.length=[12, 60]' -w 3 -o {out}`"
    )
    # the folder the config names, seen from here: no -o
    man["overrides"].append(f"run.output={out}")
    man["provenance"]["argv"] = ["/x/fibersweep/cli/__main__.py", "run", "c.yaml"]
    assert repair_command(out, man) == (
        f"`fibersweep run c.yaml flow.dx=4 'sweep.length=[12, 60]' run.output={out}` (from the "
        "folder the sweep was started in: c.yaml is relative)"  # no c.yaml here
    )
    # started from Python: a template that says what CONFIG is
    man["provenance"]["argv"] = ["script.py"]
    assert repair_command(out, man).startswith("`fibersweep run CONFIG flow.dx=4 ")
    assert "(CONFIG: the config file that made the folder" in repair_command(out, man)
    assert repair_command(out, None) == (
        f"`fibersweep run CONFIG -o {out}` (CONFIG: the config file that made the folder; its "
        "manifest.json holds the settings)"
    )


def test_a_cut_manifest_is_reported_not_a_traceback(rigid, tmp_path):
    out = tmp_path / "res"
    shutil.copytree(rigid, out)
    _truncate(out / "manifest.json")
    res, text = _invoke("check", out)
    assert res.exit_code == 1 and text.rstrip().endswith("NOT ok"), text
    assert f"UNREADABLE {out / 'manifest.json'}: unreadable manifest (" in text, text
