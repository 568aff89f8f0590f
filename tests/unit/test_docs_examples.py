"""The single-fiber examples of the docs do what the text says they do.

The README's ``simulate ... --plot vault.png`` start must pole-vault, and the
trapped example of docs/validation/source.md must be trapped, on the grid of
configs/quick.yaml (dx = 4 µm). The starts are read from the docs themselves, so
an edit of either the docs or the physics that breaks the claim fails here.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from fibersweep.config import load_config
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import simulate

REPO = Path(__file__).resolve().parents[2]


def _start(doc: str, plot: str) -> FiberStart:
    text = (REPO / doc).read_text(encoding="utf-8")
    line = next(
        ln for ln in text.splitlines() if ln.startswith("fibersweep simulate") and plot in ln
    )
    assert "configs/quick.yaml" in line, line
    num = r"(-?[0-9.]+)"
    theta0, y0, length = (
        float(re.search(rf"--{k} {num}", line).group(1)) for k in ("theta0", "y0", "length")
    )
    return FiberStart(theta0=theta0, y0=y0, length=length)


@pytest.mark.parametrize(
    ("doc", "plot", "expected"),
    [
        ("README.md", "vault.png", "Pole-vaulting"),
        ("docs/validation/source.md", "vault.png", "Pole-vaulting"),
        ("docs/validation/source.md", "trap.png", "Trapping"),
    ],
)
def test_documented_start_has_documented_class(doc, plot, expected, flow_cache_dir):
    from fibersweep.flow.cache import get_flow_field

    cfg = load_config(REPO / "configs" / "quick.yaml")
    field, _ = get_flow_field(cfg.flow, flow_cache_dir)
    res = simulate(field, cfg.fiber, _start(doc, plot))
    assert res.status == "ok", res.reason
    assert res.cls == expected, (res.cls, res.delta, res.theta_c, res.y_c)
    assert res.contact
