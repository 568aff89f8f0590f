"""Batch runner of the discrepancy workflow: budget, failures recorded, effects validated."""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.simulate import BudgetExhausted, Simulator
from fibersweep.errors import InputError
from fibersweep.flow.field import FlowField
from fibersweep.units import Geometry


@pytest.fixture(scope="module")
def uniform_field():
    g = Geometry()
    return FlowField.from_function(lambda X, Y: (600.0 + 0 * X, 0 * X), g, 8.0)


def test_budget_is_enforced_before_running(uniform_field):
    with Simulator(uniform_field, FiberSettings(), workers=1, budget=3, progress=False) as sim:
        with pytest.raises(BudgetExhausted, match="only 3"):
            sim.run(np.zeros((4, 3)) + [0, 0.1, 1.0], {}, np.arange(4))
        assert sim.used == 0


def test_bad_start_is_a_recorded_failure_and_unknown_effect_an_input_error(uniform_field):
    with Simulator(uniform_field, FiberSettings(), workers=1, progress=False) as sim:
        starts = np.array([[0.0, -2.0, 1.0], [0.0, 9.0, 1.0]])  # the second is outside the channel
        df = sim.run(starts, {}, np.arange(2))
        assert list(df["status"]) == ["ok", "failed"]
        assert "y0" in df["reason"][1] and np.isnan(df["delta"][1])
        assert sim.used == 2 and sim.failed == 1
        with pytest.raises(InputError, match="valid names"):
            sim.run(starts, {"fricton": 0.2}, np.arange(2))



def test_a_bare_batch_whose_every_run_failed_stops_with_an_error(uniform_field):
    """No verdict may rest on a model that ran none of the fibers; under an effect such a
    batch is an outcome of the effect and is returned."""
    from fibersweep.errors import SolverError

    starts = np.array([[0.0, 9.0, 1.0], [0.0, 8.0, 1.0]])  # both outside the channel
    with Simulator(uniform_field, FiberSettings(), workers=1, progress=False) as sim:
        with pytest.raises(SolverError, match="every one of the 2 runs"):
            sim.run(starts, {}, np.arange(2), desc="baseline")
        df = sim.run(starts, {"friction": 0.2}, np.arange(2))
        assert list(df["status"]) == ["failed", "failed"]

@pytest.mark.parametrize(("executor", "workers"), [("local", 2), ("dask", 2)])
def test_batches_run_on_every_executor_with_the_same_results(uniform_field, executor, workers):
    """The workflow's simulations go through the sweep executors: the local pool and Dask
    give the in-process rows exactly (every run has its own seed), batch after batch."""
    starts = np.array([[0.0, -2.0, 1.0], [5.0, -1.5, 0.8], [0.0, 9.0, 1.0], [-5.0, 2.5, 1.2]])
    seeds = np.arange(4)
    with Simulator(uniform_field, FiberSettings(), workers=1, progress=False) as sim:
        want = sim.run(starts, {"friction": 0.2}, seeds)
    with Simulator(
        uniform_field, FiberSettings(), workers=workers, progress=False, executor=executor
    ) as sim:
        for _ in range(2):  # the kept workers serve a second batch too
            got = sim.run(starts, {"friction": 0.2}, seeds)
            assert got.equals(want)
        assert sim.used == 8 and sim.failed == 2


def test_copies_reuse_the_runs_of_a_subset_and_equal_a_fresh_full_copy(uniform_field):
    # a copy of rows {1, 3} and then of all 5 fibers simulates 5 runs in all, and the full
    # copy equals one made in one batch by a fresh maker (same draws: common random numbers)
    from fibersweep.discrepancy.copies import CopyMaker, NoiseModel

    starts = np.array([[0.0, -2.0, 1.0], [5.0, -1.5, 0.8], [0.0, 1.0, 1.0],
                       [-5.0, 2.5, 1.2], [2.0, 0.5, 0.9]])  # fmt: skip
    eff = {"friction": 0.2}
    with Simulator(uniform_field, FiberSettings(), workers=1, progress=False) as sim:
        maker = CopyMaker(starts, NoiseModel(), 3, sim)
        part = maker.copy(1, eff, np.array([3, 1]))
        full = maker.copy(1, eff)
        again = maker.copy(1, eff, np.array([4, 0]))
        assert sim.used == 5
        # keyed by the exact row set, the first two copies were 2 + 5 runs, the third free
        assert maker.runs_without_reuse == 7
    with Simulator(uniform_field, FiberSettings(), workers=1, progress=False) as sim:
        want = CopyMaker(starts, NoiseModel(), 3, sim).copy(1, eff)
    assert full.equals(want)
    assert part.equals(want.iloc[[3, 1]].reset_index(drop=True))
    assert again.equals(want.iloc[[4, 0]].reset_index(drop=True))


def test_several_copies_are_one_batch_and_equal_copy_by_copy(uniform_field):
    # copies 0..2 of rows {0, 2, 4} after copy 1 of row 2: one batch of the 8 missing
    # runs, and every table equals the one a fresh maker makes copy by copy
    from fibersweep.discrepancy.copies import CopyMaker, NoiseModel

    starts = np.array([[0.0, -2.0, 1.0], [5.0, -1.5, 0.8], [0.0, 1.0, 1.0],
                       [-5.0, 2.5, 1.2], [2.0, 0.5, 0.9]])  # fmt: skip
    rows = np.array([0, 2, 4])
    eff = {"friction": 0.2}
    with Simulator(uniform_field, FiberSettings(), workers=1, progress=False) as sim:
        maker = CopyMaker(starts, NoiseModel(), 3, sim)
        maker.copy(1, eff, np.array([2]))
        batches = sim._batches
        got = maker.copies(range(3), eff, rows)
        assert sim._batches == batches + 1 and sim.used == 9
    with Simulator(uniform_field, FiberSettings(), workers=1, progress=False) as sim:
        fresh = CopyMaker(starts, NoiseModel(), 3, sim)
        want = [fresh.copy(k, eff, rows) for k in range(3)]
    for g, w in zip(got, want, strict=True):
        assert g.equals(w)


def test_a_cached_field_travels_as_its_entry_and_an_in_memory_one_as_itself(
    uniform_field, coarse_field
):
    """One run path: the workflow's workers map a cached field by its key, like a sweep's;
    a field built in memory (no entry to map) is sent once in the worker spec."""
    from fibersweep.sweep import worker

    cached = worker.setting_for_field(coarse_field, FiberSettings())
    assert cached.field is None and cached.field_path.endswith(cached.flow_key)
    mapped = worker.field_for(cached)
    assert isinstance(mapped.ux, np.memmap) and mapped.geometry == coarse_field.geometry
    assert np.array_equal(mapped.ux, coarse_field.ux) and mapped.dx == coarse_field.dx
    assert worker.field_for(cached) is mapped, "one mapping per process, by cache key"
    memory = worker.setting_for_field(uniform_field, FiberSettings())
    assert memory.field is uniform_field and memory.field_path == ""


def test_a_workflow_that_stops_early_ends_its_bar_at_the_runs_it_used(uniform_field, capsys):
    """Planned 1150 runs, 2 used: the bar (plain lines into a captured stderr) ends at 2/2."""
    starts = np.array([[0.0, -2.0, 1.0], [5.0, -1.5, 0.8]])
    with Simulator(uniform_field, FiberSettings(), workers=1, budget=1150) as sim:
        sim.run(starts, {}, np.arange(2), desc="screen effects")
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert "\r" not in err and "0/1150" in lines[0]
    assert lines[-1].startswith("screen effects") and "2/2" in lines[-1], lines


def test_the_bar_counts_what_will_run_and_says_what_later_stages_may_add(
    uniform_field, monkeypatch
):
    """The bar's length is the runs done plus those the next stages will run (not the
    plan's worst case); the runs of stages that depend on an outcome are said beside it."""
    import io

    from fibersweep.discrepancy import simulate as simulate_mod
    from fibersweep.progressbar import progress_bar

    out = io.StringIO()
    monkeypatch.setattr(
        simulate_mod, "progress_bar", lambda **kw: progress_bar(file=out, **kw)
    )
    starts = np.zeros((3, 3)) + [0.0, -2.0, 1.0]
    with Simulator(uniform_field, FiberSettings(), workers=1, planned=1000) as sim:
        sim.expect(3, later=500)
        sim.run(starts, {}, np.arange(3))
        bar = sim._bar
        assert bar.total == 3 and bar.n == 3  # not the 1000 planned at worst
        assert "up to 500 more" in str(bar.postfix)
        sim.expect(2)  # the next stage: 2 runs, nothing later
        assert bar.total == 5 and not bar.postfix
        sim.run(starts, {}, np.arange(3))  # a batch beyond what was said grows the bar
        assert bar.total == 6 and bar.n == 6


def test_runs_moved_from_later_into_the_bar_keep_what_was_said(uniform_field):
    """expect(10, later=20), then 5 of the later runs start: 15 ahead, 15 still later."""
    with Simulator(uniform_field, FiberSettings(), workers=1) as sim:
        sim.expect(10, later=20)
        sim.expect_more(5)
        assert sim._planned == sim.used + 15 and sim._later == 15
        sim.expect_more(30)
        assert sim._planned == sim.used + 45 and sim._later == 0
