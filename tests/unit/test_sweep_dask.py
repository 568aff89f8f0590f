"""Dask executor on a loopback LocalCluster (2 worker processes): same outcomes, chunked or
not, survives a worker killed mid-task or mid-chunk, blames no chunk-mate. Cheap (a few
seconds each), so CI runs them."""

from __future__ import annotations

import time

import pytest
from _sweep_helpers import Job, init, square

from fibersweep.errors import InputError, SolverError
from fibersweep.sweep.dask_executor import DaskExecutor, chunk_sizes
from fibersweep.sweep.local_executor import LocalExecutor

# chunk_sizes is pure: its tests need no Dask.


@pytest.mark.parametrize("n", [0, 1, 9, 18, 50, 100, 1323])
@pytest.mark.parametrize("slots", [1, 2, 16])
def test_auto_chunk_sizes_cover_every_run_and_shrink(n, slots):
    sizes = chunk_sizes(n, slots)
    assert sum(sizes) == n
    assert all(1 <= s <= 16 for s in sizes)
    assert sizes == sorted(sizes, reverse=True), "large chunks first"
    if n:
        assert sizes[0] == min(16, -(-n // (2 * slots)))  # ceil(n / (slots * 2)), clipped
        tail = min(n, slots)
        assert sizes[-tail:] == [1] * tail, "the sweep ends on single runs: no idle tail"


def test_auto_chunk_sizes_examples():
    assert chunk_sizes(100, 2) == [16, 16, 16, 13, 10, 8, 6, 4, 3, 2, 2, 1, 1, 1, 1]
    assert chunk_sizes(4, 2) == [1, 1, 1, 1]
    big = chunk_sizes(1323, 2)
    assert big.count(16) == 79 and len(big) == 91  # ~14.5 runs per Dask task
    assert chunk_sizes(10, 1, largest=3, per_slot=1) == [3, 3, 3, 1]


def test_fixed_chunk_sizes_and_bad_arguments():
    assert chunk_sizes(10, 2, chunk_size=4) == [4, 4, 2]
    assert chunk_sizes(3, 2, chunk_size=1) == [1, 1, 1]
    assert chunk_sizes(0, 2, chunk_size=4) == []
    for kw in ({"n_tasks": -1, "slots": 2}, {"n_tasks": 5, "slots": 0}):
        with pytest.raises(InputError):
            chunk_sizes(**kw)
    with pytest.raises(InputError, match="chunk_size"):
        chunk_sizes(5, 2, chunk_size=0)
    with pytest.raises(InputError, match="chunk_size"):
        DaskExecutor(chunk_size=0)


pytest.importorskip("distributed")


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


def test_dask_chunks_match_per_run_tasks_and_stream(tmp_path):
    """Chunks of 4: the same outcomes as one task per run and as the local pool; a run that
    raises fails alone (re-run alone once), its chunk-mates succeed; outcomes arrive chunk by
    chunk, not at the end."""
    jobs = [Job(f"k{i}", float(i), sleep=0.1) for i in range(12)]
    jobs[5] = Job("bad", 5.0, action="raise")  # inside the second chunk
    chunked = DaskExecutor(workers=2, retries=1, chunk_size=4)
    c, seen = {}, {}
    for o in chunked.run(square, jobs, init, ("C",)):
        assert o.key not in c, "each task exactly once"
        c[o.key], seen[o.key] = o, time.perf_counter()
    assert sorted(c) == sorted(j.key for j in jobs)
    assert chunked.chunks_submitted == 3 + 1, "3 chunks, then 'bad' alone once"
    single = DaskExecutor(workers=2, retries=1, chunk_size=1)
    s = _run(single, jobs, initializer=init, initargs=("C",))
    assert single.chunks_submitted == 12 + 1
    loc = _run(LocalExecutor(workers=2), jobs)
    for j in jobs:
        assert c[j.key].error.split(":")[0] == s[j.key].error.split(":")[0]
        assert c[j.key].error.split(":")[0] == loc[j.key].error.split(":")[0]
        if j.key != "bad":
            assert c[j.key].error == "" and c[j.key].attempts == 1
            assert c[j.key].value["x2"] == s[j.key].value["x2"] == loc[j.key].value["x2"]
            assert c[j.key].value["tag"] == "C"
    assert c["bad"].error == "ValueError: bad job bad" and c["bad"].attempts == 2
    # 3 chunks of 0.4 s on 2 workers: one worker runs two in a row, so the first outcomes
    # were yielded at least one chunk's duration before the last.
    assert max(seen.values()) - min(seen.values()) > 0.25


@pytest.mark.parametrize("chunk_size", [None, 3])
def test_dask_worker_killed_mid_task_loses_nothing(tmp_path, chunk_size):
    marker = tmp_path / "died"
    jobs = [Job(f"k{i}", float(i), sleep=0.05) for i in range(8)]
    jobs.insert(2, Job("dies", 5.0, sleep=0.05, action=f"die-once:{marker}"))
    ex = DaskExecutor(workers=2, retries=1, chunk_size=chunk_size)
    res = _run(ex, jobs, initializer=init, initargs=("D",))
    assert marker.exists(), "a worker process really died"
    assert all(o.error == "" for o in res.values()), {k: o.error for k, o in res.items()}
    assert res["dies"].value["x2"] == 25.0
    if chunk_size == 3:
        assert ex.chunks_submitted == 3, "the scheduler re-ran the killed chunk as it was"


def test_dask_poison_run_in_a_chunk_fails_alone():
    """A run that always kills its worker: once the scheduler gives up on its chunk, each run
    of the chunk is re-run alone; only the poison run is reported failed."""
    import dask

    jobs = [
        Job("k0", 0.0, sleep=0.02),
        Job("k1", 1.0, sleep=0.02),
        Job("poison", 0.0, action="die"),
    ]
    ex = DaskExecutor(workers=2, retries=0, chunk_size=3)
    # Give up on a task after its first worker death (default 3) to keep the test short.
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        res = _run(ex, jobs, initializer=init, initargs=("P",))
    assert "KilledWorker" in res["poison"].error
    assert res["poison"].attempts == 2
    for k in ("k0", "k1"):
        assert res[k].error == "" and res[k].attempts == 2, res[k]
    assert ex.chunks_submitted == 1 + 3


@pytest.mark.parametrize("chunk_size", [None, 2])
def test_dask_setup_error_stops_with_reason(chunk_size):
    jobs = [Job("a", 1.0), Job("b", 2.0), Job("c", 3.0)]
    ex = DaskExecutor(workers=1, retries=1, chunk_size=chunk_size)
    with pytest.raises(SolverError, match="worker set-up failed.*TypeError"):
        list(ex.run(square, jobs, init, (1, "/nonexistent")))


def test_dask_duplicate_keys_are_refused():
    with pytest.raises(InputError, match="unique"):
        list(DaskExecutor(workers=1).run(square, [Job("a", 1.0), Job("a", 2.0)]))


def test_dask_existing_scheduler_address(tmp_path):
    """--scheduler tcp://HOST:PORT: tasks go to a cluster we did not start."""
    from distributed import LocalCluster

    with LocalCluster(
        n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
    ) as cluster:
        ex = DaskExecutor(scheduler=cluster.scheduler_address)
        res = _run(ex, [Job("a", 3.0), Job("b", 4.0)], initializer=init, initargs=("S",))
        assert res["a"].value["x2"] == 9.0 and res["b"].value["tag"] == "S"


def test_local_cluster_serves_no_web_pages():
    """The README promises no dashboard: the scheduler's HTTP port answers 404 everywhere."""
    import urllib.error
    import urllib.request

    from fibersweep.sweep.dask_executor import local_cluster

    cluster = local_cluster(1)
    try:
        port = cluster.scheduler.http_server.port
        assert port != 8787
        for path in ("/status", "/health", "/metrics"):
            with pytest.raises(urllib.error.HTTPError) as exc:
                urllib.request.urlopen(f"http://127.0.0.1:{port}{path}", timeout=5)
            assert exc.value.code == 404
    finally:
        cluster.close()


def test_dask_leaves_the_callers_logging_as_it_was():
    """The executor quiets Dask's INFO chatter only while it runs (no global change)."""
    import logging

    logger = logging.getLogger("distributed")
    before = logger.level
    outs = list(DaskExecutor(workers=1).run(square, [Job("a", 2.0)]))
    assert [o.value["x2"] for o in outs] == [4.0]
    assert logger.level == before
