"""The public Python API and the command line give the same answers.

Each command that has an API function is one call into it (``fibersweep/cli/``
parses, calls, prints); here both are run on the same small config and their
outputs compared: the same run ids, classes and δ, the same tables, the same
error naming the same field. The sweeps are the quick config cut to 4 runs on the
coarse grid and a tiny pillar array (3 rows, 8 runs), both on the shared test
flow-field cache.
"""

from __future__ import annotations

import inspect
import re
import shutil

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import fibersweep
from fibersweep import api
from fibersweep.cli import app
from fibersweep.config import Config, ConfigError

SMALL = ["sweep.theta0=[-4.0, 4.0]", "sweep.y0=[0.3, 0.4]", "run.workers=1"]
ARRAY = ["flow.dx=4", "fiber.array_rows=3", "run.workers=1", "sweep.length=[4, 40]",
         "sweep.flow.array.shift=[0.1, 0.2]", "sweep.random={count: 2, seed: 0}"]  # fmt: skip


def _cli(args: list[str]):
    return CliRunner().invoke(app, [str(a) for a in args])


def _runs(path) -> pd.DataFrame:
    runs = fibersweep.load(path, trajectories=False).runs
    return runs.sort_values("id").reset_index(drop=True)


# --------------------------------------------------------------------------- the names


def test_the_api_tuple_and_the_api_module_agree():
    functions = [n for n in api.__all__ if inspect.isfunction(getattr(api, n))]
    # fibersweep.discrepancy is the subpackage: the workflow is fibersweep.api.discrepancy
    assert [n for n in functions if n != "discrepancy"] == list(fibersweep.API)
    assert "discrepancy" in functions
    for name in functions:
        fn = getattr(api, name)
        if name in fibersweep.API:
            assert getattr(fibersweep, name) is fn
        doc = inspect.getdoc(fn)
        assert "Parameters\n----------" in doc and "Returns\n-------" in doc, name
    # the result objects are frozen dataclasses
    for name in ("SweepRun", "SweepEstimate", "FiberRun", "FlowFields", "FieldReport",
                 "Classified", "SortReport", "DiscrepancyReport", "DiscrepancyPlan"):  # fmt: skip
        cls = getattr(api, name)
        assert cls.__dataclass_params__.frozen, name
    with pytest.raises(AttributeError):
        fibersweep.not_a_function  # noqa: B018


# --------------------------------------------------------------------------- channel


@pytest.fixture(scope="module")
def sweeps(tmp_path_factory, flow_cache_dir):
    """The same 4-run sweep by the API and by the CLI, into two folders."""
    root = tmp_path_factory.mktemp("api")
    cache = f"run.cache_dir={flow_cache_dir}"
    rows = []
    done = api.run("configs/quick.yaml", *SMALL, cache, output=root / "api", progress=rows.append)
    res = _cli(["run", "configs/quick.yaml", *SMALL, cache, "-o", root / "cli"])
    assert res.exit_code == 0, res.output
    return done, rows, res.output, root


def test_run_gives_what_the_command_writes(sweeps):
    done, rows, printed, root = sweeps
    assert done.path == root / "api" and done.ran == 4 and done.failed == 0
    a, c = _runs(root / "api"), _runs(root / "cli")
    assert list(a["id"]) == list(c["id"])
    assert list(a["class"]) == list(c["class"])
    assert np.array_equal(a["delta"].to_numpy(), c["delta"].to_numpy(), equal_nan=True)
    # the counts the command prints are the API's
    table = ", ".join(f"{k} {v}" for k, v in done.counts.items()) + f", failed {done.failed}"
    assert f"table: {table}" in printed
    assert sum(done.ran_counts.values()) == 4 and len(rows) == 4
    assert sorted(r["id"] for r in rows) == sorted(a["id"])
    assert done.load(trajectories=False).runs.shape == a.shape


def test_estimate_is_the_dry_run(sweeps, flow_cache_dir):
    done, _, _, root = sweeps
    cache = f"run.cache_dir={flow_cache_dir}"
    est = api.estimate("configs/quick.yaml", *SMALL, cache, output=root / "api")
    assert len(est.plan.tasks) == 4 and not est.plan.todo and est.timing == "finished"
    res = _cli(["run", "configs/quick.yaml", *SMALL, cache, "-o", root / "api", "--dry-run"])
    assert res.exit_code == 0, res.output
    assert "4 runs in the sweep; done 4 ok, 0 failed; to do now 0" in res.output
    assert f"({est.per_run_s:.2f} s per run, mean of the finished runs)" in res.output


def test_classify_gives_what_the_command_writes(sweeps):
    _, _, _, root = sweeps
    for name in ("api", "cli"):
        shutil.copytree(root / name, root / f"{name}-pivot")
    got = api.classify(root / "api-pivot", rule="pivot")
    res = _cli(["classify", root / "cli-pivot", "--rule", "pivot"])
    assert res.exit_code == 0, res.output
    assert got.thresholds.rule == "pivot" and not got.array and got.n_runs == 4
    assert f"re-classified 4 runs ({got.n_changed} changed)" in res.output
    assert got.counts.to_string(index=False) in res.output
    a, c = _runs(root / "api-pivot"), _runs(root / "cli-pivot")
    assert list(a["class"]) == list(c["class"]) and list(a["class_pivot"]) == list(c["class"])


def test_simulate_gives_what_the_command_prints(flow_cache_dir, tmp_path):
    cache = f"run.cache_dir={flow_cache_dir}"
    one = api.simulate("configs/quick.yaml", cache, theta0=-8, y0=0.39, length=1,
                       plot=tmp_path / "api.png")  # fmt: skip
    res = _cli(["simulate", "configs/quick.yaml", "--theta0", "-8", "--y0", "0.39",
                "--length", "1", cache, "--plot", tmp_path / "cli.png"])  # fmt: skip
    assert res.exit_code == 0, res.output
    r = one.result
    assert r.status == "ok" and one.array is None and np.isnan(one.returned)
    assert f"class: {r.cls}\n" in res.output
    assert f"delta: {r.delta:.4f} h_obs" in res.output
    assert f"steps: {r.n_steps} in" in res.output
    assert one.figure == tmp_path / "api.png" and one.figure.stat().st_size > 5000
    assert (tmp_path / "cli.png").stat().st_size > 5000


def test_flow_field_gives_what_the_command_prints(flow_cache_dir):
    cache = f"run.cache_dir={flow_cache_dir}"
    fields = api.flow_field("configs/quick.yaml", cache)
    res = _cli(["flow", "configs/quick.yaml", cache])
    assert res.exit_code == 0, res.output
    (rep,) = fields.reports
    assert fields.field is rep.field and rep.info.hit and rep.figure is None
    assert f"cache: hit  {rep.info.path}" in res.output
    est = rep.separatrix
    assert f"y/h_obs = {est.traced:.4f} +- {est.error:.4f}" in res.output


# --------------------------------------------------------------------------- errors


@pytest.mark.parametrize(
    ("override", "named"),
    [("sweep.thetaX=[1]", "sweep.thetaX"), ("fiber.contact.chii=1.2", "fiber.contact.chii")],
)
def test_a_bad_override_is_the_same_config_error(override, named, tmp_path):
    with pytest.raises(ConfigError) as exc:
        api.run("configs/quick.yaml", override, output=tmp_path / "out")
    message = str(exc.value)
    assert named in message
    res = _cli(["run", "configs/quick.yaml", override, "-o", tmp_path / "out"])
    assert res.exit_code == 2
    assert f"error: {message}" in res.output
    assert not (tmp_path / "out").exists()
    # a Config object takes the same overrides, with the same message for the field
    cfg = api.load_config("configs/quick.yaml")
    assert isinstance(cfg, Config)
    with pytest.raises(ConfigError, match=re.escape(named)):
        api.load_config(cfg, override)
    assert api.load_config(cfg, "flow.dx=2").flow.dx == 2.0


def test_a_channel_only_option_on_array_results_is_refused_alike(arrays):
    _, root = arrays
    with pytest.raises(fibersweep.errors.InputError, match="--rule") as exc:
        api.classify(root / "api", rule="pivot")
    res = _cli(["classify", root / "api", "--rule", "pivot"])
    assert res.exit_code == 2 and str(exc.value).split(";")[0] in res.output


def test_discrepancy_refuses_an_array_config_alike(tmp_path):
    measured = tmp_path / "m.csv"
    measured.write_text("theta0,y0,length,delta\n0,0.3,1.0,0.1\n")
    with pytest.raises(fibersweep.errors.InputError, match="single-pillar channel") as exc:
        api.discrepancy(measured, "configs/array.yaml", output=tmp_path / "r")
    res = _cli(["discrepancy", measured, "configs/array.yaml", "-o", tmp_path / "r"])
    assert res.exit_code == 2 and str(exc.value)[:60] in " ".join(res.output.split())


# --------------------------------------------------------------------------- array


@pytest.fixture(scope="module")
def arrays(tmp_path_factory, flow_cache_dir):
    """A tiny array sweep (2 shifts x 2 lengths x 2 starts), and a copy for the command."""
    root = tmp_path_factory.mktemp("api-array")
    done = api.run("configs/array.yaml", *ARRAY, f"run.cache_dir={flow_cache_dir}",
                   output=root / "api")  # fmt: skip
    shutil.copytree(root / "api", root / "cli")
    return done, root


def test_sort_report_gives_the_tables_the_command_writes(arrays):
    done, root = arrays
    assert done.ran == 8 and set(done.counts) >= {"zigzag", "trapped"}
    rep = api.sort_report(root / "api", target_length=20, figures=False)
    res = _cli(["sort-report", root / "cli", "--target-length", "20", "--no-figures"])
    assert res.exit_code == 0, res.output
    for name in ("migration.csv", "outlets.csv", "critical.csv"):
        assert (root / "api" / name).read_bytes() == (root / "cli" / name).read_bytes(), name
    assert [p.name for p in rep.tables] == ["migration.csv", "outlets.csv", "critical.csv"]
    pd.testing.assert_frame_equal(
        rep.migration.reset_index(drop=True), pd.read_csv(root / "cli" / "migration.csv"),
        check_dtype=False,
    )  # fmt: skip
    assert rep.key == "flow.array.shift" and sorted(rep.curve["value"]) == [0.1, 0.2]
    assert rep.target == 20 and len(rep.answers) == 1 and rep.figures == ()
    assert rep.answers[0].answer.text in " ".join(res.output.split("\n  "))
    assert f"tables: {root / 'cli' / 'migration.csv'}" in res.output
    # 3 rows are too few zigzag periods: a warning of both, naming the setting to change
    assert rep.short and any("3 rows are 0.3 zigzag periods" in w for w in rep.warnings)
    for w in rep.warnings:
        assert f"warning: {w}" in res.output and "[docs/" in w
    # the intervals: every critical length has one, and the printed ± says its level
    assert {"ci_lo", "ci_hi"} <= set(rep.critical.columns)
    assert {"ci_lo", "ci_hi"} <= set(pd.read_csv(root / "cli" / "critical.csv").columns)


def test_run_warns_outside_the_validated_range(arrays):
    done, _ = arrays
    (rows,) = [w for w in done.warnings if "zigzag periods" in w]
    assert "fiber.array_rows" in rows and "docs/arrays.md" in rows


def test_sort_report_warns_of_a_device_shorter_than_one_zigzag_period(arrays):
    _, root = arrays
    rep = api.sort_report(root / "api", rows=5, figures=False, write=False)
    (dev,) = [w for w in rep.warnings if "a device of 5 rows" in w]
    assert "--rows 10 or more" in dev  # 1/ε = 10 rows at ε = 0.1
    res = _cli(["sort-report", root / "cli", "--rows", "5", "--no-figures"])
    assert res.exit_code == 0 and f"warning: {dev}" in res.output


def test_simulate_refuses_a_start_on_a_pillar_before_the_field_naming_the_free_starts(
    tmp_path,
):
    """y0 = 0.2 at θ0 = 0 puts a 40 µm fiber on a pillar of configs/array.yaml: refused
    at once (no field solved into the empty cache, no kernel compiled), with the ranges
    of y0 that are free at that angle and length."""
    cache = tmp_path / "cache"
    with pytest.raises(fibersweep.errors.InputError, match="touches a pillar") as exc:
        api.simulate("configs/array.yaml", f"run.cache_dir={cache}", theta0=0, y0=0.2,
                     length=40)  # fmt: skip
    message = str(exc.value)
    assert "free starts at θ0 = 0°, L = 40 µm: y0 in [0.0000, " in message and " ∪ " in message
    assert not cache.exists() or not any(cache.iterdir())
    from fibersweep.sweep.draws import free_starts

    cfg = api.load_config("configs/array.yaml")
    spans = free_starts(cfg, 0.0, 40.0)
    assert all(not (a <= 0.2 <= b) for a, b in spans)
    mid = 0.5 * (spans[-1][0] + spans[-1][1])  # a free start is free by the run's own check
    from fibersweep.sweep.draws import check_start_of

    check_start_of(cfg, 0.0, mid, 40.0)
    res = _cli(["simulate", "configs/array.yaml", "--theta0", "0", "--y0", "0.2", "--length",
                "40", f"run.cache_dir={cache}"])  # fmt: skip
    assert res.exit_code == 2 and "free starts at θ0 = 0°" in res.output


def test_sort_report_refuses_the_same_input_as_the_command(arrays):
    _, root = arrays
    with pytest.raises(fibersweep.errors.InputError, match="--outlets"):
        api.sort_report(root / "api", outlets="1.5", figures=False, write=False)
    with pytest.raises(fibersweep.errors.InputError, match="--separate"):
        api.sort_report(root / "api", separate="20", figures=False, write=False)
    rep = api.sort_report(root / "api", outlets=[0.3, 0.7], separate=(10, 30), figures=False,
                          write=False)  # fmt: skip
    assert rep.target == 20 and rep.separate == (10.0, 30.0) and rep.tables == ()
    assert sorted(rep.outlets["outlet"].unique()) == [0, 1, 2]


def test_simulate_in_the_channel_names_the_free_starts_too(tmp_path):
    """Past one pillar the same: a vertical fiber whose beads leave the channel is refused
    before the field, with the y0 (in h_obs) where it fits."""
    cache = tmp_path / "cache"
    with pytest.raises(fibersweep.errors.InputError, match="outside the channel") as exc:
        api.simulate("configs/quick.yaml", f"run.cache_dir={cache}", theta0=90, y0=5.2,
                     length=1)  # fmt: skip
    assert "free starts at θ0 = 90°, L/l_obs = 1: y0 in [-4.4133, 5.0800] (y0/h_obs)" in str(
        exc.value
    )
    assert not cache.exists() or not any(cache.iterdir())
