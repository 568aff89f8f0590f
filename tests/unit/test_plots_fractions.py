"""Class fractions with Wilson intervals, δ spread, and their commands.

The Wilson interval is checked against scipy's independent implementation
(``binomtest(...).proportion_ci(method="wilson")``) to 1e-12, and against a
textbook value: 0 of 10 at 95 % gives [0, 0.2775] (Brown, Cai & DasGupta 2001).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from _results_folder import refined_folder
from scipy.stats import binomtest
from typer.testing import CliRunner

from fibersweep.cli import app
from fibersweep.errors import InputError
from fibersweep.plots.fractions import (
    class_fractions,
    delta_by_figure,
    delta_spread,
    fractions_figure,
    wilson_interval,
)
from fibersweep.plots.style import paper_style


@pytest.mark.parametrize("level", [0.9, 0.95])
def test_wilson_interval_matches_scipy(level):
    for n in (1, 2, 7, 30, 250):
        for k in sorted({0, 1, n // 3, n - 1, n}):
            ci = binomtest(k, n).proportion_ci(confidence_level=level, method="wilson")
            lo, hi = wilson_interval(k, n, level)
            assert lo == pytest.approx(ci.low, abs=1e-12) and hi == pytest.approx(
                ci.high, abs=1e-12
            )
    assert wilson_interval(0, 10)[1] == pytest.approx(0.2775, abs=5e-5)


def _runs():
    rows = []
    for f in (0.0, 0.3):
        for k in range(20):
            cls = "Below" if k < 10 else "Above" if k < 17 - 4 * (f > 0) else "Trapping"
            rows.append({"id": f"{f}-{k}", "theta0": 0.0, "y0": k / 20, "length": 1.0,
                         "fiber.effects.friction": f, "status": "ok", "class": cls,
                         "delta": np.nan if cls == "Trapping" else 0.01 * k,
                         "settings": f"s{f}"})  # fmt: skip
    rows.append({**rows[0], "id": "bad", "status": "failed", "class": None})
    return pd.DataFrame(rows)


def test_class_fractions_count_classified_runs_per_value():
    fr = class_fractions(_runs(), "fiber.effects.friction").set_index(
        ["fiber.effects.friction", "class"]
    )
    assert fr.loc[(0.0, "Trapping"), "k"] == 3 and fr.loc[(0.3, "Trapping"), "k"] == 7
    assert (fr["n"] == 20).all()  # the failed run is not in n ...
    assert fr.loc[(0.0, "Below"), "failed"] == 1  # ... but is counted
    assert (fr["lo"] <= fr["fraction"]).all() and (fr["fraction"] <= fr["hi"]).all()
    with pytest.raises(InputError, match=r"--by 'frict': not a setting.*valid: .*length"):
        class_fractions(_runs(), "frict")


def test_delta_spread_and_figures():
    sp = delta_spread(_runs(), "fiber.effects.friction")
    assert list(sp["n"]) == [17, 13]  # trapped runs have no δ
    assert sp.loc[0, "median"] == pytest.approx(np.median(0.01 * np.arange(17)))
    with paper_style():
        fig = fractions_figure(_runs(), "fiber.effects.friction")
        assert "Wilson" in fig.axes[0].get_title() and "1 failed" in fig.axes[0].get_title()
        fig = delta_by_figure(_runs(), "fiber.effects.friction")
        assert "trapped" in fig.axes[0].get_title()


def test_commands_on_a_real_folder(tmp_path_factory, tmp_path):
    folder = refined_folder(tmp_path_factory.mktemp("sweep"))
    r = CliRunner().invoke(app, ["plot-fractions", str(folder), "-o", str(tmp_path / "f.png")])
    assert r.exit_code == 0, r.output
    assert "length = 0.8: Below" in r.output and (tmp_path / "f.png").stat().st_size > 5000
    r = CliRunner().invoke(app, ["plot-delta", str(folder), "-o", str(tmp_path / "d.png")])
    assert r.exit_code == 0, r.output
    assert "median δ" in r.output
    r = CliRunner().invoke(app, ["plot-fractions", str(folder), "--by", "nope"])
    assert r.exit_code == 2 and "not a setting" in r.output
