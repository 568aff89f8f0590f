"""Dask executor on a loopback LocalCluster (2 worker processes): same outcomes, survives a
worker killed mid-task. Cheap (a few seconds), so CI runs them."""

from __future__ import annotations

import pytest
from _sweep_helpers import Job, init, square

pytest.importorskip("distributed")

from fibersweep.errors import SolverError  # noqa: E402
from fibersweep.sweep.executors import DaskExecutor, LocalExecutor  # noqa: E402


def _run(ex, jobs, **kw):
    outs = list(ex.run(square, jobs, **kw))
    assert sorted(o.key for o in outs) == sorted(j.key for j in jobs), "each task exactly once"
    return {o.key: o for o in outs}


def test_dask_matches_local_and_inits_once_per_worker(tmp_path):
    jobs = [Job(f"k{i}", float(i), sleep=0.02) for i in range(10)]
    jobs.append(Job("bad", 1.0, action="raise"))
    d = _run(
        DaskExecutor(workers=2, retries=0), jobs, initializer=init, initargs=("D", str(tmp_path))
    )
    loc = _run(LocalExecutor(workers=2), jobs)
    for j in jobs:
        assert d[j.key].error.split(":")[0] == loc[j.key].error.split(":")[0]
        if not d[j.key].error:
            assert d[j.key].value["x2"] == loc[j.key].value["x2"] == j.x**2
            assert d[j.key].value["tag"] == "D"
    assert "bad job bad" in d["bad"].error
    # The plugin ran once per worker process (2), not once per task (11).
    assert len(list(tmp_path.glob("init-*"))) == 2


def test_dask_worker_killed_mid_task_loses_nothing(tmp_path):
    marker = tmp_path / "died"
    jobs = [Job(f"k{i}", float(i), sleep=0.05) for i in range(8)]
    jobs.insert(2, Job("dies", 5.0, sleep=0.05, action=f"die-once:{marker}"))
    res = _run(DaskExecutor(workers=2, retries=1), jobs, initializer=init, initargs=("D",))
    assert marker.exists(), "a worker process really died"
    assert all(o.error == "" for o in res.values()), {k: o.error for k, o in res.items()}
    assert res["dies"].value["x2"] == 25.0


def test_dask_setup_error_stops_with_reason():
    with pytest.raises(SolverError, match="worker set-up failed.*TypeError"):
        list(DaskExecutor(workers=1).run(square, [Job("a", 1.0)], init, (1, "/nonexistent")))


def test_dask_existing_scheduler_address(tmp_path):
    """--scheduler tcp://HOST:PORT: tasks go to a cluster we did not start."""
    from distributed import LocalCluster

    with LocalCluster(
        n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
    ) as cluster:
        ex = DaskExecutor(scheduler=cluster.scheduler_address)
        res = _run(ex, [Job("a", 3.0), Job("b", 4.0)], initializer=init, initargs=("S",))
        assert res["a"].value["x2"] == 9.0 and res["b"].value["tag"] == "S"
