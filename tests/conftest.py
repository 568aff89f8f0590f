"""Shared pytest fixtures.

Flow fields (issue 2) are computed once per machine and kept in a repo-local,
git-ignored cache (``.fibersweep-cache/tests``; override with the environment
variable ``FIBERSWEEP_TEST_CACHE``), so repeated local runs load them in
milliseconds. A cold computation costs: ``coarse_field`` (SPEC geometry,
dx = 4 µm, 600 x 200 x 5 half-depth nodes, 1800 steps) about 30 s on the loaded
2-core machine (≈ 15 s on free cores); ``small_field`` (400 x 800 µm channel,
dx = 4 µm) about a sixth of that.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from fibersweep.config.flow import FlowSettings, GeometrySettings

REPO = Path(__file__).resolve().parents[1]


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--studies",
        action="store_true",
        help="run the docs' study commands (hours; with -m study)",
    )


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Without --studies, the study tests are deselected (not listed as skipped)."""
    if config.getoption("--studies"):
        return
    keep, study = [], []
    for it in items:
        (study if it.get_closest_marker("study") else keep).append(it)
    if study:
        config.hook.pytest_deselected(items=study)
        items[:] = keep


@pytest.fixture(scope="session")
def flow_cache_dir() -> Path:
    """Directory of the shared test flow-field cache."""
    path = Path(os.environ.get("FIBERSWEEP_TEST_CACHE", REPO / ".fibersweep-cache" / "tests"))
    path.mkdir(parents=True, exist_ok=True)
    return path


COARSE_SETTINGS = FlowSettings(dx=4.0)
SMALL_SETTINGS = FlowSettings(
    geometry=GeometrySettings(width=400.0, depth=40.0, length=800.0, pillar_height=75.0),
    dx=4.0,
)


@pytest.fixture(scope="session")
def coarse_settings() -> FlowSettings:
    """The flow settings of :func:`coarse_field` (the SPEC channel at dx = 4 µm)."""
    return COARSE_SETTINGS


@pytest.fixture(scope="session")
def coarse_field(flow_cache_dir):
    """FlowField of the SPEC geometry at dx = 4 µm (TRT, symmetric half depth), µm/s."""
    from fibersweep.flow.cache import get_flow_field

    field, _ = get_flow_field(COARSE_SETTINGS, flow_cache_dir)
    return field


@pytest.fixture(scope="session")
def small_field(flow_cache_dir):
    """FlowField of a smaller channel (W 400, L 800, H 40 µm, h_obs 75 µm) at dx = 4 µm."""
    from fibersweep.flow.cache import get_flow_field

    field, _ = get_flow_field(SMALL_SETTINGS, flow_cache_dir)
    return field


@pytest.fixture()
def config(tmp_path, flow_cache_dir, coarse_field):
    """A small sweep config on the shared test cache (the discrepancy CLI tests' box)."""
    # coarse_field makes sure the default-geometry field at dx = 4 µm is in the test cache
    p = tmp_path / "cfg.yaml"
    p.write_text(
        "sweep:\n"
        "  theta0: {start: -10, stop: 10, num: 3}\n"
        "  y0: {start: 0.15, stop: 0.65, num: 3}\n"
        "  length: {start: 0.5, stop: 1.4, num: 3}\n"
        f"run:\n  cache_dir: {flow_cache_dir}\n  workers: 1\n"
    )
    return p
