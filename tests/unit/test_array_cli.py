"""Array config errors name the field and exit 2."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from fibersweep.cli import app


@pytest.mark.parametrize(
    ("override", "named"),
    [
        (["array.period_y=35"], "array.period_y"),  # pillars overlap across the flow
        (["array.pillar_shape=circle", "array.pillar_size=77"], "array.period_y"),  # gap < 2a
        (["array.shift=0.11"], "array.shift"),  # 8.8 µm is not whole cells of 2 µm
        (["array.pillar_shape=triangel"], "array.pillar_shape"),
        (["sweep.axes={shift: [0.1, 0.13]}"], "sweep.axes.shift"),
        (["sweep.axes={gap: [1]}"], "sweep.axes.gap"),
        (["fiber.effects={inlet_speed: 0.1}"], "fiber.effects"),  # a channel-only effect
        (["fiber.effects={frictoin: 0.1}"], "fiber.effects"),  # unknown effect
    ],
)
def test_bad_array_input_exits_2_naming_the_field(override, named):
    res = CliRunner().invoke(app, ["run-array", "configs/array.yaml", *override])
    assert res.exit_code == 2, res.output
    assert named in res.output


def test_sort_report_on_a_folder_without_results_exits_2(tmp_path):
    res = CliRunner().invoke(app, ["sort-report", str(tmp_path)])
    assert res.exit_code == 2
    assert "RESULTS" in res.output
