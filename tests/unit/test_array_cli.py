"""Bad pillar-array input in the standard config: exit 2 naming the field; the removed
``run-array`` command says what to use instead."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from fibersweep.cli import app


@pytest.mark.parametrize(
    ("override", "named"),
    [
        (["flow.array.period_y=35"], "flow.array.period_y"),  # pillars overlap across the flow
        (
            [
                "flow.array.pillar_shape=circle",
                "flow.array.pillar_size=60",
                "fiber.bead_radius=10.5",
            ],
            "flow.array.period_y",
        ),  # gap 20 µm < 2a = 21 µm
        (["flow.array.pillar_shape=circle", "flow.array.pillar_size=77"], "flow.dx"),  # wall
        # 1.5 µm from the cell's edge: the sub-grid wall needs 4 cells
        (["flow.array.shift=0.11"], "flow.array.shift"),  # 8.8 µm is not whole cells of 2 µm
        (["flow.array.pillar_shape=triangel"], "flow.array.pillar_shape"),
        (["flow.geometry.width=400"], "flow.geometry"),  # not used with an array
        (["sweep.flow.array.shift=[0.1, 0.13]"], "sweep.flow.array.shift"),  # 10.4 µm
        (["sweep.flow.array.gap=[1]"], "sweep.flow.array.gap"),  # not a setting
        (["fiber.effects={inlet_speed: 0.1}"], "fiber.effects"),  # a channel-only effect
        (["fiber.effects={frictoin: 0.1}"], "fiber.effects"),  # unknown effect
        (["fiber.model=bead-spring-ros2"], "sweep.length"),  # 4 µm: one bead, not a chain
        (["sweep.y0=[0.2, 1.5]"], "sweep.y0"),  # a fraction of period_y
        (["sweep.length=[2, 40]"], "sweep.length"),  # shorter than one bead (µm)
    ],
)
def test_bad_array_input_exits_2_naming_the_field(override, named, tmp_path):
    args = ["run", "configs/array.yaml", *override, f"run.output={tmp_path / 'out'}"]
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 2, res.output
    assert named in res.output
    assert not (tmp_path / "out").exists()


def test_run_array_is_removed_and_points_to_run():
    res = CliRunner().invoke(app, ["run-array", "configs/array.yaml"])
    assert res.exit_code == 2
    assert "use fibersweep run" in res.output


def test_sort_report_on_a_folder_without_results_exits_2(tmp_path):
    res = CliRunner().invoke(app, ["sort-report", str(tmp_path)])
    assert res.exit_code == 2
    assert "RESULTS" in res.output
