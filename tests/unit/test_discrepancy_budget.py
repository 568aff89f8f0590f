"""The budget is a promise: stages that cannot fit are skipped and said, the report is
always written, and the command exits 0 with its verdict.

End to end on the tests' coarse field (12 fibers, 2 copies: 24 baseline runs).
With every library effect a candidate, the power analysis of a "no significant
gap" verdict needs 660 runs (3 copies x 12 fibers x (2 per probe, 9 probes + the
baseline) less the 24 baseline runs it reuses, :func:`.followup.followup_costs`);
a budget of 300 holds the smallest analysis (246 runs) but leaves 276 after the
noise floor, so the power analysis is skipped for the budget.
"""

from __future__ import annotations

import json

import numpy as np
from typer.testing import CliRunner

from fibersweep.cli import app
from fibersweep.discrepancy.followup import followup_costs
from fibersweep.discrepancy.settings import DiscrepancySettings, plan_budget


def test_the_follow_up_costs_are_known_before_the_analysis():
    s = DiscrepancySettings(copies=2, pairs=0, budget=300)
    cands = s.candidates_of()
    plan = plan_budget(12, s, cands)
    assert plan.total(12) <= 300  # the analysis at its most fits
    rng = np.random.default_rng(0)
    starts = np.column_stack([rng.uniform(-10, 10, 12), rng.uniform(0.15, 0.65, 12),
                              rng.uniform(0.5, 1.4, 12)])  # fmt: skip
    c = followup_costs(starts, s, plan, cands)
    # exact: planned_runs's certain runs (3 x 12 x (1 + 2 x 9)) less the 2 x 12 reused
    assert c.power == 3 * 12 * (1 + 2 * 9) - 2 * 12 == 660
    assert c.power > 300 - 2 * 12  # more than the noise floor leaves


def test_a_budget_too_small_for_the_power_analysis_still_writes_the_verdict(tmp_path, config):
    runner = CliRunner()
    measured = tmp_path / "m.parquet"
    r = runner.invoke(app, ["synth", str(config), "--n", "12", "--seed", "3", "-o", str(measured)])
    assert r.exit_code == 0, r.output
    out = tmp_path / "report"
    r = runner.invoke(
        app,
        ["discrepancy", str(measured), str(config), "-o", str(out), "--copies", "2",
         "--pairs", "0", "--budget", "300"],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    # the plan says beforehand what the budget leaves the follow-ups
    assert "budget 300:" in r.output and "after the verdict, if it calls for them" in r.output
    s = json.loads((out / "summary.json").read_text())
    assert s["verdict"]["kind"] == "no significant gap"
    assert s["simulations"] <= 300 and s["power"] is None
    assert s["power_skipped"].startswith("skipped: budget")
    assert s["stages_skipped"]["power analysis"] == s["power_skipped"]
    assert "verdict: no significant gap" in r.output and "not run: power analysis" in r.output
    md = (out / "report.md").read_text()
    first, detail = md.split("# Statistical detail")
    assert "### Not run for the budget" in first and "power analysis: it needs up to 660" in first
    # no gap: no section or figure about where a gap lives
    assert "Where the gap lives" not in md and not (out / "residual_map.png").exists()
    assert "## Words used below" in detail
