"""Any setting as a sweep axis, end to end through the CLI (issue 11).

A flow axis (pillar height 75 and 60 µm in the small 400 x 800 µm channel at dx = 4 µm)
needs two fields: the 75 µm one is the shared test cache's ``small_field``, the 60 µm one is
computed once (about 5-15 s). A friction axis multiplies the runs; one output folder holds
them all, each row with its swept values, and a second invocation runs nothing.
"""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from fibersweep.cli import app
from fibersweep.sweep.store import RUNS_DIR, list_parts, read_runs

runner = CliRunner()

FLOW = """flow:
  dx: 4.0
  geometry: {width: 400.0, depth: 40.0, length: 800.0, pillar_height: 75.0}
"""


def _invoke(*args: str):
    res = runner.invoke(app, [str(a) for a in args])
    return res, res.output + (res.stderr if res.stderr_bytes is not None else "")


def _config(tmp: Path, cache: Path, name: str, sweep: str) -> Path:
    text = (
        FLOW
        + "fiber:\n  record:\n    trajectories: true\n    samples: 60\n"
        + "sweep:\n  theta0: [0.0]\n  y0: [0.2, 0.8]\n  length: 1.0\n"
        + sweep
        + f"run:\n  workers: 2\n  output: {tmp / 'out'}\n  cache_dir: {cache}\n"
    )
    p = tmp / f"{name}.yaml"
    p.write_text(text)
    return p


@pytest.fixture(scope="module")
def swept(tmp_path_factory, small_field, flow_cache_dir):
    """A sweep over pillar height (2 fields) and friction: 2 x 2 combinations x 2 starts."""
    tmp = tmp_path_factory.mktemp("axes")
    cfg = _config(
        tmp,
        flow_cache_dir,
        "axes",
        "  flow.geometry.pillar_height: [75, 60]\n  fiber.effects.friction: [0, 0.3]\n",
    )
    res, text = _invoke("run", cfg)
    assert res.exit_code == 0, text
    return tmp, cfg, text


def test_flow_axis_computes_two_fields_and_every_run_is_recorded(swept, flow_cache_dir):
    tmp, _, text = swept
    assert "2 flow fields" in text, text
    out = tmp / "out"
    df = read_runs(out)
    assert len(df) == 8 and df["id"].is_unique and (df["status"] == "ok").all(), df
    # one typed column per swept key, with every combination present twice (two starts)
    combos = df.groupby(["flow.geometry.pillar_height", "fiber.effects.friction"]).size()
    assert combos.to_dict() == {(60.0, 0.0): 2, (60.0, 0.3): 2, (75.0, 0.0): 2, (75.0, 0.3): 2}
    assert df["settings"].nunique() == 4
    man = json.loads((out / "manifest.json").read_text())
    assert man["swept"] == ["flow.geometry.pillar_height", "fiber.effects.friction"]
    assert len(man["flow_keys"]) == 2 and len(man["combinations"]) == 4
    for key in man["flow_keys"]:  # both fields are in the cache
        assert (flow_cache_dir / f"flow-{key}" / "manifest.json").exists()
    schema = pq.read_schema(list_parts(out / RUNS_DIR)[0])
    f = schema.field("flow.geometry.pillar_height")
    assert str(f.type) == "double" and f.metadata[b"unit"] == "µm".encode()
    assert str(schema.field("fiber.effects.friction").type) == "double"


def test_dask_runs_the_same_mixed_table(swept, flow_cache_dir, tmp_path):
    """Dask workers map the fields the same way: bit-identical physics, same columns."""
    pytest.importorskip("distributed")
    tmp, cfg, _ = swept
    other = tmp_path / "dask.yaml"
    other.write_text(cfg.read_text().replace(str(tmp / "out"), str(tmp_path / "dask")))
    res, text = _invoke("run", other, "--executor", "dask", "--workers", "2")
    assert res.exit_code == 0, text
    cols = ["id", "settings", "flow.geometry.pillar_height", "fiber.effects.friction", "class",
            "delta", "x_f", "y_f", "theta_f", "n_steps"]  # fmt: skip
    local = read_runs(tmp / "out")[cols].sort_values("id").reset_index(drop=True)
    dask = read_runs(tmp_path / "dask")[cols].sort_values("id").reset_index(drop=True)
    pd.testing.assert_frame_equal(dask, local)


def test_second_run_and_dry_run_do_nothing(swept):
    tmp, cfg, _ = swept
    before = read_runs(tmp / "out")
    res, text = _invoke("run", cfg)
    assert res.exit_code == 0 and "to do now 0" in text, text
    res, text = _invoke("run", cfg, "--dry-run")
    assert res.exit_code == 0 and "done 8 ok, 0 failed; to do now 0" in text, text
    assert "4 setting combinations" in text, text
    assert len(read_runs(tmp / "out")) == len(before)


def test_growing_an_axis_runs_only_the_new_combination(swept, flow_cache_dir):
    tmp, cfg, _ = swept
    grown = cfg.read_text().replace("friction: [0, 0.3]", "friction: [0, 0.3, 0.6]")
    cfg.write_text(grown)
    res, text = _invoke("run", cfg, "--dry-run")
    assert res.exit_code == 0 and "done 8 ok, 0 failed; to do now 4" in text, text
    # a setting that is not swept changed: refused, as for one-setting sweeps
    res, text = _invoke("run", cfg, "fiber.bead_radius=1.8", "--dry-run")
    assert res.exit_code == 2 and "fiber.bead_radius: 2.0 -> 1.8" in text, text


def test_plot_and_classify_group_by_the_swept_keys(swept):
    tmp, _, _ = swept
    out = tmp / "out"
    res, text = _invoke("classify", out)
    assert res.exit_code == 0, text
    counts = (out / "counts.csv").read_text().splitlines()
    assert counts[0].startswith("flow.geometry.pillar_height,fiber.effects.friction,class,runs")
    res, text = _invoke("plot-phase", out)
    assert res.exit_code == 0 and "phase.png" in text, text
    res, text = _invoke("plot-phase", out, "--col", "fiber.effects.friction", "--row", "nope")
    assert res.exit_code == 2 and "nope" in text, text


def test_bad_axis_value_names_the_key_and_line(tmp_path, flow_cache_dir):
    cfg = _config(tmp_path, flow_cache_dir, "bad", "  fiber.contact.pillar: [rough, smoth]\n")
    res, text = _invoke("run", cfg, "--dry-run")
    assert res.exit_code == 2, text
    assert "sweep.fiber.contact.pillar (line 12): value 'smoth'" in text, text
