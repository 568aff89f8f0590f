"""plot-phase facets: defaults from what varies, explicit --col/--row, files per extra key."""

from __future__ import annotations

import itertools

import pandas as pd
import pytest

from fibersweep.errors import InputError
from fibersweep.plots.phase import facet_keys, plot_all

F, P, H = "fiber.effects.friction", "fiber.contact.pillar", "flow.geometry.pillar_height"


def _runs(**axes):
    rows = []
    grid = list(itertools.product(*axes.values()))
    for k, combo in enumerate(grid):
        for t, y in itertools.product([-5.0, 5.0], [0.2, 0.8]):
            rows.append({"id": f"{k}-{t}-{y}", "theta0": t, "y0": y, "status": "ok",
                         "class": "Below" if y < 0.5 else "Above", "delta": 0.01,
                         "contact": False, "theta_c": float("nan"), "y_c": float("nan"),
                         "settings": f"s{k}", **dict(zip(axes, combo, strict=True))})  # fmt: skip
    df = pd.DataFrame(rows)
    if "length" not in df:
        df["length"] = 1.0
    return df


def test_defaults_follow_what_varies():
    assert facet_keys(_runs()) == (None, None, [])
    assert facet_keys(_runs(length=[0.8, 1.0])) == ("length", None, [])
    assert facet_keys(_runs(**{F: [0.0, 0.3], "length": [0.8, 1.0]})) == (F, "length", [])
    # a swept key that takes one value is no facet
    assert facet_keys(_runs(**{F: [0.3], P: ["rough", "smooth"]})) == (P, None, [])
    assert facet_keys(_runs(**{F: [0.0, 0.3], P: ["rough", "smooth"], H: [60.0, 75.0]})) == (
        F, P, [H],
    )  # fmt: skip


def test_explicit_facets_and_unknown_ones():
    runs = _runs(**{F: [0.0, 0.3], P: ["rough", "smooth"]})
    assert facet_keys(runs, col=P) == (P, F, [])
    assert facet_keys(runs, row=F) == (P, F, [])
    with pytest.raises(InputError, match=r"--row 'frict': not a column to facet by; valid: .*"):
        facet_keys(runs, row="frict")


def test_a_third_varying_key_gives_one_file_per_value(tmp_path):
    runs = _runs(**{F: [0.0, 0.3], P: ["rough", "smooth"], H: [60.0, 75.0]})
    names = sorted(p.name for p in plot_all(runs, tmp_path, separatrix={"s0": 0.3}))
    assert f"phase-{H}=60.png" in names and f"phase_delta-{H}=75.png" in names
    assert "contact_map.png" in names and "phase.png" not in names
