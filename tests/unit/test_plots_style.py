"""One figure style: the package's .mplstyle is shipped and every figure is drawn in it."""

from __future__ import annotations

import matplotlib as mpl
import numpy as np
import pandas as pd

from fibersweep.plots import phase
from fibersweep.plots.style import STYLE_FILE, paper_style


def test_style_file_is_package_data_and_applies():
    assert STYLE_FILE.is_file()
    before = dict(mpl.rcParams)
    with paper_style():
        assert mpl.rcParams["font.size"] == 9
        assert mpl.rcParams["savefig.dpi"] == 200
        assert mpl.rcParams["axes.prop_cycle"].by_key()["color"][0].lower() == "#0072b2"
    assert mpl.rcParams["font.size"] == before["font.size"]  # restored


def _runs(lengths):
    rows = []
    for L in lengths:
        for th in (-8.0, 0.0, 8.0):
            for y0 in (0.2, 0.4, 0.6):
                rows.append(dict(theta0=th, y0=y0, length=L, status="ok", contact=y0 == 0.4,
                                 **{"class": "Below" if y0 < 0.3 else "Above"},
                                 delta=0.2 if y0 == 0.4 else 0.001 * y0,
                                 theta_c=10.0 if y0 == 0.4 else np.nan,
                                 y_c=0.5 if y0 == 0.4 else np.nan))  # fmt: skip
    return pd.DataFrame(rows)


def test_single_length_is_stated():
    with paper_style():
        fig = phase.phase_figure(_runs([0.82]), 0.35, "class", col=None)
        assert "0.82" in fig.axes[0].get_title() and "L/l" in fig.axes[0].get_title()
        fig = phase.phase_figure(_runs([0.82, 1.0]), 0.35, "class", col="length")
        assert all("L/l" in ax.get_title() for ax in fig.axes if ax.get_visible())


def test_delta_histogram_keeps_single_counts_visible_and_same_precision():
    runs = _runs([1.0])
    with paper_style():
        fig = phase.delta_hist_figure(runs)
    ax = fig.axes[0]
    assert ax.get_yscale() == "log" and ax.get_ylim()[0] < 1.0  # a count of 1 is above the axis
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    decimals = {lab.split("sd = ")[1].split(".")[1].__len__() for lab in labels}
    assert len(labels) == 2 and len(decimals) == 1
