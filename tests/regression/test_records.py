"""Records that travel: units on every column, provenance kept through `classify`, the rule
behind each class, a warning wherever a class column mixes rules, and `fibersweep.load`.

A 4-run sweep on the shared coarse field (SPEC geometry, dx = 4 µm), trajectories on.
"""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

import fibersweep
from fibersweep.cli import app
from fibersweep.sweep.coldocs import TRAJ_COLUMN_DOCS
from fibersweep.sweep.store import RUNS_DIR, TRAJ_DIR, list_parts, read_runs

runner = CliRunner()

# Columns whose metadata comes with RunResult's generated columns (issue 31), not checked here.
ELSEWHERE = {"n_beads", "t_end", "min_clearance"}


def _config(tmp: Path, cache: Path, y0: str = "[0.39, 0.9]") -> Path:
    p = tmp / "sweep.yaml"
    p.write_text(
        "flow:\n  dx: 4.0\n"
        "fiber:\n  record:\n    trajectories: true\n    samples: 60\n"
        f"sweep:\n  theta0: [-8.0, 0.0]\n  y0: {y0}\n  length: [1.0]\n"
        f"run:\n  workers: 1\n  output: {tmp / 'res'}\n  cache_dir: {cache}\n"
    )
    return p


def _invoke(*args):
    res = runner.invoke(app, [str(a) for a in args])
    return res, res.output + (res.stderr if res.stderr_bytes is not None else "")


def _meta(part: Path) -> dict:
    return json.loads(pq.read_schema(part).metadata[b"fibersweep"])


@pytest.fixture(scope="module")
def swept(tmp_path_factory, coarse_field, flow_cache_dir):
    tmp = tmp_path_factory.mktemp("records")
    cfg = _config(tmp, flow_cache_dir)
    res, text = _invoke("run", cfg)
    assert res.exit_code == 0, text
    return tmp, cfg, tmp / "res"


def test_every_column_carries_its_unit_and_meaning(swept):
    _, _, out = swept
    for sub in (RUNS_DIR, TRAJ_DIR):
        schema = pq.read_schema(list_parts(out / sub)[-1])
        for f in schema:
            if f.name in ELSEWHERE:
                continue
            meta = f.metadata or {}
            assert b"unit" in meta and meta.get(b"doc"), (sub, f.name)
    traj = pq.read_schema(list_parts(out / TRAJ_DIR)[-1])
    assert traj.field("x").metadata[b"unit"] == "µm".encode()
    assert traj.field("head_speed").metadata[b"unit"] == b"\xc2\xb5m/s"
    assert traj.field("theta").metadata[b"unit"] == b"deg"
    assert {f.name for f in traj} <= set(TRAJ_COLUMN_DOCS)
    # a sweep never refined has no 'round' column (tests/regression/test_refine_e2e.py has it)
    assert "round" not in pq.read_schema(list_parts(out / RUNS_DIR)[-1]).names
    assert "round" not in read_runs(out)


def test_classify_keeps_provenance_and_records_the_rule(swept, tmp_path):
    import shutil

    _, _, src = swept
    out = tmp_path / "copy"
    shutil.copytree(src, out)
    before = _meta(list_parts(out / RUNS_DIR)[-1])
    assert before["config"]["fiber"]["classify"]["rule"] == "switch"
    assert (read_runs(out)["class_rule"] == "switch").all()
    res, text = _invoke("classify", out, "--rule", "pivot")
    assert res.exit_code == 0, text
    parts = list_parts(out / RUNS_DIR)
    assert len(parts) == 1
    after = _meta(parts[0])
    for key in ("fibersweep", "git", "flow_key", "config"):  # kept from the sweep
        assert after[key] == before[key], key
    assert after["rule"] == "pivot" and after["classify"]["rule"] == "pivot"
    assert after["classified_by"]["fibersweep"] == fibersweep.__version__
    runs = read_runs(out)
    assert (runs["class_rule"] == "pivot").all()
    assert (runs["class"] == runs["class_pivot"]).all()
    # the added columns carry their meaning too
    f = pq.read_schema(parts[0]).field("class_rule")
    assert f.metadata[b"doc"].startswith(b"pole-vaulting rule")


def test_a_folder_that_mixes_rules_is_flagged_everywhere_until_relabelled(
    swept, tmp_path, flow_cache_dir
):
    import shutil

    _, _, src = swept
    out = tmp_path / "res"
    shutil.copytree(src, out)
    res, text = _invoke("classify", out, "--rule", "pivot")
    assert res.exit_code == 0, text
    # the README's order: classify --rule pivot, then an axis run adds rows by the default rule
    res, text = _invoke("run", _config(tmp_path, flow_cache_dir, "[0.39, 0.9, 0.2]"))
    assert res.exit_code == 0, text
    assert "mixes pole-vaulting rules (4 by pivot, 2 by switch runs)" in text, text
    runs = read_runs(out)
    assert sorted(runs["class_rule"]) == ["pivot"] * 4 + ["switch"] * 2
    res, text = _invoke("check", out)
    assert res.exit_code == 0 and "warning:" in text and "--rule pivot" in text, text
    res, text = _invoke("plot-phase", out, "-o", tmp_path / "fig")
    assert res.exit_code == 0 and "warning:" in text and "mixes" in text, text
    assert fibersweep.load(out, trajectories=False).warnings
    # one classify makes it uniform: no warning any more
    res, text = _invoke("classify", out, "--rule", "pivot")
    assert res.exit_code == 0, text
    res, text = _invoke("check", out)
    assert res.exit_code == 0 and "warning" not in text, text
    assert not fibersweep.load(out, trajectories=False).warnings


def test_load_returns_runs_trajectories_settings_and_units(swept):
    _, _, out = swept
    res = fibersweep.load(out)
    assert len(res.runs) == 4 and set(res.trajectories["id"]) == set(res.runs["id"])
    assert res.settings["sweep"]["y0"] == [0.39, 0.9]
    assert res.settings["fiber"]["classify"]["rule"] == "switch"
    assert res.units["y0"] == "h_obs" and res.units["delta"] == "h_obs"
    assert res.units["x"] == "µm" and res.units["t"] == "s"
    assert res.runs.attrs["units"]["theta0"] == "deg"
    assert res.docs["theta0"].startswith("start angle")
    assert res.provenance["flow_key"] and "git" in res.provenance
    one = res.trajectory(res.runs["id"].iloc[0])
    assert len(one) == one["sample"].max() + 1 and one["t"].is_monotonic_increasing
    assert "4 runs, 4 trajectories" in repr(res)


def test_load_refuses_a_folder_that_is_not_a_sweep(tmp_path):
    from fibersweep.errors import InputError

    with pytest.raises(InputError, match="not a fibersweep output folder"):
        fibersweep.load(tmp_path)
