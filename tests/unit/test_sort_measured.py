"""Measured fibers beside the model's f(L) (``sort-report --measured``).

The pure functions of :mod:`fibersweep.sorting.measured` on hand-built tables with
known answers (Wilson's textbook values, a step f(L) whose critical length is known,
the model's own runs given back as a measured table), then the command on a tiny
array sweep (dx = 4 µm, 3 rows, 3 lengths x 3 starts: seconds), whose own runs,
written as an array measured table, must come back as the model's numbers.
"""

from __future__ import annotations

import math

import matplotlib
import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from fibersweep import api
from fibersweep.cli import app
from fibersweep.errors import InputError
from fibersweep.sorting import measured as sm
from fibersweep.sorting.report import critical_table, migration_table

matplotlib.use("Agg")

LENGTHS = [4.0, 8.0, 12.0, 16.0, 20.0, 24.0, 32.0, 40.0]


def _runs(f_of_L, per_length: int = 6, trapped_at: dict | None = None) -> pd.DataFrame:
    """Model runs of one setting at LENGTHS: f from ``f_of_L``, the first k runs of a
    length trapped where ``trapped_at`` = {L: k}."""
    rows = []
    for L in LENGTHS:
        for k in range(per_length):
            trapped = k < (trapped_at or {}).get(L, 0)
            rows.append({"setting": 0, "setting_label": "", "length": L,
                         "mode": "trapped" if trapped else "zigzag",
                         "fraction": f_of_L(L, k), "migration_angle": 0.0})  # fmt: skip
    return pd.DataFrame(rows)


def _fibers(lengths: np.ndarray, f: np.ndarray, trapped: np.ndarray | None = None):
    trapped = np.zeros(len(lengths), bool) if trapped is None else trapped
    return pd.DataFrame({"length": lengths, "fraction": np.where(trapped, np.nan, f),
                         "trapped": trapped})  # fmt: skip


# --------------------------------------------------------------------------- pure functions


def test_wilson_gives_the_textbook_interval():
    # Wilson 1927 / Agresti & Coull 1998 at 95 %: 5 of 10 -> 0.2366 to 0.7634; 5 of 5 ->
    # 0.5655 to 1 (the docstring's "0.57 to 1"); 4-decimal tables, hence 1e-4
    lo, hi = sm.wilson(np.array([0.5, 1.0, 0.0]), np.array([10, 5, 5]))
    np.testing.assert_allclose(lo, [0.2366, 0.5655, 0.0], atol=1e-4)
    np.testing.assert_allclose(hi, [0.7634, 1.0, 0.4345], atol=1e-4)
    lo, hi = sm.wilson(0.3, 0)  # no fibers: no interval
    assert math.isnan(float(lo)) and math.isnan(float(hi))


def test_default_bins_are_one_per_simulated_length():
    np.testing.assert_array_equal(sm.length_edges([4, 8, 12, 20]), [2, 6, 10, 16, 24])
    np.testing.assert_array_equal(sm.length_edges([4, 20, 40]), [0, 12, 30, 50])  # not below 0
    np.testing.assert_array_equal(sm.parse_length_edges("2, 10,30"), [2, 10, 30])
    for bad in ("2", "10,2", "a,b"):
        with pytest.raises(InputError, match="--edges"):
            sm.parse_length_edges(bad)


def test_a_step_in_f_gives_its_critical_length_inside_the_interval():
    # every fiber shorter than 15 µm zigzags (f = 0), every longer one is displaced (f = 1):
    # the measured critical length is 15 µm, somewhere between the bins around it
    rng = np.random.default_rng(3)
    L = rng.uniform(2.0, 44.0, 400)
    model = migration_table(_runs(lambda L, k: float(L > 15.0)))
    m = sm.compare(_fibers(L, (L > 15.0).astype(float)), model)
    (c,) = m.critical.itertuples()
    assert c.rising and c.lo < 15.0 < c.hi
    # the bins 10-14 and 14-18 µm bracket the step: their mean lengths are the bracket
    assert c.lo == pytest.approx(m.bins.loc[m.bins["bin"] == 2, "length"].item())
    assert c.ci_lo <= 15.0 <= c.ci_hi and c.lo <= c.ci_lo and c.ci_hi <= c.hi
    # a plateau's bins: every fiber agrees, yet the Wilson interval keeps a share's width
    plateau = m.bins[m.bins["bin"] == 7].iloc[0]
    assert plateau["fraction_mean"] == 1.0 and plateau["fraction_lo"] < 0.95


def test_a_smooth_transition_is_located_by_many_fibers():
    # f a logistic share (each fiber displaced with probability 1/(1 + exp(-(L - 18)/3)))
    # and 150 fibers per bin: the 95 % interval holds 18 µm and, with a share's standard
    # error of 0.04 over a slope of 1/12 per µm, is a few µm wide, not a whole bracket
    rng = np.random.default_rng(11)
    edges = sm.length_edges(LENGTHS)
    L = np.concatenate([rng.uniform(a, b, 150) for a, b in zip(edges[:-1], edges[1:], strict=True)])
    f = (rng.random(L.size) < 1 / (1 + np.exp(-(L - 18.0) / 3.0))).astype(float)
    model = migration_table(_runs(lambda L, k: 0.0))
    (c,) = sm.compare(_fibers(L, f), model).critical.itertuples()
    assert c.ci_lo <= 18.0 <= c.ci_hi
    assert c.ci_hi - c.ci_lo < 4.0


def test_the_models_own_runs_come_back_as_the_models_numbers():
    # measured = the model's runs at the simulated lengths: each bin holds one length's
    # runs, so f, its spread and the critical length (the same critical_table on the same
    # numbers) are the model's to rounding
    runs = _runs(lambda L, k: (0.9 if L > 14 else 0.05) + 0.02 * (k % 3), trapped_at={20.0: 2})
    table = migration_table(runs)
    fibers = _fibers(runs["length"].to_numpy(), runs["fraction"].to_numpy(),
                     (runs["mode"] == "trapped").to_numpy())  # fmt: skip
    m = sm.compare(fibers, table)
    for col in ("length", "moving", "trapped", "fraction_mean", "fraction_std"):
        np.testing.assert_allclose(m.bins[col], table[col], rtol=1e-12, err_msg=col)
    np.testing.assert_allclose(m.model["fraction_mean"], table["fraction_mean"], rtol=1e-12)
    pd.testing.assert_frame_equal(m.critical, critical_table(table))
    assert m.trapped.trapped == 2 and m.trapped.model[0] == pytest.approx(2 / 48, abs=1e-12)


def test_trapped_share_of_the_model_is_taken_at_the_measured_lengths():
    # the model traps half its runs at 4 µm and none at 8 µm; 3 measured fibers at 4 µm
    # and 1 at 8 µm: the model's share at those lengths is (3 x 0.5 + 1 x 0) / 4
    model = migration_table(_runs(lambda L, k: 0.0, per_length=4, trapped_at={4.0: 2}))
    m = sm.compare(_fibers(np.array([4.2, 3.9, 4.0, 8.1]), np.zeros(4)), model)
    assert m.trapped.model[0] == pytest.approx(0.375, abs=1e-12)
    assert (m.trapped.trapped, m.trapped.fibers, m.trapped.share) == (0, 4, 0.0)


def test_fibers_outside_the_bins_are_counted_and_left_out():
    model = migration_table(_runs(lambda L, k: 0.0))
    m = sm.compare(_fibers(np.array([1.0, 5.0, 30.0, 90.0]), np.zeros(4)), model)
    assert (m.fibers, m.outside, m.binned) == (4, 2, 2)
    m = sm.compare(_fibers(np.array([5.0, 30.0]), np.zeros(2)), model, edges="0,20,50")
    assert list(m.bins["fibers"]) == [1, 1] and m.given_edges


@pytest.mark.parametrize(
    ("fibers", "named"),
    [
        (pd.DataFrame({"length": [10.0], "fraction": [0.1]}), "column trapped missing"),
        (_fibers(np.array([0.4, 0.9, 1.2]), np.zeros(3)), "length: .* L / l_obs"),
        (_fibers(np.array([80.0, 120.0]), np.zeros(2)), "length: no fiber inside the model's"),
        (pd.DataFrame({"length": [10.0], "fraction": [np.nan], "trapped": [False]}),
         "fraction: missing for a fiber that was not trapped"),
    ],
)  # fmt: skip
def test_a_table_that_cannot_be_compared_names_the_column(fibers, named):
    with pytest.raises(InputError, match=named):
        sm.compare(fibers, migration_table(_runs(lambda L, k: 0.0)))


def test_the_migration_figure_draws_the_measured_points():
    from fibersweep.plots.array_design import migration_figure

    runs = _runs(lambda L, k: float(L > 14))
    table = migration_table(runs)
    L = np.repeat(LENGTHS, 5) + 0.3
    m = sm.compare(_fibers(L, (L > 22).astype(float)), table)
    fig = migration_figure(table, {0: 5.7}, {0: ""}, critical_table(table), measured=m)
    texts = [t.get_text() for t in fig.legends[0].get_texts()]
    assert texts[0].startswith("model: critical") and texts[1].startswith("measured (40 fibers)")
    assert "critical 2" in texts[1]  # the measured critical length, between 20 and 24 µm


# --------------------------------------------------------------------------- the command


@pytest.fixture(scope="module")
def store(tmp_path_factory, flow_cache_dir):
    """A tiny array sweep (1 shift, 3 lengths x 3 starts, 3 rows) and its runs as an
    array measured table (the model's own fibers)."""
    out = tmp_path_factory.mktemp("measured") / "res"
    res = CliRunner().invoke(app, [
        "run", "configs/array.yaml", "flow.dx=4", "fiber.array_rows=3", "run.workers=1",
        "sweep.length=[4, 20, 40]", "sweep.random={count: 3, seed: 0}",
        f"run.cache_dir={flow_cache_dir}", f"run.output={out}",
    ])  # fmt: skip
    assert res.exit_code == 0, res.output
    runs = api.sort_report(out, figures=False, write=False).runs
    table = runs[["theta0", "y0", "length", "fraction"]].copy()
    table["trapped"] = (runs["mode"] == "trapped").to_numpy()
    table.loc[table["trapped"], "fraction"] = np.nan
    path = out.parent / "measured.csv"
    table.to_csv(path, index=False)
    return out, path, table


def test_sort_report_prints_the_measured_beside_the_model(store):
    out, path, _ = store
    res = CliRunner().invoke(app, ["sort-report", str(out), "--measured", str(path),
                                   "--no-figures"])  # fmt: skip
    assert res.exit_code == 0, res.output
    text = res.output
    assert "9 fibers, all in 3 length bins" in text and "95 % Wilson interval" in text
    assert "L bin [µm]" in text and "L mean [µm]" in text
    assert "critical length, model" in text and "trapped: measured" in text
    # the same runs cross 1/2 at the same length (f 0.52 at 4 µm, 0.19 at 20 µm)
    assert "measured - model: +0.0 µm; their 95 % intervals overlap" in text
    written = pd.read_csv(out / "measured.csv")
    # the model's own runs: measured f per bin is the model's f per length (to the CSV's
    # round trip of floats)
    mig = pd.read_csv(out / "migration.csv")
    np.testing.assert_allclose(written["fraction_mean"], mig["fraction_mean"], rtol=1e-9)
    np.testing.assert_allclose(written["model_fraction_0"], mig["fraction_mean"], rtol=1e-9)
    assert f"tables: {out / 'migration.csv'}, {out / 'outlets.csv'}, {out / 'measured.csv'}" in text


@pytest.mark.parametrize(
    ("change", "named"),
    [
        (lambda t: t.assign(length=t["length"] / 86.6), "length"),
        (lambda t: t.drop(columns="trapped"), "trapped"),
        (lambda t: t.assign(length=t["length"] + 500.0), "no fiber inside"),
    ],
)
def test_sort_report_refuses_a_table_it_cannot_compare(store, tmp_path, change, named):
    out, _, table = store
    bad = tmp_path / "bad.csv"
    change(table).to_csv(bad, index=False)
    res = CliRunner().invoke(app, ["sort-report", str(out), "--measured", str(bad),
                                   "--no-figures"])  # fmt: skip
    assert res.exit_code == 2, res.output
    assert named in res.output


def test_edges_without_a_measured_table_exit_2(store):
    out, _, _ = store
    res = CliRunner().invoke(app, ["sort-report", str(out), "--edges", "2,30", "--no-figures"])
    assert res.exit_code == 2 and "--measured" in res.output
