"""The discrepancy workflow in a pillar array: schema, observables, noise, synth, candidates.

Fast: the runs are a tiny array (the shipped config at dx = 4 µm, 3 rows, a dozen
fibers, one worker), its unit-cell field in the shared test cache as the array CLI
tests keep it (tests/unit/test_cli_arrays.py).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from fibersweep.cli import app
from fibersweep.config import load_config
from fibersweep.discrepancy.array_schema import (
    array_measured_data,
    load_array_measured,
    validate_array_measured,
)
from fibersweep.discrepancy.array_workflow import array_effect_names, array_library
from fibersweep.discrepancy.copies import NoiseModel, array_noise
from fibersweep.discrepancy.gap import value_matrices
from fibersweep.discrepancy.observables import (
    OBSERVABLES,
    geometry_of,
    noise_draws,
    of_geometry,
    scored,
    table_columns,
)
from fibersweep.discrepancy.scores import score_matrix
from fibersweep.discrepancy.simulate import _failed, outcome_row
from fibersweep.errors import InputError
from fibersweep.fiber.result import FiberStart, RunResult

SMALL = ["flow.dx=4", "fiber.array_rows=3", "run.workers=1"]


def _table(**cols) -> pd.DataFrame:
    base = dict(
        fiber_id=[1, 2, 3, 4],
        theta0=[0.0, 5.0, -5.0, 2.0],
        y0=[0.1, 0.5, 0.9, 0.3],
        length=[20.0, 40.0, 80.0, 120.0],
        fraction=[0.1, np.nan, 1.0, 0.95],
        trapped=[False, True, False, False],
        mode=["zigzag", "trapped", "displacement", "displacement"],
    )
    base.update(cols)
    return pd.DataFrame(base)


# ----------------------------------------------------------------------------- schema


def test_a_valid_array_table_is_canonicalised_and_round_trips_a_csv(tmp_path):
    t = validate_array_measured(_table(trapped=["false", "true", "0", "no"], mode=["ZigZag",
                                       "trapped", "displacement", "Displacement"]))  # fmt: skip
    assert list(t.columns) == ["fiber_id", "theta0", "y0", "length", "fraction", "trapped", "mode"]
    assert t["trapped"].tolist() == [False, True, False, False]
    assert t["mode"].tolist() == ["zigzag", "trapped", "displacement", "displacement"]
    assert t["fiber_id"].dtype == np.int64
    p = tmp_path / "m.csv"
    _table().to_csv(p, index=False)
    back = load_array_measured(p)
    pd.testing.assert_frame_equal(back, validate_array_measured(_table()), check_dtype=False)
    data = array_measured_data(back)
    assert data.observed == ("fraction", "trapped", "mode") and len(data) == 4


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (dict(fraction=[np.nan, np.nan, 1.0, 0.9]), r"fraction: missing/NaN value in row 1 "),
        (dict(fraction=[0.1, 0.5, 1.0, 0.9]), r"fraction: given for a trapped fiber in row 2"),
        (dict(mode=["zigzag", "zigzag", "displacement", "displacement"]),
         r"mode: 'trapped' must go with trapped = true .* row 2"),
        (dict(mode=["zigzag", "trapped", "bumped", "displacement"]),
         r"mode: unknown value in row 3 .*'bumped'.* valid: zigzag"),
        (dict(y0=[0.1, 0.5, 40.0, 0.3]), r"y0: out of range \[0, 1\] in row 3 .* period_y"),
        (dict(length=[0.0, 40.0, 80.0, 120.0]), r"length: out of range \(0, 10000\] in row 1"),
        (dict(trapped=[False, "maybe", False, False]), r"trapped: not a boolean .* row 2"),
        (dict(fiber_id=[1, 1, 3, 4]), r"fiber_id: duplicated in rows 1, 2"),
        (dict(rows_first=[1.5, 2, 0, 0]), r"rows_first: not a whole number in row 1"),
        (dict(Fraction2=[1, 2, 3, 4]), r"Fraction2: unknown column; did you mean 'fraction'"),
    ],
)  # fmt: skip
def test_each_problem_names_the_column_the_rule_and_the_rows(change, message):
    with pytest.raises(InputError, match=message):
        validate_array_measured(_table(**change))


def test_a_missing_required_column_is_named():
    with pytest.raises(InputError, match="missing required column.*trapped"):
        validate_array_measured(_table().drop(columns="trapped"))


# ----------------------------------------------------------------------------- observables


def _array_run(mode: str, fraction: float, e2e: float = math.nan) -> RunResult:
    return RunResult(start=FiberStart(0.0, 0.3, 40.0), status="ok", rows=3, fraction=fraction,
                     mode=mode, wraps=0, min_end_to_end=e2e)  # fmt: skip


def test_each_geometry_scores_only_its_own_observables():
    channel, array = set(scored(tracks=True)), set(scored(geometry="array"))
    assert not channel & array
    assert scored(geometry="array") == ("fraction", "trapped", "mode", "bend")
    assert table_columns() == ("class", "delta", "contact", "theta_c", "y_c", "t_pass",
                               "t_contact")  # the channel's table is as before  # fmt: skip
    assert set(of_geometry("channel")) | set(of_geometry("array")) == set(OBSERVABLES)
    assert geometry_of(["fraction", "mode"]) == "array" and geometry_of(["delta"]) == "channel"


def test_an_array_run_gives_its_observables_and_a_trapped_run_no_fraction():
    row = outcome_row(_array_run("displacement", 0.93, e2e=0.9))
    assert set(row) == {*of_geometry("array"), "status", "reason"}
    assert row["fraction"] == 0.93 and row["trapped"] == 0.0 and row["mode"] == "displacement"
    assert row["bend"] == pytest.approx(0.1)  # 1 - end-to-end / contour
    trapped = outcome_row(_array_run("trapped", 0.4))
    assert math.isnan(trapped["fraction"]) and trapped["trapped"] == 1.0
    assert math.isnan(trapped["bend"])  # rigid: no bending
    # a run that failed before it started has no mode: the batch says it is an array's
    failed = outcome_row(RunResult(start=FiberStart(0, 0.3, 40), status="failed",
                                   reason="touches a pillar"), array=True)  # fmt: skip
    assert failed == _failed("touches a pillar", array=True)
    assert failed["mode"] is None and math.isnan(failed["fraction"])


def test_array_observables_score_like_any_registry_entry():
    t = array_measured_data(validate_array_measured(_table()))
    runs = [
        _array_run(m, f)
        for m, f in (("zigzag", 0.12), ("trapped", 0.0), ("displacement", 0.98), ("mixed", 0.6))
    ]
    copies = [pd.DataFrame([outcome_row(r) for r in runs])] * 3
    V = value_matrices(t.table, copies, t.observed)
    assert list(V) == ["fraction", "trapped", "mode"]
    # fraction is undefined exactly for the trapped fiber, in the data and the copies
    assert np.array_equal(np.isfinite(V["fraction"][:, 0]), [True, False, True, True])
    for name, v in V.items():
        s = score_matrix(name, v)
        assert np.isfinite(s[np.isfinite(v[:, 0])]).all()


# ----------------------------------------------------------------------------- noise


def test_array_noise_wraps_y0_reflects_length_at_one_bead_and_draws_fraction_noise():
    cfg = load_config("configs/array.yaml")
    nm = array_noise(cfg.fiber)
    assert nm.geometry == "array" and nm.min_length == 4.0  # 2a of 2 µm beads
    assert set(nm.outcome) == {"fraction", "bend"}  # the array's laws, none of the channel's
    starts = np.array([[0.0, 0.999, 4.2], [0.0, 0.001, 4.1]] * 500)
    out = nm.jitter_starts(starts, np.random.default_rng(1))
    assert ((out[:, 1] >= 0) & (out[:, 1] < 1)).all()  # the lattice repeats every period_y
    assert (out[:, 2] >= 4.0).all()  # no fiber shorter than one bead
    # fraction: additive, sd 0.01; 20000 draws estimate the sd to 0.5 % (1/sqrt(2n)),
    # checked to 3 % (6 sigma: this test cannot flake)
    n = 20000
    outc = pd.DataFrame({"fraction": np.full(n, 0.5), "bend": np.full(n, np.nan)})
    noisy = nm.observe(outc, noise_draws([3, 4], n))
    assert np.std(noisy["fraction"] - 0.5) == pytest.approx(0.01, rel=0.03)
    assert noisy["bend"].isna().all()  # NaN stays NaN
    with pytest.raises(InputError, match="no measurement noise law for delta"):
        NoiseModel(outcome={"delta": 0.1}, geometry="array")


# ----------------------------------------------------------------------------- candidates


def test_library_effects_that_change_the_channel_are_refused_by_name():
    assert array_library() == ("friction", "pillar_hydro", "off_midplane", "brownian")
    cfg = load_config("configs/array.yaml")
    with pytest.raises(InputError, match="--effect inlet_speed: .*friction, pillar_hydro"):
        array_effect_names(("friction", "inlet_speed"), cfg.fiber)


def test_a_row_shift_off_the_lattice_is_refused_naming_the_field():
    from fibersweep.api.compare import declared_candidates

    cfg = load_config("configs/array.yaml", SMALL)  # dx = 4 µm: 10 µm is not whole cells
    with pytest.raises(InputError, match=r"flow.array.shift=0.125.*not a whole number of lattice"):
        declared_candidates(cfg, ["flow.array.shift=0.125"])
    (c,) = declared_candidates(cfg, ["flow.array.shift=0.15"])  # 12 µm: 3 cells
    assert c.key == "flow.array.shift" and c.choice == 0.15


# ----------------------------------------------------------------------------- synth (runs)


@pytest.fixture(scope="module")
def synth_table(tmp_path_factory, flow_cache_dir):
    out = tmp_path_factory.mktemp("synth") / "m.csv"
    res = CliRunner().invoke(app, ["synth", "configs/array.yaml", *SMALL, "--n", "10",
                                   "--seed", "3", "--effect", "friction=0.5",
                                   f"run.cache_dir={flow_cache_dir}", "-o", str(out)])  # fmt: skip
    assert res.exit_code == 0, res.output
    return out, res.output


def test_synth_on_an_array_config_writes_an_array_measured_table(synth_table):
    import json

    path, printed = synth_table
    assert "through 3 rows" in printed and "length [µm]" in printed
    t = load_array_measured(path)  # the writer's output follows the schema
    truth = json.loads(path.with_suffix(".truth.json").read_text())
    assert truth["effects"] == {"friction": 0.5} and truth["geometry"] == "array"
    assert len(t) + len(truth["failed"]) == 10
    assert {"fraction", "trapped", "mode"} <= set(t.columns) and "bend" not in t.columns
    # reported starts are the true ones plus the start noise (θ0 1°, y0 0.01, L 1 µm):
    # within 6 sd of them, and not equal to them
    ts = truth["true_starts"]
    for col, sd in (("theta0", 1.0), ("length", 1.0)):
        d = t[col].to_numpy() - np.asarray(ts[col])
        assert (np.abs(d) < 6 * sd).all() and (d != 0).all()
    dy = (t["y0"].to_numpy() - np.asarray(ts["y0"]) + 0.5) % 1.0 - 0.5  # periodic
    assert (np.abs(dy) < 0.06).all()
    assert ((t["mode"] == "trapped") == t["trapped"]).all()


def test_synth_refuses_an_effect_that_changes_the_single_pillar(tmp_path, flow_cache_dir):
    res = CliRunner().invoke(app, ["synth", "configs/array.yaml", *SMALL, "--n", "4",
                                   "--effect", "inlet_speed=0.1",
                                   f"run.cache_dir={flow_cache_dir}",
                                   "-o", str(tmp_path / "m.csv")])  # fmt: skip
    assert res.exit_code == 2, res.output
    assert "inlet_speed" in res.output and "not available in pillar arrays" in res.output


def test_discrepancy_on_an_array_config_reports_in_the_array_terms(synth_table, tmp_path,
                                                                     flow_cache_dir):  # fmt: skip
    import json

    path, _ = synth_table
    out = tmp_path / "rep"
    res = CliRunner().invoke(app, ["discrepancy", str(path), "configs/array.yaml", *SMALL,
                                   f"run.cache_dir={flow_cache_dir}", "--copies", "2",
                                   "--pairs", "0", "--no-power", "--no-next",
                                   "--effect", "friction", "--candidate", "flow.array.shift=0.15",
                                   "--budget", "150", "-o", str(out)])  # fmt: skip
    assert res.exit_code == 0, res.output
    # the plan states the candidate field's cost (solved once, or found in the cache)
    assert "flow.array.shift=0.15: its unit-cell field" in res.output
    s = json.loads((out / "summary.json").read_text())
    assert s["observables"] == ["fraction", "trapped", "mode"]
    assert s["observables_absent"] == ["bend"]  # the array's, none of the channel's
    assert (out / "phase_before_after.png").stat().st_size > 5000  # f against L


def test_array_discrepancy_refuses_channel_tables_and_tracks(tmp_path, flow_cache_dir):
    channel = tmp_path / "c.csv"
    channel.write_text("theta0,y0,length,class\n0,0.3,1.0,Above\n")
    base = ["discrepancy", str(channel), "configs/array.yaml", *SMALL, "-o", str(tmp_path / "r")]
    res = CliRunner().invoke(app, base)
    assert res.exit_code == 2 and "missing required column(s) fraction, trapped" in res.output
    res = CliRunner().invoke(app, [*base, "--trajectories", str(channel)])
    assert res.exit_code == 2 and "channel frame" in res.output, res.output


def test_lengths_shorter_than_a_bead_are_refused_naming_the_rows():
    """A fiber shorter than one bead (2a) cannot run; lengths all below 2 µm are named as
    L / l_obs. Exact rule, no tolerance: 2a itself is allowed."""
    from fibersweep.api.compare import check_array_lengths

    check_array_lengths(np.array([4.0, 40.0]), 2.0, "t.csv")  # one bead: allowed
    with pytest.raises(InputError, match=r"row 2 .*3 µm") as exc:
        check_array_lengths(np.array([10.0, 3.0]), 2.0, "t.csv")
    assert "l_obs" not in str(exc.value)
    with pytest.raises(InputError, match="look like fractions L / l_obs"):
        check_array_lengths(np.array([0.5, 0.8]), 2.0, "t.csv")


def test_an_array_candidate_on_a_channel_config_is_refused():
    from fibersweep.api.compare import declared_candidates

    cfg = load_config("configs/quick.yaml")
    with pytest.raises(InputError, match="flow.array settings are a pillar array's"):
        declared_candidates(cfg, ["flow.array.shift=0.15"])


def test_a_misspelled_required_column_gets_a_did_you_mean(tmp_path):
    from fibersweep.discrepancy.array_schema import load_array_measured

    path = tmp_path / "m.csv"
    pd.DataFrame({"theta0": [0.0], "y0": [0.5], "length": [40.0], "fracton": [0.1],
                  "trapped": [False]}).to_csv(path, index=False)  # fmt: skip
    with pytest.raises(InputError, match="did you mean 'fraction'"):
        load_array_measured(path)
