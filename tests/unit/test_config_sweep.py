"""Config schema: sweep axes in three forms, errors a user can act on (path, line, hint)."""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.config import ConfigError, load_config, parse_config
from fibersweep.sweep.starts import PHYSICS, grid_starts


def _write(tmp_path, text):
    p = tmp_path / "c.yaml"
    p.write_text(text)
    return p


def test_axes_list_range_linspace(tmp_path):
    cfg = load_config(
        _write(
            tmp_path,
            "sweep:\n"
            "  theta0: {start: -10, stop: 10, step: 5}\n"
            "  y0: {start: 0.3, stop: 0.45, num: 4}\n"
            "  length: [0.8, 1.2]\n",
        )
    )
    starts = grid_starts(cfg.sweep)
    assert len(starts) == 5 * 4 * 2
    th = sorted({s.theta0 for s in starts})
    assert th == [-10.0, -5.0, 0.0, 5.0, 10.0]
    np.testing.assert_allclose(sorted({s.y0 for s in starts}), [0.3, 0.35, 0.4, 0.45], atol=1e-12)
    # a range whose stop is not hit exactly by float steps still includes it (0.1 * 3 != 0.3)
    cfg2 = parse_config({"sweep": {"y0": {"start": 0.0, "stop": 0.3, "step": 0.1}}})
    assert len({s.y0 for s in grid_starts(cfg2.sweep)}) == 4


def test_defaults_and_run_section():
    cfg = parse_config({})
    assert cfg.run.workers == 2 and cfg.run.executor == "local"
    assert cfg.fiber.record.trajectories is False
    assert len(grid_starts(cfg.sweep)) == 1


def test_unknown_key_names_path_line_and_suggestion(tmp_path):
    p = _write(tmp_path, "flow:\n  dx: 4\nsweep:\n  theta0: [0]\n  y00: 0.4\n")
    with pytest.raises(ConfigError) as ei:
        load_config(p)
    msg = str(ei.value)
    assert "sweep.y00 (line 5): unknown key; did you mean 'y0'?" in msg
    assert "Valid keys here: theta0, y0, length" in msg


def test_bad_values_say_expected_and_given(tmp_path):
    p = _write(
        tmp_path,
        "run:\n  workers: 0\nsweep:\n  theta0: hello\n  length: {start: 2, stop: 1, step: 0.1}\n",
    )
    with pytest.raises(ConfigError) as ei:
        load_config(p)
    msg = str(ei.value)
    assert "run.workers (line 2): Input should be greater than or equal to 1; given 0" in msg
    assert "sweep.theta0 (line 4): expected a number, a list of numbers" in msg
    assert "sweep.length (line 5): empty range: start 2.0 > stop 1.0" in msg
    assert len(ei.value.problems) == 3, ei.value.problems


def test_nested_misspelling_and_yaml_syntax(tmp_path):
    with pytest.raises(ConfigError, match=r"fiber\.contact\.chii \(line 3\).*did you mean 'chi'"):
        load_config(_write(tmp_path, "fiber:\n  contact:\n    chii: 1.2\n"))
    with pytest.raises(ConfigError, match="invalid YAML"):
        load_config(_write(tmp_path, "sweep: [1, 2\n"))
    with pytest.raises(ConfigError, match="cannot read config"):
        load_config(tmp_path / "missing.yaml")


@pytest.mark.parametrize("name", ["quick.yaml", "paper.yaml"])
def test_shipped_configs_are_valid(name):
    from pathlib import Path

    cfg = load_config(Path(__file__).parents[2] / "configs" / name)
    n = len(grid_starts(cfg.sweep))
    assert n >= 20
    if name == "paper.yaml":
        th = [s.theta0 for s in grid_starts(cfg.sweep)]
        y0 = [s.y0 for s in grid_starts(cfg.sweep)]
        L = [s.length for s in grid_starts(cfg.sweep)]
        assert (min(th), max(th)) == (-10.0, 10.0)
        assert (min(y0), max(y0)) == (0.0, 1.0)
        assert (min(L), max(L)) == (0.5, 1.4)
        assert cfg.flow.dx == 2.0
        assert 1200 <= n <= 1400, n


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("sweep:\n  y0: [0.3, 1e9]\n", "sweep.y0 (line 2): y0/h = 1000000000.0"),
        ("sweep:\n  y0: 0.5\n  length: 0.01\n", "sweep.length (line 3): L/l_obs = 0.01"),
        # Centre on the pillar's centroid: the start overlaps the pillar.
        ("sweep:\n  y0: 0.333\n", None),
    ],
)
def test_sweep_points_are_checked_before_any_flow_is_computed(tmp_path, text, expected):
    """Starts outside the channel, unresolvable lengths: config error at the sweep field."""
    p = _write(tmp_path, text)
    if expected is None:
        assert grid_starts(load_config(p, physics=PHYSICS).sweep)  # far upstream: valid
        return
    with pytest.raises(ConfigError) as ei:
        load_config(p, physics=PHYSICS)
    assert expected in str(ei.value)
    assert len(ei.value.problems) == 1


def test_start_on_the_pillar_is_a_config_error(tmp_path):
    # x0 at the pillar's centre puts every bead of a centred fiber inside it.
    p = _write(tmp_path, "fiber:\n  x0: 1200\nsweep:\n  y0: 0.333\n")
    with pytest.raises(ConfigError, match=r"sweep\.y0 \(line 4\): .*overlaps the pillar"):
        load_config(p, physics=PHYSICS)


def test_fiber_that_does_not_fit_the_channel_length_names_fiber_x0(tmp_path):
    p = _write(tmp_path, "fiber:\n  x0: 1\nsweep:\n  y0: 0.9\n")
    with pytest.raises(ConfigError, match=r"fiber\.x0 \(line 2\): the fiber at x0 = 1"):
        load_config(p, physics=PHYSICS)


def test_prefiltered_start_check_keeps_every_failing_point():
    """Points skipped by the fast pre-check provably pass; every failing one is checked."""
    from fibersweep.config import Config, SweepSettings
    from fibersweep.config.fiber import FiberSettings
    from fibersweep.errors import InputError
    from fibersweep.fiber.contact.pillar import make_pillar
    from fibersweep.fiber.setup import check_start
    from fibersweep.sweep.starts import starts_to_check

    # x0 on the pillar's column, y0 from wall to wall, one unresolvable length: many
    # points fail, for each of the three reasons. model_construct skips the config's
    # own start check so that the failing points can be listed here.
    cfg = Config.model_construct(
        fiber=FiberSettings(x0=1150.0),
        sweep=SweepSettings(
            theta0={"start": -80, "stop": 80, "num": 9},
            y0={"start": -5.2, "stop": 5.6, "num": 41},
            length=[0.02, 0.5, 1.0, 2.5],
        ),
    )
    geo = cfg.flow.geometry.to_geometry()
    pillar = make_pillar(geo, cfg.fiber.contact, cfg.fiber.bead_radius, 1.0)

    def first_problems(starts):
        first: dict[str, str] = {}
        for s in starts:
            try:
                check_start(geo, cfg.flow.dx, cfg.fiber, s, pillar)
            except InputError as exc:
                kind = str(exc).split(":")[0] + (" pillar" if "pillar" in str(exc) else "")
                first.setdefault(kind, str(exc))
        return first

    every = first_problems(grid_starts(cfg.sweep))
    assert set(every) == {"length", "y0", "y0 pillar"}
    kept = starts_to_check(cfg, geo, pillar.r_cut)
    assert first_problems(kept) == every  # the same first problem of each kind
    # Position problems can fail anywhere, so every such point must be kept; the
    # length rule depends on L alone, so one point per length is enough.
    resolvable = [s for s in grid_starts(cfg.sweep) if s.length > 0.02]
    positions = [s for s in resolvable if first_problems([s])]
    assert positions and set(positions) <= set(kept)
    assert len(kept) < 0.6 * cfg.sweep.size  # and clear points are skipped


def test_executor_names_come_from_the_registry(tmp_path):
    """The config does not import the sweep: the caller (the CLI) hands the registry in."""
    from fibersweep.sweep.executors import EXECUTORS

    with pytest.raises(ConfigError) as ei:
        load_config(_write(tmp_path, "run:\n  executor: dsak\n"), executors=EXECUTORS)
    assert (
        "run.executor (line 2): unknown executor; did you mean 'dask'? valid: local, dask"
        in str(ei.value)
    )
    p = _write(tmp_path, "run:\n  executor: dask\n")
    assert load_config(p, executors=EXECUTORS).run.executor == "dask"
    # an executor's own option, checked against its options model
    p = _write(tmp_path, "run:\n  executor: local\n  options:\n    chunk_size: 4\n")
    with pytest.raises(ConfigError) as ei:
        load_config(p, executors=EXECUTORS)
    assert "run.options.chunk_size (line 4): not an option of the local executor" in str(ei.value)
    p = _write(tmp_path, "run:\n  executor: dask\n  options:\n    chunk_size: 4\n")
    assert load_config(p, executors=EXECUTORS).run.options == {"chunk_size": 4}


def test_cross_field_checks_report_at_their_field(tmp_path):
    """Model-level checks name their field structurally (FieldError), not in the text."""
    p = _write(tmp_path, "run:\n  executor: dask\n  scheduler: foo\n")
    with pytest.raises(ConfigError) as ei:
        load_config(p)
    assert "run.scheduler (line 3): expected an address like tcp://HOST:PORT" in str(ei.value)


def test_the_config_does_not_import_the_sweep():
    """Layering: config -> fiber/flow settings, never back into the sweep."""
    import subprocess
    import sys

    code = (
        "import sys, fibersweep.config as c\n"
        "c.load_config\n"
        "print(sorted(m for m in sys.modules if m.startswith('fibersweep.sweep')))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", out.stdout
