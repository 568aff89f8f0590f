"""Every command on a pillar array's results, rigid and flexible, through the CLI.

Each command either answers in the array's terms (a table, a figure, a page) or
exits 2 naming the command that does. Two small sweeps (dx = 4 µm, 3 rows, a few
seeded starts) stand for ``configs/array.yaml`` and ``configs/array-flexible.yaml``.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from fibersweep.cli import app

SMALL = ["flow.dx=4", "fiber.array_rows=3", "run.workers=1"]


def _run(args: list[str]):
    res = CliRunner().invoke(app, args)
    return res


@pytest.fixture(scope="module")
def rigid(tmp_path_factory, flow_cache_dir):
    """A shift sweep of rigid fibers: 2 shifts x 3 lengths x 3 starts."""
    out = tmp_path_factory.mktemp("rigid") / "res"
    res = _run(["run", "configs/array.yaml", *SMALL, "sweep.length=[4, 20, 40]",
                "sweep.flow.array.shift=[0.1, 0.2]", "sweep.random={count: 3, seed: 0}",
                f"run.cache_dir={flow_cache_dir}", f"run.output={out}"])  # fmt: skip
    assert res.exit_code == 0, res.output
    return out


@pytest.fixture(scope="module")
def flexible(tmp_path_factory, flow_cache_dir):
    """Bead-spring fibers of 10 kPa (bead positions kept, as the shipped config does)."""
    out = tmp_path_factory.mktemp("flex") / "res"
    res = _run(["run", "configs/array-flexible.yaml", *SMALL, "sweep.fiber.young_modulus=[1.0e+4]",
                "sweep.length=[20, 40]", "sweep.random={count: 2, seed: 0}",
                f"run.cache_dir={flow_cache_dir}", f"run.output={out}"])  # fmt: skip
    assert res.exit_code == 0, res.output
    # touching beads at 10 kPa are not converged: the run says so, once
    assert res.output.count("touching beads are not converged") == 1
    return out


@pytest.fixture(params=["rigid", "flexible"])
def results(request):
    return request.getfixturevalue(request.param)


@pytest.mark.parametrize(
    ("command", "named"),
    [("plot-phase", "sort-report"), ("plot-delta", "sort-report")],
)
def test_channel_figures_refuse_array_results_naming_the_command_to_use(results, command, named):
    res = _run([command, str(results)])
    assert res.exit_code == 2, res.output
    assert "pillar-array" in res.output and named in res.output
    assert not (results / "figures" / "phase.png").exists()


def test_plot_fractions_draws_modes_against_a_setting(results):
    res = _run(["plot-fractions", str(results), "--by", "length"])
    assert res.exit_code == 0, res.output
    assert (results / "figures" / "fractions-length.png").stat().st_size > 5000
    printed = {line.split(": ")[1].split()[0] for line in res.output.splitlines() if ": " in line}
    assert printed <= {"zigzag", "displacement", "wrap-and-jump", "trapped", "mixed", "wrote"}


def test_plot_tracks_draws_displacement_against_rows(results, tmp_path):
    res = _run(["plot-tracks", str(results), "-o", str(tmp_path / "t.png")])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "t.png").stat().st_size > 5000


def test_animate_follows_a_run_through_the_rows(results, tmp_path):
    res = _run(["animate", str(results), "--where", "length == 20", "--frames", "4",
                "-o", str(tmp_path / "a.gif")])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert (tmp_path / "a.gif").read_bytes()[:3] == b"GIF"


def _page_data(path):
    html = path.read_text()
    m = re.search(r'<script id="data" type="application/json">(.*?)</script>', html, re.S)
    return json.loads(m.group(1))


def test_explore_page_of_array_results(results, tmp_path):
    out = tmp_path / "e.html"
    res = _run(["explore", str(results), "-o", str(out)])
    assert res.exit_code == 0, res.output
    data = _page_data(out)
    assert data["frame"] == "array" and "zigzag" in data["classes"]
    sid = next(iter(data["lattices"]))
    assert data["lattices"][sid]["px"] == 80.0
    cols = data["columns"]
    beads = {r[cols.index("id")]: r[cols.index("n_beads")] for r in data["rows"]}
    model = {r[cols.index("id")]: r[cols.index("model")] for r in data["rows"]}
    for rid, tr in data["tracks"].items():
        assert tr["fibers"], rid
        for xs, ys in tr["fibers"]:  # a bent fiber: every bead; a rigid one: its two ends
            assert len(xs) == len(ys) == (beads[rid] if model[rid] != "rigid" else 2)


def test_classify_and_check_work_on_array_results(results):
    res = _run(["classify", str(results)])
    assert res.exit_code == 0, res.output
    assert "modes" in res.output and "(0 changed)" in res.output
    assert _run(["check", str(results)]).exit_code == 0
    # a channel's class rule means nothing for modes: refused, naming what applies
    res = _run(["classify", str(results), "--rule", "pivot"])
    assert res.exit_code == 2 and "--trap-time" in res.output and "sort-report" in res.output
    # a trap time longer than the run's own cannot un-trap a run that stopped there: said
    # where some run is trapped
    import fibersweep

    trapped = (fibersweep.load(results, trajectories=False).runs["mode"] == "trapped").any()
    res = _run(["classify", str(results), "--trap-time", "5"])
    assert res.exit_code == 0
    assert ("cannot tell whether they would have moved on" in res.output) == trapped
    res = _run(["classify", str(results), "--trap-time", "2"])  # back to the run's rule
    assert res.exit_code == 0 and "cannot tell" not in res.output


def test_sort_report_is_a_designer_page(rigid):
    res = _run(["sort-report", str(rigid), "--target-length", "20"])
    assert res.exit_code == 0, res.output
    out = res.output
    assert "trapped" in out and "critical length against shift" in out
    assert "target critical length 20 µm" in out
    # each critical length with its interval and its level, the statistical error apart
    assert re.search(r"µm \(95 %: [-\d.]+ to [-\d.]+ µm; statistical alone ± [\d.]+\)", out)
    # 3 rows at ε = 0.1 and 0.2: warned once, before the tables, naming what to change
    assert out.count("zigzag periods") == 1 and "fiber.array_rows" in out
    mig = pd.read_csv(rigid / "migration.csv")
    assert {"trapped", "moving", "fraction_se"} <= set(mig.columns)
    outlets = pd.read_csv(rigid / "outlets.csv")
    # each length's recoveries and its trapped share add up to 1
    tot = outlets.groupby(["setting", "length"]).agg(
        rec=("recovery", "sum"), t=("trapped", "first")
    )
    assert np.allclose(tot["rec"] + tot["t"], 1.0)
    crit = pd.read_csv(rigid / "critical.csv")
    assert sorted(crit["value"]) == [0.1, 0.2]
    fig = rigid / "figures"
    for name in ("migration.png", "outlets.png", "sort-tracks.png", "critical-shift.png",
                 "cell-flow-shift=0.1.png", "cell-flow-shift=0.2.png"):  # fmt: skip
        assert (fig / name).stat().st_size > 5000, name
    assert list(fig.glob("chrono-*.png"))
    assert not list(rigid.glob("chrono-*.png"))  # under figures/, named after what they show


@pytest.mark.parametrize("edges", ["1.5", "0", "0.5,0.5", "a"])
def test_sort_report_refuses_outlet_edges_out_of_range(rigid, edges):
    res = _run(["sort-report", str(rigid), "--outlets", edges, "--no-figures"])
    assert res.exit_code == 2, res.output
    assert "--outlets" in res.output


def test_sort_report_of_flexible_fibers(flexible):
    res = _run(["sort-report", str(flexible)])
    assert res.exit_code == 0, res.output
    assert "critical length" in res.output and "trapped" in res.output
    # 10 kPa with touching beads: outside the validated range, said with what to set
    assert "warning: bead-spring fibers of E = 10 kPa with touching beads" in res.output
    assert "set fiber.bead_spacing to 0.5 (b = a)" in res.output
    assert "note: no chronophotograph" not in res.output  # the shapes were stored
    assert list((flexible / "figures").glob("chrono-*.png"))


def test_drawn_flexible_snapshots_have_all_their_beads(flexible):
    """The chronophotographs of sort-report, from the store: every snapshot every bead."""
    from matplotlib.collections import LineCollection

    from fibersweep.config.array import ArraySettings
    from fibersweep.plots import array_chrono as ac
    from fibersweep.results import load_array_results

    runs, settings, cfg = load_array_results(flexible)
    array = ArraySettings.model_validate(settings[0]["array"]).to_array()
    picks = [r.to_dict() for _, r in runs.iterrows()]
    fig = ac.chrono_figure(array, picks, cfg["fiber"]["bead_radius"])
    for ax, run in zip(fig.axes[: len(picks)], picks, strict=True):
        segs = [
            s for c in ax.collections if isinstance(c, LineCollection) for s in c.get_segments()
        ]
        assert segs and all(len(s) == run["n_beads"] for s in segs)
    # a flexible run without its beads is never drawn as a chord
    from fibersweep.plots.shapes import ShapeNotStored

    with pytest.raises(ShapeNotStored, match="all_beads"):
        ac.chrono_figure(array, [{**picks[0], "traj_beads": None}], cfg["fiber"]["bead_radius"])


def test_load_gives_array_units_and_the_f_summary(results):
    import fibersweep

    r = fibersweep.load(results, trajectories=False)
    assert r.geometry == "array"
    assert r.units["length"] == "µm" and r.units["y0"] == "period_y"
    assert "trapped" in r.docs["fraction"]
    s = r.fraction_summary()
    assert {"trapped", "moving", "fraction_mean"} <= set(s.columns)
    g = r.runs[r.runs["mode"] != "trapped"].groupby("length")["fraction"].mean()
    if len(s["setting"].unique()) == 1:
        assert np.allclose(s.set_index("length")["fraction_mean"], g)


def test_dry_run_of_an_array_with_no_cached_field_estimates_from_an_array_run(tmp_path):
    res = _run(["run", "configs/array.yaml", *SMALL, "sweep.length=[4, 40]",
                "sweep.flow.array.shift=[0.1, 0.2]", "sweep.random={count: 2, seed: 0}",
                f"run.cache_dir={tmp_path / 'cache'}", f"run.output={tmp_path / 'out'}",
                "--dry-run"])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert "unit cell on 4 µm" in res.output and "per run" in res.output
    assert "outside the channel" not in res.output
    assert not any((tmp_path / "cache").glob("cell-*"))  # nothing solved into the cache
    assert not (tmp_path / "out").exists()


def test_simulate_in_an_array_speaks_the_array_and_draws_the_rows(tmp_path, flow_cache_dir,
                                                                  monkeypatch):  # fmt: skip
    from fibersweep.plots import style

    drawn = []
    real = style.save_figure
    monkeypatch.setattr(style, "save_figure", lambda fig, p, **kw: drawn.append(fig) or real(
        fig, p, **kw))  # fmt: skip
    png = tmp_path / "a.png"
    res = _run(["simulate", "configs/array.yaml", "--theta0", "0", "--y0", "0.5", "--length",
                "40", *SMALL, f"run.cache_dir={flow_cache_dir}", "--plot", str(png)])  # fmt: skip
    assert res.exit_code == 0, res.output
    for word in ("mode:", "rows crossed:", "shift per row:", "f =", "migration angle"):
        assert word in res.output
    assert "y0/h" not in res.output and "L/l_obs" not in res.output and "class:" not in res.output
    assert png.stat().st_size > 5000 and len(drawn) == 1
    assert drawn[0].axes[0].get_xlabel() == "rows crossed"


def test_simulate_a_flexible_fiber_in_an_array_draws_every_bead(tmp_path, flow_cache_dir,
                                                                 monkeypatch):  # fmt: skip
    """A 10 kPa, 40 µm bead-spring fiber through the array's rows: the array's terms,
    and every drawn snapshot has all the fiber's beads (never a chord)."""
    from matplotlib.collections import LineCollection

    from fibersweep.plots import style

    drawn = []
    real = style.save_figure
    monkeypatch.setattr(style, "save_figure", lambda fig, p, **kw: drawn.append(fig) or real(
        fig, p, **kw))  # fmt: skip
    png = tmp_path / "flex.png"
    res = _run(["simulate", "configs/array-flexible.yaml", "--theta0", "0", "--y0", "0.5",
                "--length", "40", "fiber.young_modulus=1e4", *SMALL,
                f"run.cache_dir={flow_cache_dir}", "--plot", str(png)])  # fmt: skip
    assert res.exit_code == 0, res.output
    for word in ("mode:", "rows crossed:", "f ="):
        assert word in res.output
    assert png.stat().st_size > 5000 and len(drawn) == 1
    n_beads = 10  # 40 µm of 2 µm beads (b = 2a)
    segs = [s for ax in drawn[0].axes for c in ax.collections if isinstance(c, LineCollection)
            for s in c.get_segments() if len(s) > 2]  # fmt: skip
    assert segs and all(len(s) == n_beads for s in segs), {len(s) for s in segs}


def test_a_grid_start_on_a_pillar_is_refused_naming_the_free_starts(tmp_path):
    """A grid start that touches a pillar exits 2 before anything runs, with the ranges of
    y0 free at its angle and length (the run's own check)."""
    out_dir = f"run.output={tmp_path / 'o'}"
    res = _run(["run", "configs/array.yaml", "sweep.random=null", "sweep.y0=[0.2]",
                "sweep.theta0=[0]", "sweep.length=[40]", out_dir])  # fmt: skip
    assert res.exit_code == 2, res.output
    out = " ".join(res.output.split())
    assert "y0 = 0.2 (fraction of period_y), theta0 = 0 deg touches a pillar" in out
    assert "free starts at θ0 = 0°, L = 40 µm: y0 in [0.0000, 0.1142] ∪ [0.3452, 1.0000]" in out
    assert not (tmp_path / "o").exists()
