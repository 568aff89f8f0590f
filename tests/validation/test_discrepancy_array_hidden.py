"""The discrepancy workflow in a pillar array on data with a hidden setting or effect (slow).

Each case synthesises ``N`` fibers through ``ROWS`` rows of the shipped array
(``configs/array.yaml`` at its own dx = 2 µm, so a row shift of 0.125 is a whole
number of cells: 10 µm = 5 dx) with the truth hidden, then runs the workflow
against the config as designed, with the hidden setting among the declared
candidates and two library effects that act in an array beside it. The label is
never given to the workflow. Plan: the reduced plan of the channel's fast hidden
tests (3 copies, 2 fit copies, 4 Brent steps; pairs, power and what-to-measure-next
off), so one case costs about 500-900 array runs.

Tolerances: the verdict must name exactly the hidden candidate (0 wrong names);
a fitted library effect's 95 % interval must hold the truth. Seeds are fixed
(one data set per case): these are checks that the slice works end to end on a
detectable truth, not the calibration of rates over seeds (left to a study).

Also here: the single-pillar snapshot at N = 60 is bit-identical to the stored
one (``scripts/studies/discrepancy/snapshot_n60.py``; regenerate with ``--write``
when a change is meant to alter it).
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

from fibersweep.api.compare import declared_candidates, sweep_box
from fibersweep.config import load_config
from fibersweep.discrepancy.array_schema import array_measured_data
from fibersweep.discrepancy.array_synth import synthesize_array
from fibersweep.discrepancy.array_workflow import array_effect_names
from fibersweep.discrepancy.copies import array_noise
from fibersweep.discrepancy.workflow import DiscrepancySettings, run_discrepancy
from fibersweep.flow.cache import get_flow_field

pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parents[2]
N = 60
ROWS = 6
BASE = ["flow.dx=2", f"fiber.array_rows={ROWS}", "run.workers=2"]
PLAN = dict(copies=3, fit_copies=2, candidates=2, fit_evals=4, refits=1, n_perm=1999, pairs=0,
            power_fibers=0, next_copies=0)  # fmt: skip


def _case(cache: Path, truth: list[str], effects: dict[str, float], declared: list[str],
          seed: int, library: tuple[str, ...] = ("friction", "pillar_hydro")):  # fmt: skip
    """Synthesise with ``truth`` (overrides) and ``effects`` hidden; analyse against the design."""
    made = load_config(REPO / "configs" / "array.yaml", [*BASE, *truth])
    field_t, _ = get_flow_field(made.flow, cache)
    table, _ = synthesize_array(field_t, made.fiber, sweep_box(made), N, effects, seed=seed,
                                workers=2, progress=False)  # fmt: skip
    cfg = load_config(REPO / "configs" / "array.yaml", BASE)
    field, _ = get_flow_field(cfg.flow, cache)
    s = DiscrepancySettings(seed=seed, workers=2, noise=array_noise(cfg.fiber),
                            effects=array_effect_names(library, cfg.fiber),
                            declared=declared_candidates(cfg, declared), **PLAN)  # fmt: skip
    return run_discrepancy(array_measured_data(table), field, cfg.fiber, s, progress=False,
                           flow=cfg.flow, cache_dir=cache)  # fmt: skip


def test_a_row_shift_one_lattice_step_off_is_named(flow_cache_dir):
    # designed 0.1 (8 µm per row), fabricated 0.125 (10 µm: one dx = 2 µm step more)
    res = _case(flow_cache_dir, ["flow.array.shift=0.125"], {}, ["flow.array.shift=0.125"], 5701)
    assert res.verdict.kind == "named", res.verdict.text
    assert list(res.verdict.effects) == ["flow.array.shift=0.125"], res.verdict.text


def test_a_pillar_ten_percent_larger_is_named(flow_cache_dir):
    res = _case(flow_cache_dir, ["flow.array.pillar_size=44"], {}, ["flow.array.pillar_size=44"],
                5702)  # fmt: skip
    assert res.verdict.kind == "named", res.verdict.text
    assert list(res.verdict.effects) == ["flow.array.pillar_size=44"], res.verdict.text


def test_hidden_friction_in_an_array_is_named_with_an_interval_holding_it(flow_cache_dir):
    res = _case(flow_cache_dir, [], {"friction": 0.8}, ["flow.array.shift=0.125"], 5703)
    assert res.verdict.kind == "named", res.verdict.text
    assert list(res.verdict.effects) == ["friction"], res.verdict.text
    lo, hi, *_ = res.extra["intervals"]["friction"]
    assert lo <= 0.8 <= hi, (lo, hi)


def test_no_hidden_effect_gives_no_gap_in_an_array(flow_cache_dir):
    res = _case(flow_cache_dir, [], {}, ["flow.array.shift=0.125"], 5704)
    assert res.verdict.kind == "no significant gap", res.verdict.text


def test_single_pillar_snapshot_at_n60_is_bit_identical():
    path = REPO / "scripts" / "studies" / "discrepancy" / "snapshot_n60.py"
    spec = importlib.util.spec_from_file_location("snapshot_n60", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    stored = mod.SNAPSHOT.read_text()
    now = json.dumps(mod.snapshot(workers=2), indent=1, sort_keys=True) + "\n"
    assert now == stored  # bit for bit: every float at full precision
