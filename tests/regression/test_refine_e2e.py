"""Adaptive refinement end to end through the CLI, with the real simulator.

SPEC geometry on the coarse dx = 4 µm field of the shared test cache, L = 0.8 l_obs, a
2 x 5 grid refined along y0 to 0.02 h_obs. Checked: the refinement rounds are ordinary
runs of the one table (column ``round``); every class bracket left in the table is
within tolerance or the budget/rounds ran out; a further round continues from the stored
ones; a partly lost round is re-derived and only its missing runs run again; the dry run
says what is known of the rounds. (The figure's boundaries: tests/unit/test_plots_boundaries.py.)
"""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from fibersweep.analysis.boundaries import brackets
from fibersweep.cli import app
from fibersweep.sweep.store import read_runs, rewrite_runs

runner = CliRunner()
TOL = 0.02


def _invoke(*args: str):
    res = runner.invoke(app, [str(a) for a in args])
    return res, res.output + (res.stderr if res.stderr_bytes is not None else "")


def _config(tmp: Path, cache: Path, rounds: int) -> Path:
    p = tmp / "refine.yaml"
    p.write_text(
        "flow:\n  dx: 4.0\n"
        "sweep:\n  theta0: [-6.0, 4.0]\n  y0: [0.1, 0.3, 0.45, 0.6, 0.9]\n  length: 0.8\n"
        f"  refine:\n    axes: [y0]\n    tolerance: {{y0: {TOL}}}\n    max_runs: 60\n"
        f"    rounds: {rounds}\n"
        f"run:\n  workers: 1\n  output: {tmp / 'out'}\n  cache_dir: {cache}\n"
    )
    return p


@pytest.fixture(scope="module")
def refined(tmp_path_factory, coarse_field, flow_cache_dir):
    tmp = tmp_path_factory.mktemp("refine")
    cfg = _config(tmp, flow_cache_dir, rounds=2)
    res, text = _invoke("run", cfg, "--dry-run")
    assert res.exit_code == 0, text
    assert "the rounds are not yet known" in text, text
    res, text = _invoke("run", cfg)
    assert res.exit_code == 0, text
    first = read_runs(tmp / "out")
    # two more rounds continue from the stored ones (nothing of rounds 0-2 runs again)
    res, text2 = _invoke("run", cfg, "sweep.refine.rounds=4")
    assert res.exit_code == 0, text2
    return tmp, cfg, text, text2, first


def test_rounds_are_ordinary_runs_of_one_table(refined):
    tmp, _, text, _, first = refined
    assert "refinement round 1:" in text and "refinement round 2:" in text, text
    assert sorted(first["round"].unique()) == [0, 1, 2]
    assert (first["round"] == 0).sum() == 10 and first["id"].is_unique
    assert (first["status"] == "ok").all()
    assert "refinement: 2 rounds" in text and "(sweep.refine.rounds reached)" in text, text


def test_more_rounds_continue_without_rerunning(refined):
    tmp, _, _, text2, first = refined
    df = read_runs(tmp / "out")
    assert df["id"].is_unique
    assert set(first["id"]) <= set(df["id"])
    new = df[~df["id"].isin(first["id"])]
    assert len(new) > 0 and (new["round"] >= 3).all()
    assert f"ran {len(new)} runs" in text2, text2
    b = brackets(df, ["y0"])
    # 0.15 / 2**3 < 0.02 < 0.15 / 2**2: every bracket is located after 3 rounds of 4
    assert ((b["hi"] - b["lo"]) <= TOL + 1e-12).all(), b
    assert "every boundary bracket is within tolerance" in text2, text2
    man = json.loads((tmp / "out" / "manifest.json").read_text())
    assert man["refinement"]["stopped"] == "located" and man["refinement"]["open"] == 0
    assert man["sweep_size"] == len(df)
    for pair in b.itertuples():  # the bracket ends are stored runs of those classes
        at = df[(df["theta0"] == pair.theta0) & df["y0"].isin([pair.lo, pair.hi])]
        assert set(at["class"]) == {pair.class_lo, pair.class_hi}


def test_partly_lost_round_resumes_without_duplicates(refined):
    tmp, cfg, *_ = refined
    df = read_runs(tmp / "out")
    last = df[df["round"] == df["round"].max()]
    lost = last["id"].iloc[::2].tolist()
    rewrite_runs(tmp / "out", df[~df["id"].isin(lost)])
    res, text = _invoke("run", cfg, "sweep.refine.rounds=4", "--dry-run")
    assert res.exit_code == 0, text
    assert f"to do now {len(lost)}" in text, text
    res, text = _invoke("run", cfg, "sweep.refine.rounds=4")
    assert res.exit_code == 0, text
    assert f"ran {len(lost)} runs" in text, text
    again = read_runs(tmp / "out")
    assert again["id"].is_unique and set(again["id"]) == set(df["id"])
    cols = ["id", "class", "delta", "round"]
    pd.testing.assert_frame_equal(
        again[cols].sort_values("id").reset_index(drop=True),
        df[cols].sort_values("id").reset_index(drop=True),
    )
