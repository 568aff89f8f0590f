"""A real, small, refined sweep folder for the figure and explorer tests.

``configs/quick.yaml`` on its coarse field (the shared test flow cache), three
start angles, five y0 values and two lengths, refined along y0 to 0.02 h_obs
(at most 40 extra runs), trajectories recorded (100 samples). About 15 s the
first time in a test session (Numba's disk cache warm), shared by every test
that asks for it.
"""

from __future__ import annotations

import os
from pathlib import Path

from typer.testing import CliRunner

from fibersweep.cli import app

REPO = Path(__file__).resolve().parents[2]

OVERRIDES = [
    "sweep.theta0=[-8.0, -4.0, 0.0]",
    "sweep.y0=[0.1, 0.3, 0.5, 0.7, 0.9]",
    "sweep.length=[0.8, 1.0]",
    "sweep.refine={axes: [y0], tolerance: {y0: 0.02}, max_runs: 40, rounds: 6}",
    "fiber.record.samples=100",
    "run.workers=1",
]

_MADE: dict[str, Path] = {}


def refined_folder(base: Path) -> Path:
    """Run the sweep into ``base/refined`` once per process; its path."""
    if "refined" in _MADE:
        return _MADE["refined"]
    cache = os.environ.get("FIBERSWEEP_TEST_CACHE", str(REPO / ".fibersweep-cache" / "tests"))
    out = base / "refined"
    r = CliRunner().invoke(
        app,
        [
            "run", str(REPO / "configs" / "quick.yaml"), *OVERRIDES,
            f"run.output={out}", f"run.cache_dir={cache}",
        ],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    _MADE["refined"] = out
    return out
