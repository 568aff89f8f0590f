"""The pillar array's figures, checked without looking: both crossings of a band-pass,
a log axis for a stiffness, panels grouped by setting, recovery apart from purity,
words instead of config keys, animation frames of a readable size."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from fibersweep.config.flow import FlowSettings
from fibersweep.plots import array as pa
from fibersweep.plots import array_design as pd_
from fibersweep.plots.array_chrono import animate_array_run, fraction_text
from fibersweep.plots.fractions import fractions_figure
from fibersweep.plots.labels import describe
from fibersweep.sorting.design import critical_curve
from fibersweep.sorting.report import critical_table

E = "fiber.young_modulus"
SHIFT = "flow.array.shift"


def _texts(fig) -> list[str]:
    """Every text of a figure: titles, axis labels, legend entries, annotations."""
    out = [t.get_text() for t in fig.findobj(lambda a: hasattr(a, "get_text"))]
    return [t for t in out if t]


def _no_keys(fig) -> None:
    for t in _texts(fig):
        assert E not in t and SHIFT not in t and "young_modulus" not in t, t


def _band_pass():
    """f against length for three stiffnesses: 10 kPa a band (rises, then falls at
    ~51.5 µm), 100 kPa above 1/2 at every length, 1 MPa a high-pass."""
    L = [20.0, 40.0, 60.0, 80.0]
    fs = {0: [0.2, 0.8, 0.3, 0.2], 1: [0.9, 0.9, 0.9, 0.9], 2: [0.3, 0.7, 0.9, 0.9]}
    table = pd.DataFrame([{"setting": s, "length": x, "fraction_mean": v, "fraction_se": 0.05}
                          for s, f in fs.items() for x, v in zip(L, f, strict=True)])  # fmt: skip
    settings = [{"values": {E: v}} for v in (1.0e4, 1.0e5, 1.0e6)]
    crit = critical_table(table)
    return critical_curve(crit, table, settings, E), crit


def _markers(ax, marker: str) -> list:
    return [ln for ln in ax.lines if ln.get_marker() == marker and len(ln.get_xdata())]


def _ys(ax, marker: str) -> np.ndarray:
    return np.concatenate([np.asarray(ln.get_ydata(), float) for ln in _markers(ax, marker)])


def test_critical_figure_draws_rising_and_falling_crossings_on_a_log_axis():
    curve, crit = _band_pass()
    assert (crit["setting"] == 0).sum() == 2  # the band: a rising and a falling crossing
    fig = pd_.critical_figure(curve, E, "Pa", crossings=crit)
    ax = fig.axes[0]
    assert ax.get_xscale() == "log"
    assert ax.get_xlabel() == "Young's modulus E [kPa]"
    rising, falling = _ys(ax, "o"), _ys(ax, "v")
    assert sorted(rising) == pytest.approx(sorted(crit.loc[crit["rising"], "critical"]))
    assert falling == pytest.approx(crit.loc[~crit["rising"], "critical"])
    xs = np.concatenate([np.asarray(ln.get_xdata(), float) for ln in _markers(ax, "v")])
    assert xs == pytest.approx([10.0], rel=0.1)  # 10 kPa's (set a little apart)
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert any("rises" in t for t in labels) and any("falls" in t for t in labels)
    assert len(ax.get_title().splitlines()) == 1  # the key is a legend, not the title
    _no_keys(fig)
    # without the crossings table, the curve's one crossing per setting is still drawn
    ax = pd_.critical_figure(curve, E).axes[0]
    assert len(_ys(ax, "o")) == 2


def test_critical_figure_of_a_linear_setting():
    table = pd.DataFrame({"setting": [0, 0, 1, 1], "length": [10.0, 20.0] * 2,
                          "fraction_mean": [0.2, 0.8, 0.1, 0.6], "fraction_se": 0.05})  # fmt: skip
    settings = [{"values": {SHIFT: v}} for v in (0.1, 0.2)]
    crit = critical_table(table)
    fig = pd_.critical_figure(critical_curve(crit, table, settings, SHIFT), SHIFT,
                              crossings=crit)  # fmt: skip
    assert fig.axes[0].get_xscale() == "linear"
    assert fig.axes[0].get_xlabel() == "row shift ε"


def _runs(settings: dict[int, float], lengths, key=SHIFT, per=3):
    rows = []
    for s, v in settings.items():
        for L in lengths:
            for k in range(per):
                x = np.linspace(0.0, 400.0, 20)
                rows.append({"id": f"{s}-{L}-{k}", "setting": s, "setting_label": f"{key}={v}",
                             key: v, "length": L, "status": "ok", "theta0": 0.0, "y0": 0.5,
                             "mode": ["zigzag", "displacement", "trapped"][(k + s) % 3],
                             "settings": f"s{s}", "traj_xc": x,
                             "traj_yc": 0.1 * x * s})  # fmt: skip
    return pd.DataFrame(rows)


def test_track_panels_are_a_grid_of_settings_by_lengths_never_a_wrap():
    runs = _runs({0: 0.1, 1: 0.125, 2: 0.15, 3: 0.2}, [4.0, 8.0, 12.0, 16.0, 20.0, 24.0, 32.0,
                                                       40.0])  # fmt: skip
    labels = describe([{"values": {SHIFT: v}} for v in (0.1, 0.125, 0.15, 0.2)])
    fig = pa.overlay_figure(runs, 80.0, shifts={s: 8.0 for s in range(4)}, labels=labels)
    grid = np.array(fig.axes).reshape(4, 8)  # one row per shift, one column per length
    for r, ax_row in enumerate(grid):
        assert ax_row[0].get_ylabel().startswith(labels[r])
        for ax in ax_row:
            # the panel's runs are its row's setting: their lateral slope is 0.1 × s
            ys = [ln.get_ydata()[-1] for ln in ax.lines if len(ln.get_xdata()) == 20]
            assert ys and np.allclose(ys, 0.1 * 400.0 * r)
    assert [ax.get_title() for ax in grid[0]][:2] == ["L = 4 µm", "L = 8 µm"]
    assert all(t.get_fontsize() >= 8 for t in (grid[0, 0].title, grid[0, 0].yaxis.label))
    _no_keys(fig)


def test_one_setting_names_it_in_the_title_and_balances_its_rows():
    runs = _runs({0: 1.0e4}, [20.0, 40.0, 60.0, 80.0, 120.0, 160.0], key=E)
    fig = pa.overlay_figure(runs, 80.0, labels={0: "E = 10 kPa"}, title="length > 10")
    assert np.array([ax.get_visible() for ax in fig.axes]).reshape(2, 3).all()  # 3 + 3
    assert fig.get_suptitle() == "E = 10 kPa, selected: length > 10"


def test_outlets_figure_keeps_recovery_and_purity_apart():
    rows = []
    for s in (0, 1, 2):
        for k, (lo, hi) in enumerate(((-np.inf, 0.5), (0.5, np.inf))):
            for L in (4.0, 20.0, 40.0):
                rec = 1.0 if (L == 4.0) == (k == 0) else 0.0
                rows.append({"setting": s, "outlet": k, "from": lo, "to": hi, "length": L,
                             "recovery": rec, "purity": rec / 1.0, "trapped": 0.0})  # fmt: skip
    fig = pd_.outlets_figure(pd.DataFrame(rows), {0: "ε = 0.1", 1: "ε = 0.15", 2: "ε = 0.2"})
    titles = [ax.get_title() for ax in fig.axes if ax.get_visible() and ax.axison]
    rec = [t for t in titles if t.endswith("recovery")]
    pur = [t for t in titles if t.endswith("purity")]
    assert len(rec) == 2 and len(pur) == 2  # each outlet's recovery and purity: two panels
    styles = {ln.get_linestyle() for ax in fig.axes for ln in ax.lines}
    assert styles == {"-"}  # one line style; the settings differ by colour and marker
    legend = [t.get_text() for ax in fig.axes if ax.get_legend() for t in
              ax.get_legend().get_texts()]  # fmt: skip
    assert legend == ["ε = 0.1", "ε = 0.15", "ε = 0.2"]


def _array_runs():
    """Array runs over E (a decade) and two shifts, at two lengths."""
    rows = []
    for E_, shift, L, k in np.array(np.meshgrid([1.0e4, 1.0e5], [0.1, 0.2], [20.0, 80.0],
                                                range(4))).reshape(4, -1).T:  # fmt: skip
        rows.append({"id": f"{E_}-{shift}-{L}-{k}", E: E_, SHIFT: shift, "length": L,
                     "theta0": 0.0, "y0": 0.5, "status": "ok", "settings": f"{E_}-{shift}",
                     "mode": "zigzag" if k < 2 else "displacement"})  # fmt: skip
    return pd.DataFrame(rows)


def test_array_fractions_never_pool_a_setting_and_put_a_stiffness_on_a_log_axis():
    runs = _array_runs()
    one = runs[runs["length"] == 80.0]
    fig = fractions_figure(one, E)  # the shifts: one panel each, not pooled
    shown = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_title() for ax in shown] == ["ε = 0.1", "ε = 0.2"]
    assert all(ax.get_xscale() == "log" for ax in shown)
    assert shown[0].get_xlabel() == "Young's modulus E [kPa]"
    assert "L = 80 µm" in fig.get_suptitle() and "l_{obs}" not in fig.get_suptitle()
    assert "pooled" not in " ".join(_texts(fig))
    _no_keys(fig)
    fig = fractions_figure(one[one[SHIFT] == 0.1], E)  # one panel: the title says what is fixed
    assert "L = 80 µm" in fig.axes[0].get_title() and "ε = 0.1" in fig.axes[0].get_title()
    fig = fractions_figure(runs[runs[SHIFT] == 0.1], "length")  # rows: E, columns: none
    assert sorted(ax.get_title() for ax in fig.axes) == ["E = 10 kPa", "E = 100 kPa"]
    fig = fractions_figure(runs, "length")  # two other settings: a grid, E by shift
    assert np.shape(fig.axes) == (4,) and fig.axes[1].get_title() == "E = 10 kPa, ε = 0.2"


def test_fraction_text_says_what_a_run_without_f_is():
    assert fraction_text({"fraction": 0.934, "mode": "displacement"}) == "f = 0.93"
    assert fraction_text({"fraction": float("nan"), "mode": "trapped", "rows": 0}) == (
        "trapped before row 1 (no f)"
    )
    assert fraction_text({"fraction": None, "mode": "zigzag"}) == "f = —"


def test_animation_frames_are_readable_and_the_clock_clear_of_the_pillars(tmp_path, monkeypatch):
    from PIL import Image

    arr = FlowSettings.model_validate({"dx": 4.0, "array": {}}).array.to_array()
    t = np.linspace(0.0, 1.0, 6)
    run = {"traj_t": t, "traj_xc": np.linspace(-30.0, 10.0, 6), "traj_yc": np.full(6, 30.0),
           "traj_th": np.full(6, np.pi / 2), "n_beads": 5, "mode": "trapped", "rows": 0,
           "fraction": float("nan"), "length": 20.0, "y0": 0.4, "theta0": 2.0}  # fmt: skip
    out = animate_array_run(run, arr, 2.0, tmp_path / "a.gif", frames=3, label="E = 10 kPa")
    with Image.open(out) as im:
        assert im.size[0] >= 1000
    import matplotlib.figure

    drawn = []
    real = matplotlib.figure.Figure.savefig

    def keep(self, *a, **k):
        drawn.append(self)
        return real(self, *a, **k)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", keep)
    animate_array_run(run, arr, 2.0, tmp_path / "b.gif", frames=2)
    fig = drawn[0]  # the clock is the axes' title (above them, where no pillar is)
    ax = fig.axes[0]
    assert ax.get_title(loc="left").startswith("t = ")
    texts = " ".join(_texts(fig))
    assert "nan" not in texts and "trapped before row 1" in texts


def test_migration_figure_quotes_each_critical_length_with_its_95_percent_interval():
    """The legend and the shaded band carry the critical table's 95 % interval (scatter
    and interpolation), never the statistical error alone, which is far narrower."""
    table = pd.DataFrame(
        [{"setting": 0, "length": x, "fraction_mean": f, "fraction_se": 0.03,
          "angle_mean": 5.0 * f, "angle_std": 0.5, "trapped": 0.0}
         for x, f in ((4.0, 0.01), (20.0, 0.74), (40.0, 0.93))]
    )  # fmt: skip
    crit = critical_table(table)
    r = crit.iloc[0]
    assert r.ci_hi - r.ci_lo > 2 * r.se  # the case the figure must not hide
    fig = pd_.migration_figure(table, {0: 5.7}, {0: ""}, crit)
    legend = " ".join(t for t in _texts(fig) if "critical" in t)
    assert f"{r.critical:.1f} (95 %: {r.ci_lo:.1f} to {r.ci_hi:.1f})" in legend, legend
    assert "±" not in legend
    spans = [p for p in fig.axes[0].patches if p.get_width() > 0]
    assert any(abs(p.get_x() - r.ci_lo) < 1e-9 and abs(p.get_width() - (r.ci_hi - r.ci_lo))
               < 1e-9 for p in spans)  # fmt: skip
