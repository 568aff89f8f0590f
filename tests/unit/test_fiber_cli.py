"""`fibersweep simulate` and the chronophotograph."""

from __future__ import annotations

from typer.testing import CliRunner

from fibersweep.cli import app


def _config(tmp_path, flow_cache_dir, extra: str = "") -> str:
    p = tmp_path / "c.yaml"
    p.write_text(f"flow:\n  dx: 4.0\nrun:\n  cache_dir: {flow_cache_dir}\n{extra}")
    return str(p)


def test_simulate_prints_class_and_plots(tmp_path, flow_cache_dir, coarse_field):
    cfg = _config(tmp_path, flow_cache_dir, "fiber:\n  effects: {friction: 0.3}\n")
    png = tmp_path / "chrono.png"
    res = CliRunner().invoke(
        app,
        ["simulate", cfg, "--theta0", "-3.7", "--y0", "0.373", "--length", "0.82",
         "--plot", str(png)],
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    assert "class: Pole-vaulting" in res.output
    assert "contact: yes" in res.output and "delta: 0.1" in res.output
    start = next(line for line in res.output.splitlines() if line.startswith("start:"))
    assert start.endswith("; effects friction = 0.3")  # what the run had on
    assert png.exists() and png.stat().st_size > 10_000


def test_simulate_bad_input_exit_2(tmp_path, flow_cache_dir, coarse_field):
    cfg = _config(tmp_path, flow_cache_dir)
    res = CliRunner().invoke(
        app, ["simulate", cfg, "--theta0", "0", "--y0", "0.5", "--length", "0.01"]
    )
    assert res.exit_code == 2
    assert "length" in res.output
    res = CliRunner().invoke(
        app,
        ["simulate", cfg, "--theta0", "0", "--y0", "0.5", "--length", "1", "--model", "soft"],
    )
    assert res.exit_code == 2 and "--model" in res.output


def test_simulate_reversible(tmp_path, flow_cache_dir, coarse_field):
    cfg = _config(tmp_path, flow_cache_dir)
    res = CliRunner().invoke(
        app, ["simulate", cfg, "--theta0", "5", "--y0", "0.8", "--length", "1", "--reversible"]
    )
    assert res.exit_code == 0, res.output
    assert "class: Above" in res.output and "reversed flow: returns within" in res.output


def test_help_texts_keep_their_units():
    # units are written in brackets ([deg], [s]); the help must print them, not eat them
    # as markup
    sim = CliRunner().invoke(app, ["simulate", "--help"], terminal_width=200)
    cls = CliRunner().invoke(app, ["classify", "--help"], terminal_width=200)
    dis = CliRunner().invoke(app, ["discrepancy", "--help"], terminal_width=200)
    assert "Start angle from +x [deg]." in sim.output
    assert "stopped this long [s]" in cls.output
    assert "(default: all)" in dis.output


def test_simulate_prints_units_and_says_never_for_a_missing_pass(
    tmp_path, flow_cache_dir, coarse_field
):
    cfg = _config(tmp_path, flow_cache_dir)
    below = CliRunner().invoke(
        app, ["simulate", cfg, "--theta0", "0", "--y0", "0.2", "--length", "1"]
    )
    assert below.exit_code == 0, below.output
    assert "class: Below" in below.output
    line = next(ln for ln in below.output.splitlines() if ln.startswith("delta:"))
    assert line.split()[2] == "h_obs", line  # 'delta: -0.0123 h_obs (...)'
    assert "t_pass: " in below.output and "t_pass: never" not in below.output
    # trapped on this grid (tests/regression/test_sweep_e2e.py): no pass, no displacement
    trapped = CliRunner().invoke(
        app, ["simulate", cfg, "--theta0", "8", "--y0", "0.30", "--length", "1"]
    )
    assert trapped.exit_code == 0, trapped.output
    assert "class: Trapping" in trapped.output
    assert "t_pass: never" in trapped.output and "- s" not in trapped.output
    assert "delta: none" in trapped.output


def test_a_soft_fiber_wrapping_the_pillar_is_drawn_bent_never_as_a_chord(
    tmp_path, flow_cache_dir, coarse_field, monkeypatch
):
    """10 kPa, draped over the apex: every snapshot is drawn through all its beads, and no
    drawn bead is inside the pillar (a head-to-tail chord would cut through it)."""
    import numpy as np
    from matplotlib.collections import LineCollection

    from fibersweep.plots import chrono

    drawn = []
    real = chrono.save_figure
    monkeypatch.setattr(chrono, "save_figure", lambda f, p, **k: drawn.append(f) or real(f, p, **k))
    cfg = _config(tmp_path, flow_cache_dir, "fiber:\n  model: bead-spring-ros2\n"
                  "  young_modulus: 1.0e+4\n")  # fmt: skip
    res = CliRunner().invoke(app, ["simulate", cfg, "--theta0", "0", "--y0", "0.45", "--length",
                                   "1.2", "--plot", str(tmp_path / "f.png")])  # fmt: skip
    assert res.exit_code == 0, res.output
    n = int(res.output.split(" beads)")[0].rsplit("(", 1)[1])
    end_to_end = float(res.output.split("min end-to-end ")[1].split()[0])
    assert end_to_end < 0.8  # it bends round the apex
    (fig,) = drawn
    segs = [s for c in fig.axes[0].collections if isinstance(c, LineCollection)
            for s in c.get_segments()]  # fmt: skip
    assert segs and all(len(s) == n for s in segs)
    geo = coarse_field.geometry
    xb, yb = geo.base_center
    pts = np.concatenate(segs) * geo.pillar_height + [xb, yb]
    assert np.min(geo.shape.signed_distance(pts[:, 0], pts[:, 1])) > 0.0
