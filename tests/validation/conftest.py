"""Fixtures shared by the validation tests."""

from __future__ import annotations

import pytest


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
