"""`fibersweep flow`: output, cache reuse, figure, bad input (exit 2), solver failure."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from fibersweep.cli import app
from fibersweep.config.flow import FlowSettings, GeometrySettings
from fibersweep.errors import SolverError
from fibersweep.flow.solver import solve_lattice

runner = CliRunner()

TINY_FLOW = {
    "geometry": {"width": 40.0, "depth": 32.0, "length": 48.0, "pillar_height": 12.0},
    "dx": 4.0,
    "tolerance": 1e-5,
}


def _config(tmp_path, flow: dict) -> str:
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump({"flow": flow, "run": {"cache_dir": str(tmp_path / "cache")}}))
    return str(path)


def test_flow_reports_miss_then_hit_and_plots(tmp_path):
    cfg = _config(tmp_path, TINY_FLOW)
    first = runner.invoke(app, ["flow", cfg])
    assert first.exit_code == 0, first.output
    assert "cache: miss" in first.output
    for word in ("grid: 12 x 10 x 4", "steps", "converged", "time:", "U_center reached: 600.000"):
        assert word in first.output
    png = tmp_path / "fig" / "flow.png"
    second = runner.invoke(app, ["flow", cfg, "--plot", str(png)])
    assert second.exit_code == 0, second.output
    assert "cache: hit" in second.output
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"
    forced = runner.invoke(app, ["flow", cfg, "--force"])
    assert forced.exit_code == 0 and "cache: miss" in forced.output


@pytest.mark.parametrize(
    ("flow", "names"),
    [
        ({"geometry": {"width": -5.0}}, ["flow.geometry.width", "greater than 0"]),
        ({"geometry": {"depth": 0.0}}, ["flow.geometry.depth"]),
        ({"geometry": {"pillar_height": 900.0}}, ["flow.geometry", "pillar does not fit"]),
        ({"dx": 8.0}, ["flow.dx", "5 nodes across the depth", "at least 8"]),
        ({"dx": 3.0}, ["flow.dx", "not a whole number"]),
        ({"dx": -1.0}, ["flow.dx"]),
        ({"collision": "lbgk"}, ["flow.collision", "'trt' or 'bgk'"]),
        ({"tau": 0.4}, ["flow.tau"]),
        ({"colision": "bgk"}, ["flow.colision", "did you mean 'collision'"]),
    ],
)
def test_bad_input_exits_2_naming_the_field(tmp_path, flow, names):
    res = runner.invoke(app, ["flow", _config(tmp_path, flow)])
    assert res.exit_code == 2, res.output
    for name in names:
        assert name in res.output, res.output
    assert not (tmp_path / "cache").exists() or not any((tmp_path / "cache").iterdir())


def test_missing_config_exits_2(tmp_path):
    res = runner.invoke(app, ["flow", str(tmp_path / "nope.yaml")])
    assert res.exit_code == 2 and "cannot read config" in res.output


@pytest.mark.parametrize(("bad", "message"), [(np.nan, "non-finite"), (0.3, "Mach too high")])
def test_diverging_solver_raises_solver_error(bad, message):
    # A blown-up state (NaN, or a lattice speed far above the Mach limit) must stop
    # the solver with a SolverError (CLI exit 1), never return a garbage field.
    # check every step: this viscous toy channel would damp u = 0.3 below the
    # limit within ~100 steps
    settings = FlowSettings.model_validate({**TINY_FLOW, "check_every": 1})
    initial = np.zeros((3, 4, 10, 12))
    initial[0] = bad  # the whole channel: a lone spike would just diffuse away
    with pytest.raises(SolverError, match=message):
        solve_lattice(settings, initial=initial)


def test_tau_of_one_half_is_rejected():
    # τ ≤ 1/2 means zero or negative viscosity; the schema rejects it by name.
    with pytest.raises(ValueError, match="tau"):
        FlowSettings.model_validate({**TINY_FLOW, "tau": 0.5})


def test_flow_settings_geometry_is_used(tmp_path):
    s = FlowSettings.model_validate(TINY_FLOW)
    assert isinstance(s.geometry, GeometrySettings) and s.geometry.width == 40.0


def test_flow_reports_separatrix_with_error_estimate(tmp_path):
    # first dx = 4 alone: only the traced-vs-flux spread; then dx = 2 in the same
    # cache: its estimate adds the Richardson grid error from the cached dx = 4
    cfg = _config(tmp_path, {**TINY_FLOW, "pillar_boundary": "interpolated"})
    coarse = runner.invoke(app, ["flow", cfg])
    assert coarse.exit_code == 0, coarse.output
    assert "separatrix far upstream:" in coarse.output
    assert "grid error: no level at 2 dx or dx/2" in coarse.output
    fine = runner.invoke(app, ["flow", cfg, "flow.dx=2"])
    assert fine.exit_code == 0, fine.output
    assert "grid error: Richardson (p = 2) with cached dx = 4 µm" in fine.output


def test_separatrix_estimate_parts(coarse_field):
    from fibersweep.flow.uncertainty import separatrix_estimate

    est = separatrix_estimate(coarse_field)
    assert est.model_spread == pytest.approx(abs(est.traced - est.flux))
    assert est.error == est.model_spread and est.grid_error is None
    # the SPEC channel: the separatrix lies near a third of h_obs (SPEC section 2)
    assert 0.28 < est.traced < 0.40
    with pytest.raises(ValueError, match="2 dx or dx/2"):
        separatrix_estimate(coarse_field, coarse_field)


def test_flow_axis_computes_and_reports_each_distinct_field(tmp_path):
    """`sweep: {flow.geometry.pillar_height: [12, 8]}` and a fiber axis: two fields, not four."""
    path = tmp_path / "c.yaml"
    sweep = {
        "flow.geometry.pillar_height": [12.0, 8.0],
        "fiber.effects.friction": [0.0, 0.3],
    }
    path.write_text(yaml.safe_dump({"flow": TINY_FLOW, "sweep": sweep,
                                    "run": {"cache_dir": str(tmp_path / "cache")}}))  # fmt: skip
    png = tmp_path / "flow.png"
    res = runner.invoke(app, ["flow", str(path), "--plot", str(png)])
    assert res.exit_code == 0, res.output
    out = res.output
    assert "field 1 of 2 (flow.geometry.pillar_height=12.0):" in out
    assert "field 2 of 2 (flow.geometry.pillar_height=8.0):" in out
    assert out.count("cache: miss") == 2 and "field 3" not in out
    entries = sorted(p.name for p in (tmp_path / "cache").glob("flow-*"))
    assert len(entries) == 2
    figures = sorted(p.name for p in tmp_path.glob("flow-*.png"))
    assert figures == sorted(f"flow-{e.removeprefix('flow-')}.png" for e in entries)
    again = runner.invoke(app, ["flow", str(path)])
    assert again.exit_code == 0 and again.output.count("cache: hit") == 2
