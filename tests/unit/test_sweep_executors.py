"""Executors: every task exactly once, failures reported, crashes survived (real processes)."""

from __future__ import annotations

import pytest
from _sweep_helpers import Job, init, square

from fibersweep.errors import InputError, SolverError
from fibersweep.sweep.executors import EXECUTORS, DaskExecutor, LocalExecutor, make_executor


def _collect(ex, jobs, **kw):
    outs = list(ex.run(square, jobs, **kw))
    keys = [o.key for o in outs]
    assert sorted(keys) == sorted(j.key for j in jobs), "each task exactly once"
    return {o.key: o for o in outs}


@pytest.fixture(scope="module")
def jobs():
    return [Job(f"k{i}", float(i), sleep=0.05) for i in range(8)]


def test_local_runs_every_task_once_with_initializer(jobs, tmp_path):
    ex = LocalExecutor(workers=2)
    res = _collect(ex, jobs, initializer=init, initargs=("T", str(tmp_path)))
    for j in jobs:
        assert res[j.key].error == ""
        assert res[j.key].value["x2"] == j.x**2
        assert res[j.key].value["tag"] == "T"
    # The initializer ran once per worker process, not once per task.
    assert len(list(tmp_path.glob("init-*"))) == 2
    assert len({o.value["pid"] for o in res.values()}) <= 2


def test_local_workers_start_with_one_blas_thread_unless_the_user_chose(monkeypatch):
    """Each worker is one core's share: its BLAS calls must not spread over all cores (a
    51-bead chain's W = M J product took 13-50 s threaded against 1 s on one thread);
    a count the user set is kept."""
    monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)
    monkeypatch.setenv("MKL_NUM_THREADS", "3")
    res = _collect(LocalExecutor(workers=2), [Job("a", 1.0), Job("b", 2.0)])
    for o in res.values():
        assert o.value["blas"] == {"OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "3"}


def test_local_exception_is_an_outcome_not_a_stop(tmp_path):
    jobs = [Job("a", 1.0), Job("bad", 2.0, action="raise"), Job("c", 3.0)]
    res = _collect(LocalExecutor(workers=2), jobs)
    assert res["a"].error == "" and res["c"].error == ""
    assert "ValueError: bad job bad" in res["bad"].error


def test_local_worker_crash_once_is_retried(tmp_path):
    """A worker killed mid-sweep (os._exit) breaks the pool; its tasks are re-run, none lost."""
    marker = tmp_path / "died"
    jobs = [Job(f"k{i}", float(i), sleep=0.05) for i in range(6)]
    jobs.insert(3, Job("dies", 9.0, sleep=0.05, action=f"die-once:{marker}"))
    ex = LocalExecutor(workers=2, retries=2)
    res = _collect(ex, jobs)
    assert marker.exists()
    assert all(o.error == "" for o in res.values()), {k: o.error for k, o in res.items()}
    assert res["dies"].value["x2"] == 81.0
    assert res["dies"].attempts == 2
    assert ex.pools_started == 2


@pytest.mark.parametrize(
    "error",
    [
        # a worker died since the last wait
        "BrokenProcessPool",
        # submit() starts workers on demand: one killed while it starts breaks its pipe
        "BrokenPipeError",
    ],
)
def test_local_pool_broken_at_submit_requeues_the_task(monkeypatch, error):
    """A pool that breaks inside submit() (either way): nothing lost, no strike."""
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    exc = {"BrokenProcessPool": BrokenProcessPool, "BrokenPipeError": BrokenPipeError}[error]
    real_submit = ProcessPoolExecutor.submit
    calls = {"n": 0}

    def submit(self, *args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 3:
            raise exc("simulated")
        return real_submit(self, *args, **kwargs)

    monkeypatch.setattr(ProcessPoolExecutor, "submit", submit)
    jobs = [Job(f"k{i}", float(i), sleep=0.02) for i in range(6)]
    ex = LocalExecutor(workers=2, retries=2)
    res = _collect(ex, jobs)
    assert all(o.error == "" for o in res.values()), {k: o.error for k, o in res.items()}
    assert all(o.attempts == 1 for o in res.values()), "a task that never started has no strike"
    assert ex.pools_started == 2


def test_local_poison_task_fails_alone(tmp_path):
    """A task that always kills its worker is reported failed; its neighbours are not blamed."""
    jobs = [Job(f"k{i}", float(i), sleep=0.02) for i in range(4)] + [
        Job("poison", 0.0, action="die")
    ]
    ex = LocalExecutor(workers=2, retries=1)
    res = _collect(ex, jobs)
    assert "BrokenProcessPool" in res["poison"].error
    assert res["poison"].attempts == 2
    assert all(res[f"k{i}"].error == "" for i in range(4))


def test_local_broken_initializer_stops_with_its_reason():
    ex = LocalExecutor(workers=1, retries=0)
    with pytest.raises(SolverError, match="worker set-up failed.*TypeError"):
        list(ex.run(square, [Job("a", 1.0)], initializer=init, initargs=(1, "/nonexistent/x")))


def test_registry_fails_loudly():
    with pytest.raises(InputError, match="valid: local, dask"):
        make_executor("slurm", 2)
    with pytest.raises(
        InputError, match=r"--scheduler \(run.scheduler\) applies to the dask executor only"
    ):
        make_executor("local", 2, scheduler="tcp://127.0.0.1:8786")


def test_registry_passes_chunk_size_to_dask_only():
    """Building a DaskExecutor needs no Dask: it is imported when the executor runs."""
    ex = make_executor("dask", 3, retries=1, chunk_size=4)
    assert isinstance(ex, DaskExecutor)
    assert (ex.workers, ex.retries, ex.chunk_size) == (3, 1, 4)
    assert make_executor("dask", 2).chunk_size is None, "automatic by default"
    with pytest.raises(
        InputError, match="chunk_size applies to the dask executor only, not 'local'"
    ):
        make_executor("local", 2, chunk_size=4)


def test_public_names_stay_importable_from_executors():
    """The split modules' names are the very objects ``executors`` re-exports."""
    import pickle

    from fibersweep.sweep import dask_executor, executor_base, executors, local_executor

    homes = {
        executor_base: ["Executor", "Outcome", "WorkerSetupError", "guarded_call", "guarded_init"],
        local_executor: ["LocalExecutor"],
        dask_executor: ["DaskExecutor", "chunk_sizes", "run_chunk"],
    }
    for module, names in homes.items():
        for name in names:
            assert name in executors.__all__
            assert getattr(executors, name) is getattr(module, name)
    # Sent to worker processes by reference: they must stay top-level and picklable.
    for fn in (executors.guarded_init, executors.guarded_call, executors.run_chunk):
        assert pickle.loads(pickle.dumps(fn)) is fn


def test_importing_executors_needs_no_dask():
    import subprocess
    import sys

    code = "import sys, fibersweep.sweep.executors; print('dask' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False", "Dask is an optional extra: import it only to run"


@pytest.mark.parametrize("kind", ["local", "dask"])
def test_a_bug_in_a_run_stops_the_sweep(kind):
    """A RunBug (a run raised something no run should) is not a failed row: it stops."""
    jobs = [Job("a", 1.0), Job("bug", 2.0, action="bug"), Job("c", 3.0)]
    ex = make_executor(kind, 2, None, 0)
    with pytest.raises(SolverError, match="(?s)a run hit a bug.*run bug: TypeError in the model"):
        list(ex.run(square, jobs))


def test_worker_records_failed_runs_and_raises_bugs(monkeypatch):
    """run_task: input and numerical errors are failed rows; any other exception a RunBug."""
    import fibersweep.fiber.run as run_module
    from fibersweep.config.fiber import FiberSettings
    from fibersweep.errors import RunBug
    from fibersweep.errors import SolverError as Solver
    from fibersweep.sweep import worker

    # a worker set up with a field that travels itself (no cache entry), no warm-up
    setting = worker.SettingSpec("", "test-field", "", "", FiberSettings().model_dump_json(), "F")
    monkeypatch.setattr(worker, "_SETUP", {})
    monkeypatch.setattr(worker, "_FIELDS", {})
    worker.init_worker(worker.WorkerSpec(settings=(setting,), warm=False))
    task = worker.SweepTask("id1", 0.0, 0.5, 1.0)
    for exc in (InputError("y0: overlaps the pillar"), Solver("NaN"), ZeroDivisionError()):

        def boom(*a, exc=exc, **k):
            raise exc

        monkeypatch.setattr(run_module, "simulate", boom)
        row = worker.run_task(task)["row"]
        assert row["status"] == "failed" and type(exc).__name__ in row["reason"]

    def bug(*a, **k):
        raise TypeError("unsupported operand")

    monkeypatch.setattr(run_module, "simulate", bug)
    with pytest.raises(RunBug, match="(?s)run id1 .*TypeError: unsupported operand"):
        worker.run_task(task)


@pytest.mark.parametrize("name", sorted(EXECUTORS))
def test_every_executor_declares_its_options_and_name(name):
    """Callers read what an executor does from its declarations, never from its name."""
    from fibersweep.sweep.executor_base import ExecutorOptions

    cls = EXECUTORS[name]
    assert cls.name == name and "retries" in cls.OPTIONS and "keep" in cls.OPTIONS
    assert issubclass(cls.Options, ExecutorOptions)
    assert set(cls.OPTIONS) == set(cls.Options.model_fields)
    assert isinstance(cls.parent_handles_ctrl_c, bool)
    # make_executor passes every declared option (at a non-default value) through
    ex = make_executor(name, 1, retries=0)
    assert ex.retries == 0 and ex.parent_handles_ctrl_c is cls.parent_handles_ctrl_c
    with pytest.raises(InputError, match=r"retries: .*greater than or equal to 0"):
        make_executor(name, 1, retries=-1)
    with pytest.raises(InputError, match=rf"queue applies to no executor, not '{name}'"):
        make_executor(name, 1, queue="gpu")


@pytest.mark.parametrize("name", sorted(EXECUTORS))
def test_kept_executor_reuses_its_workers_across_runs(name, tmp_path):
    """keep=True: many small batches pay the worker start-up (and set-up) once."""
    jobs = [Job(f"k{i}", float(i)) for i in range(4)]
    args = ("T", str(tmp_path))
    with make_executor(name, 2, keep=True) as ex:
        for batch in range(3):
            res = _collect(ex, [Job(f"{j.key}-{batch}", j.x) for j in jobs], initializer=init,
                           initargs=args)  # fmt: skip
            assert all(o.error == "" for o in res.values())
    # one set-up per worker process in all, not per batch
    assert 1 <= len(list(tmp_path.glob("init-*"))) <= 2
