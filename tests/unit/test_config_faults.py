"""A config reports all its faults at once, and whole-cell checks allow for rounding.

Every problem is named at its field and line, in the same form as a single one: a
misspelled key does not hide a bad value in another section, nor one check of a
model the others. A length within 1e-3 µm of a whole number of lattice cells (a
shift written 0.0909 for 1/11) is accepted and stored as that whole number.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from fibersweep.config import ConfigError, load_config, parse_config
from fibersweep.geometry.array import LATTICE_TOLERANCE, PillarArray
from fibersweep.sweep.executors import EXECUTORS
from fibersweep.sweep.starts import PHYSICS


def _load(tmp_path: Path, text: str, *overrides: str):
    p = tmp_path / "c.yaml"
    p.write_text(text)
    return load_config(p, overrides, physics=PHYSICS, executors=EXECUTORS)


def _problems(tmp_path: Path, text: str, *overrides: str) -> list[str]:
    with pytest.raises(ConfigError) as exc:
        _load(tmp_path, text, *overrides)
    return exc.value.problems


ARRAY = """\
flow:
  dx: 2.0
  array:
    pillar_size: 20.0
    period_y: 44.0
    shift: {shift}
sweep:
  length: [8.0]
  y0: [0.0, 1.0]
  random: {{count: 2, seed: 0}}
"""


# ----------------------------------------------------------------------------- all at once


def test_a_misspelled_key_and_a_bad_start_in_another_section_are_both_reported(tmp_path):
    # the start is checked with the whole config, which pydantic skips once a section fails
    text = "run:\n  wrkers: 2\nsweep:\n  y0: [0.1, 20.0]\n"
    assert _problems(tmp_path, text) == [
        "run.wrkers (line 2): unknown key; did you mean 'workers'? Valid keys here: workers, "
        "output, cache_dir, executor, scheduler, flush_every, flush_seconds, retries, options, "
        "compact, max_points",
        "sweep.y0 (line 4): y0/h = 20.0 with theta0 = 0.0° puts beads outside the channel "
        "(bead y from 1875.0 to 1875.0 µm, width 800.0 µm)",
    ]


def test_a_misspelled_key_and_a_bad_array_value_are_both_reported(tmp_path):
    text = ARRAY.format(shift=0.095) + "fiber:\n  bead_radiu: 2.0\n"
    problems = _problems(tmp_path, text)
    assert len(problems) == 2, problems
    assert problems[0].startswith("flow.array.shift (line 6): the row shift ε λy = 0.095 × 44")
    assert problems[1].startswith("fiber.bead_radiu (line 12): unknown key; did you mean")


def test_every_failed_check_of_one_section_is_reported(tmp_path):
    # two checks of flow (the array's lattice, the solver's tolerance) and two of run
    text = (
        ARRAY.format(shift=0.095).replace("  dx: 2.0\n", "  dx: 2.0\n  tolerance: 1.0e-8\n")
        + "run:\n  executor: lcoal\n  scheduler: somewhere\n"
    )
    problems = _problems(tmp_path, text)
    assert [p.split(":")[0] for p in problems] == [
        "flow.array.shift (line 7)",
        "flow (line 1)",
        "run.executor (line 13)",
        "run.scheduler (line 14)",
    ], problems
    assert problems[1].startswith("flow (line 1): tolerance = 1e-08 is below what float32")
    assert problems[2] == "run.executor (line 13): unknown executor; did you mean 'local'? " + (
        "valid: local, dask"
    )


def test_a_failed_section_does_not_make_up_problems_in_the_checks_it_feeds(tmp_path):
    # the fiber section failed: the starts (which need the fiber) are not checked with a
    # default fiber in its place; the size limit (sweep and run) still is
    text = "fiber:\n  bead_radiu: 1.0\nsweep:\n  y0: [0.1, 20.0]\n  theta0: [0, 1, 2]\n"
    problems = _problems(tmp_path, text, "run.max_points=4")
    assert [p.split(" (")[0] for p in problems] == ["fiber.bead_radiu", "sweep"], problems
    assert "6 points, more than run.max_points (4)" in problems[1]


def test_one_problem_reads_as_before(tmp_path):
    assert _problems(tmp_path, "run:\n  scheduler: somewhere\n") == [
        "run.scheduler (line 2): expected an address like tcp://HOST:PORT, got 'somewhere'"
    ]


# ----------------------------------------------------------------------------- tolerance


def test_a_shift_a_rounding_away_from_whole_cells_is_taken_as_them(tmp_path):
    cfg = _load(tmp_path, ARRAY.format(shift=0.0909))  # 0.0909 × 44 µm = 3.9996 µm
    # stored as the whole number it was taken as: 2 cells of 2 µm, exactly
    assert cfg.flow.array.shift == 4.0 / 44.0
    arr = cfg.flow.array.to_array()
    assert arr.check_lattice(2.0) == 2 and abs(arr.lateral_shift - 4.0) < 1e-12
    # other digits of 1/11 (4.00004 µm): the same flow field and run ids
    other = _load(tmp_path, ARRAY.format(shift=0.09091))
    assert other.flow.model_dump() == cfg.flow.model_dump()


def test_a_shift_off_whole_cells_is_refused_at_its_field(tmp_path):
    problems = _problems(tmp_path, ARRAY.format(shift=0.095))  # 4.18 µm
    assert problems == [
        "flow.array.shift (line 6): the row shift ε λy = 0.095 × 44 µm = 4.18 µm is not a whole "
        "number of lattice cells (dx = 2 µm, within 0.001 µm): the unit cell's shifted periodic "
        "boundary needs a whole number; choose ε λy = k dx, e.g. shift = 0.0909091"
    ]
    # as a swept value too, named at the axis
    problems = _problems(tmp_path, ARRAY.format(shift=0.0909), "sweep.flow.array.shift=[0.095]")
    assert problems[0].startswith("sweep.flow.array.shift (override sweep.flow.array.shift=")
    assert "value 0.095: the row shift" in problems[0]


def test_the_tolerance_is_1e_3_um():
    assert LATTICE_TOLERANCE == 1e-3
    arr = PillarArray(pillar_size=20.0, period_y=44.0, shift=(4.0 + 0.9e-3) / 44.0)
    assert arr.check_lattice(2.0) == 2
    arr = PillarArray(pillar_size=20.0, period_y=44.0, shift=(4.0 + 1.1e-3) / 44.0)
    with pytest.raises(ValueError, match="within 0.001 µm"):
        arr.check_lattice(2.0)


def test_whole_values_keep_their_bits():
    # a config that was whole before keeps every value as written (same ids and keys)
    cfg = parse_config({"flow": {"dx": 2.0, "array": {"shift": 0.1, "period_y": 80.0}}})
    assert cfg.flow.array.shift == 0.1
    cfg = parse_config({"flow": {"dx": 0.8, "array": {"shift": 0.3, "period_y": 80.0}}})
    assert cfg.flow.array.shift == 0.3


def test_channel_and_patch_lengths_are_taken_as_whole_cells():
    cfg = parse_config({"flow": {"dx": 4.0, "geometry": {"length": 2400.0004}}})
    assert cfg.flow.geometry.length == 2400.0
    cfg = parse_config({"flow": {"dx": 4.0, "patch": {"dx": 1.3333}}})
    assert cfg.flow.patch.dx == 4.0 / 3.0
    with pytest.raises(ConfigError, match=r"flow.dx: geometry.length = 2400.01 µm is not a whole"):
        parse_config({"flow": {"dx": 4.0, "geometry": {"length": 2400.01}}})
    with pytest.raises(ConfigError, match=r"within 0.001 µm"):
        parse_config({"flow": {"dx": 4.0, "patch": {"dx": 1.33}}})
