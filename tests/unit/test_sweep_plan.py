"""Sweep planning: what is done, what to run, what changed (no simulation needed)."""

from __future__ import annotations

import pytest

from fibersweep.config import parse_config
from fibersweep.errors import InputError
from fibersweep.sweep.manifest import write_manifest
from fibersweep.sweep.plan import make_tasks, move_aside, plan_sweep, result_settings
from fibersweep.sweep.store import PartWriter, read_runs
from fibersweep.sweep.worker import failed_row


def _cfg(tmp_path, **fiber):
    return parse_config(
        {
            "fiber": fiber,
            "sweep": {"theta0": [-5.0, 0.0, 5.0], "y0": [0.3, 0.4], "length": 1.0},
            "run": {"output": str(tmp_path / "out")},
        }
    )


def _store(cfg, key, n_ok, n_failed=0):
    tasks = make_tasks(cfg, key)
    out = cfg.run.output
    write_manifest(out, {"config": cfg.model_dump(mode="json"),
                         "result_settings": result_settings(cfg, key)})  # fmt: skip
    with PartWriter(out) as w:
        for t in tasks[:n_ok]:
            w.add({"id": t.key, "theta0": t.theta0, "y0": t.y0, "length": t.length,
                   "class": "Below", "status": "ok", "wall_time": 0.5}, None)  # fmt: skip
        for t in tasks[n_ok : n_ok + n_failed]:
            w.add(failed_row(t, "nan"), None)
    return tasks


def test_fresh_output_runs_everything(tmp_path):
    cfg = _cfg(tmp_path)
    plan = plan_sweep(cfg, "K")
    assert len(plan.tasks) == 6 and len(plan.todo) == 6 and plan.mean_run_s is None
    assert len({t.key for t in plan.tasks}) == 6


def test_repeated_axis_values_run_once(tmp_path):
    cfg = parse_config({"sweep": {"theta0": [0.0, 0.0, 1e-13], "y0": 0.4}})
    assert len(make_tasks(cfg, "K")) == 1


def test_resume_retry_and_estimate(tmp_path):
    cfg = _cfg(tmp_path)
    tasks = _store(cfg, "K", n_ok=3, n_failed=1)
    plan = plan_sweep(cfg, "K")
    assert (plan.done_ok, plan.done_failed) == (3, 1)
    assert [t.key for t in plan.todo] == [t.key for t in tasks[4:]]
    assert plan.estimate_s(workers=2) == pytest.approx(0.5 * 2 / 2)
    retry = plan_sweep(cfg, "K", retry_failed=True)
    assert [t.key for t in retry.todo] == [tasks[3].key]
    fresh = plan_sweep(cfg, "K", resume=False)
    assert fresh.fresh and len(fresh.todo) == 6


def test_growing_the_sweep_keeps_old_points(tmp_path):
    cfg = _cfg(tmp_path)
    _store(cfg, "K", n_ok=6)
    bigger = cfg.model_copy(update={"sweep": cfg.sweep.model_copy(update={"y0": [0.3, 0.4, 0.5]})})
    plan = plan_sweep(bigger, "K")
    assert plan.done_ok == 6 and len(plan.todo) == 3 and not plan.changes
    smaller = cfg.model_copy(update={"sweep": cfg.sweep.model_copy(update={"y0": [0.3]})})
    assert plan_sweep(smaller, "K").kept_other == 3


def test_changed_physics_or_field_is_refused_with_the_difference(tmp_path):
    cfg = _cfg(tmp_path)
    _store(cfg, "K", n_ok=6)
    with pytest.raises(InputError) as ei:
        plan_sweep(_cfg(tmp_path, bead_radius=1.5), "K")
    msg = str(ei.value)
    assert "fiber.bead_radius: 2.0 -> 1.5" in msg and "6 of the 6 stored runs" in msg
    with pytest.raises(InputError, match="flow_key: 'K' -> 'K2'"):
        plan_sweep(cfg, "K2")
    # Thresholds: a note, not an error.
    plan = plan_sweep(_cfg(tmp_path, classify={"trap_time": 4.0}), "K")
    assert plan.todo == [] and "fibersweep classify" in plan.notes[0]


def test_move_aside_keeps_old_results(tmp_path):
    cfg = _cfg(tmp_path)
    _store(cfg, "K", n_ok=2)
    dest = move_aside(tmp_path / "out")
    assert dest is not None and len(read_runs(dest)) == 2
    assert read_runs(tmp_path / "out").empty


def test_resume_notes_runs_of_another_revision(tmp_path, monkeypatch):
    """Resuming runs made by another fibersweep revision gives a note (not an error)."""
    import fibersweep.sweep.manifest as M

    cfg = _cfg(tmp_path)
    key = "K"
    _store(cfg, key, n_ok=3)
    manifest = M.read_manifest(cfg.run.output)
    manifest["provenance"] = {"git": "a" * 40}
    write_manifest(cfg.run.output, manifest)
    monkeypatch.setattr(M, "revision", lambda: ("b" * 40, "checkout"))
    plan = plan_sweep(cfg, key)
    assert plan.done_ok == 3 and any("revision aaaaaaaaaaaa" in n for n in plan.notes)
    monkeypatch.setattr(M, "revision", lambda: ("a" * 40, "checkout"))
    assert not any("revision" in n for n in plan_sweep(cfg, key).notes)
    monkeypatch.setattr(M, "revision", lambda: ("b" * 40, "checkout"))
    assert not any("revision" in n for n in plan_sweep(cfg, key, resume=False).notes)
