"""``fibersweep synth`` and ``fibersweep discrepancy`` end to end, and their input errors."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
from typer.testing import CliRunner

from fibersweep.cli import app


def test_synth_then_discrepancy_writes_the_report(tmp_path, config):
    runner = CliRunner()
    measured = tmp_path / "m.parquet"
    r = runner.invoke(app, ["synth", str(config), "--n", "12", "--seed", "3", "-o", str(measured)])
    assert r.exit_code == 0, r.output
    truth = json.loads((tmp_path / "m.truth.json").read_text())
    assert truth["effects"] == {} and truth["n_written"] + len(truth["failed"]) == 12
    table = pd.read_parquet(measured)
    assert "effects" not in table.columns and len(table) == truth["n_written"]
    assert table["y0"].between(0.1, 0.7).all()  # the sweep box plus noise
    out = tmp_path / "report"
    r = runner.invoke(
        app,
        ["discrepancy", str(measured), str(config), "-o", str(out), "--copies", "2",
         "--no-power"],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    s = json.loads((out / "summary.json").read_text())
    assert s["verdict"]["kind"] == "no significant gap"
    assert s["simulations"] == 2 * len(table) and s["power"] is None
    md = (out / "report.md").read_text()
    assert md.startswith("# Discrepancy report")
    # synth writes every observable, so the report says none was left untested
    assert s["observables_absent"] == [] and "class" in s["observables"]
    assert "Every observable the workflow knows was measured." in md
    # no gap: no map of where it lives (it would show noise), the classes' map is drawn
    assert not (out / "residual_map.png").exists()
    assert (out / "phase_before_after.png").stat().st_size > 0
    assert not list(out.glob("updated_config*.yaml"))
    # follow-up fibers: with no two hypotheses to separate they are not tested, the
    # analysis of MEASURED is the same, and the report says why
    more = tmp_path / "more.parquet"
    r = runner.invoke(app, ["synth", str(config), "--n", "3", "--seed", "5", "-o", str(more)])
    assert r.exit_code == 0, r.output
    out2 = tmp_path / "report2"
    r = runner.invoke(
        app,
        ["discrepancy", str(measured), str(config), "-o", str(out2), "--copies", "2",
         "--no-power", "--followup", str(more)],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    s2 = json.loads((out2 / "summary.json").read_text())
    assert s2["verdict"] == s["verdict"] and s2["simulations"] == s["simulations"]
    assert s2["settle"] is None and "no two hypotheses" in s2["settle_skipped"]
    assert "follow-up not tested" in r.output
    assert "## Follow-up fibers" in (out2 / "report.md").read_text()
    r = runner.invoke(
        app, ["discrepancy", str(measured), str(config), "--followup", str(tmp_path / "no.csv")]
    )
    assert r.exit_code == 2 and "no.csv: no such file" in r.output


def test_bad_inputs_exit_2_with_a_named_problem(tmp_path, config):
    runner = CliRunner()
    r = runner.invoke(app, ["synth", str(config), "--effect", "frictoin=0.3", "-o", "x.parquet"])
    assert r.exit_code == 2 and "friction" in r.output and "valid names" in r.output
    rng = np.random.default_rng(0)
    bad = tmp_path / "rad.csv"
    pd.DataFrame(
        {
            "theta0": np.radians(rng.uniform(-10, 10, 10)),
            "y0": rng.uniform(0, 1, 10),
            "length": rng.uniform(0.5, 1.4, 10),
            "class": "Below",
        }
    ).to_csv(bad, index=False)
    r = runner.invoke(app, ["discrepancy", str(bad), str(config), "-o", str(tmp_path / "r")])
    assert r.exit_code == 2 and "radians" in r.output


def test_misspelled_column_exits_2_unless_ignored(tmp_path, config):
    runner = CliRunner()
    rng = np.random.default_rng(1)
    n = 10  # the held-out split needs at least 8
    table = pd.DataFrame(
        {
            "theta0": rng.uniform(-10, 10, n),
            "y0": rng.uniform(0.2, 0.6, n),
            "length": rng.uniform(0.5, 1.4, n),
            "class": "Below",
            "Delta": 0.0,
        }
    )
    bad = tmp_path / "typo.csv"
    table.to_csv(bad, index=False)
    out = tmp_path / "r"
    r = runner.invoke(app, ["discrepancy", str(bad), str(config), "-o", str(out)])
    assert r.exit_code == 2, r.output
    assert "Delta: unknown column; did you mean 'delta'?" in r.output
    assert not out.exists()
    r = runner.invoke(
        app,
        ["discrepancy", str(bad), str(config), "-o", str(out), "--copies", "2",
         "--ignore-extra-columns", "--no-power", "--no-next", "--pairs", "0"],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    s = json.loads((out / "summary.json").read_text())
    assert s["observables"] == ["class"]
    assert "delta" in s["observables_absent"] and "theta_c" in s["observables_absent"]
    assert "Absent from the measured data, so not tested: " in (out / "report.md").read_text()


def test_effect_options_one_convention(tmp_path, config):
    runner = CliRunner()
    measured = tmp_path / "m.parquet"
    r = runner.invoke(app, ["synth", str(config), "--n", "10", "--seed", "4", "-o", str(measured)])
    assert r.exit_code == 0, r.output
    # discrepancy fits the values: a value given to --effect is a named input error
    r = runner.invoke(app, ["discrepancy", str(measured), str(config), "--effect", "friction=0.3"])
    assert r.exit_code == 2 and "give the name only" in r.output
    # the removed comma list is an unknown option; the repeatable --effect runs
    r = runner.invoke(app, ["discrepancy", str(measured), str(config), "--effects", "friction"])
    assert r.exit_code == 2 and "--effects" in r.output
    out = tmp_path / "r"
    r = runner.invoke(
        app,
        ["discrepancy", str(measured), str(config), "-o", str(out), "--copies", "2",
         "--no-power", "--no-next", "--pairs", "0", "--effect", "friction",
         "--effect", "inlet_speed"],
    )  # fmt: skip
    assert r.exit_code == 0, r.output


def test_power_command_writes_limits(tmp_path, config):
    runner = CliRunner()
    out = tmp_path / "pw"
    r = runner.invoke(
        app,
        ["power", str(config), "--n", "100", "--simulate", "8", "--effect", "inlet_speed",
         "-o", str(out)],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    p = json.loads((out / "power.json").read_text())
    assert p["n"] == 100 and p["n_simulated"] == 8
    assert {e["effect"] for e in p["effects"]} == {"inlet_speed"} and len(p["effects"]) == 2
    # 3 copies of the baseline and of each of 2 probes at 2 magnitudes, 8 fibers each,
    # and 3 x 8 more per limit read again where it lies (at most 4 per probe)
    extra, rest = divmod(p["simulations"] - 3 * 8 * (1 + 2 * 2), 3 * 8)
    again = [e for e in p["effects"] if e["read_at"] is not None]
    assert rest == 0 and len(again) <= extra <= 4 * 2, p["simulations"]
    assert r.output.count("read at") == len(again)
    assert "detection limits at N = 100" in r.output
    # each limit with its 95 % interval over the simulated starts (--boot 30 by default)
    assert all(len(e["limit_ci"]) == 2 for e in p["effects"])


def test_a_candidate_that_is_an_effect_exits_2_naming_the_option(tmp_path, config):
    runner = CliRunner()
    r = runner.invoke(app, ["power", str(config), "--candidate", "fiber.effects.friction=0.3"])
    assert r.exit_code == 2, r.output
    assert "--candidate fiber.effects.friction=0.3" in r.output and "--effect friction" in r.output
    cfg = tmp_path / "withcand.yaml"
    cfg.write_text(config.read_text() + "discrepancy:\n  candidates: ['friction=0..1']\n")
    r = runner.invoke(app, ["power", str(cfg)])
    assert r.exit_code == 2 and "discrepancy.candidates[0]" in r.output, r.output


def test_power_reports_a_declared_candidate_in_its_own_terms(tmp_path, config):
    """``power --candidate KEY=VALUE``: the alternative alone (no --effect), 8 fibers."""
    runner = CliRunner()
    out = tmp_path / "pw"
    r = runner.invoke(
        app,
        ["power", str(config), "--n", "100", "--simulate", "8", "--boot", "0",
         "--candidate", "fiber.contact.chi=2.5", "-o", str(out)],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    rows = json.loads((out / "power.json").read_text())["effects"]
    assert [row["effect"] for row in rows] == ["fiber.contact.chi=2.5"]
    assert "fiber.contact.chi = 2.5" in rows[0]["setting"]
    assert "fiber.contact.chi=2.5:" in r.output
