"""``run --dry-run`` without a cached field estimates from a short timing (no "unknown")."""

from __future__ import annotations

import math

import pytest
from typer.testing import CliRunner

from fibersweep.cli import app
from fibersweep.config.fiber import FiberSettings
from fibersweep.config.flow import FlowSettings, GeometrySettings
from fibersweep.fiber.result import FiberStart
from fibersweep.flow.lbm import lattice_of
from fibersweep.sweep.estimate import estimate_uncached

SMALL = GeometrySettings(width=400.0, depth=40.0, length=800.0, pillar_height=75.0)


def test_estimate_covers_every_grid_of_the_nested_solve():
    flow = FlowSettings(geometry=SMALL, dx=2.0)
    e = estimate_uncached(flow, FiberSettings(), FiberStart(theta0=0.0, y0=0.9, length=1.0))
    # the nested solve does 4 µm then 2 µm: both grids, coarsest first, with their sizes
    assert [dx for dx, _ in e.grids] == [4.0, 2.0]
    assert e.grids[1][1] == lattice_of(flow).cells
    assert e.grids[1][1] > 6 * e.grids[0][1]  # 8x the cells, less the pillar's share
    for v in (e.flow_s, e.run_s, e.mlups):
        assert math.isfinite(v) and v > 0


def test_dry_run_without_cached_field_gives_an_estimate(tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text(
        "flow:\n  dx: 4.0\n  geometry: {width: 400, length: 800}\n"
        "sweep:\n  theta0: [0.0]\n  y0: [0.9]\n  length: [1.0]\n"
        f"run:\n  output: {tmp_path / 'out'}\n  cache_dir: {tmp_path / 'cache'}\n"
    )
    r = CliRunner().invoke(app, ["run", str(cfg), "--dry-run"])
    assert r.exit_code == 0, r.output
    assert "NOT cached" in r.output
    assert "unknown" not in r.output
    assert "flow fields" in r.output and "per run" in r.output
    assert not any((tmp_path / "cache").glob("flow-*"))  # nothing was stored


@pytest.mark.parametrize(
    ("workers", "load", "cpus", "free"),
    [(2, 0.3, 2, 2), (2, 1.2, 2, 1), (2, 6.0, 2, 1), (8, 3.0, 16, 8), (8, 12.0, 16, 4)],
)
def test_workers_beyond_the_free_cores_are_not_counted(workers, load, cpus, free):
    from fibersweep.sweep.estimate import free_workers

    assert free_workers(workers, load, cpus) == free


def test_dry_run_on_a_busy_machine_counts_the_workers_the_free_cores_hold(tmp_path, monkeypatch):
    # 2 workers on 2 cores with a load average of 6: the estimate is that of one worker,
    # and says why (the real run's workers share the cores with what runs already)
    from fibersweep.sweep import estimate

    cfg = tmp_path / "c.yaml"
    cfg.write_text(
        "flow:\n  dx: 4.0\n  geometry: {width: 400, length: 800}\n"
        "sweep:\n  theta0: [0.0, 5.0]\n  y0: [0.9]\n  length: [1.0]\n"
        f"run:\n  output: {tmp_path / 'out'}\n  cache_dir: {tmp_path / 'cache'}\n  workers: 2\n"
    )
    monkeypatch.setattr(estimate, "busy_cores", lambda: (6.0, 2))
    r = CliRunner().invoke(app, ["run", str(cfg), "--dry-run"])
    assert r.exit_code == 0, r.output
    assert "load average 6.0 on 2 cores" in r.output and "counted as 1" in r.output
