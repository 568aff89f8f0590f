"""A folder of several settings: tasks, ids, resume, retry and the changed-settings check.

No simulation: runs are written as rows, as the sweep's workers would write them.
"""

from __future__ import annotations

import pyarrow.parquet as pq
import pytest

from fibersweep.config import parse_config
from fibersweep.errors import InputError
from fibersweep.sweep.ids import run_ids
from fibersweep.sweep.manifest import write_manifest
from fibersweep.sweep.plan import make_tasks, plan_sweep, result_settings
from fibersweep.sweep.store import RUNS_DIR, PartWriter, list_parts, read_runs
from fibersweep.sweep.worker import failed_row

FRICTION = "fiber.effects.friction"


def _cfg(tmp_path, sweep=None, **fiber):
    return parse_config(
        {
            "fiber": fiber,
            "sweep": {"theta0": [-5.0, 5.0], "y0": [0.3, 0.8], "length": 1.0, **(sweep or {})},
            "run": {"output": str(tmp_path / "out")},
        }
    )


def _store(cfg, key="K", failed=()):
    """Write every task of ``cfg`` as done (ids in ``failed`` as failed) and its manifest."""
    plan = plan_sweep(cfg, key)
    write_manifest(
        cfg.run.output,
        {
            "config": cfg.model_dump(mode="json"),
            "result_settings": result_settings(cfg, key),
            "swept": plan.columns,
        },
    )
    with PartWriter(cfg.run.output) as w:
        for t in plan.tasks:
            if t.key in failed:
                w.add(failed_row(t, "nan"), None)
            else:
                w.add({"id": t.key, "theta0": t.theta0, "y0": t.y0, "length": t.length,
                       "class": "Below", "status": "ok", "wall_time": 0.5, **t.columns()},
                      None)  # fmt: skip
    return plan.tasks


def test_single_setting_ids_are_unchanged():
    """No setting axis: the ids are the content ids of before (start, fiber, flow key)."""
    cfg = parse_config({"sweep": {"theta0": [-5.0, 5.0], "y0": [0.3, 0.8]}})
    t, y, L = cfg.sweep.grid()
    assert [k.key for k in make_tasks(cfg, "K")] == run_ids(t, y, L, cfg.fiber, "K")


def test_each_combination_has_its_own_ids_settings_and_values(tmp_path):
    cfg = _cfg(tmp_path, {FRICTION: [0, 0.3, 0.6]})
    tasks = make_tasks(cfg, "K")
    assert len(tasks) == 4 * 3 and len({t.key for t in tasks}) == 12
    assert len({t.settings for t in tasks}) == 3
    assert [dict(t.values)[FRICTION] for t in tasks[::4]] == [0.0, 0.3, 0.6]
    # the friction-0.3 runs have the ids of a one-setting sweep with friction 0.3
    fixed = _cfg(tmp_path, effects={"friction": 0.3})
    assert {t.key for t in tasks[4:8]} == {t.key for t in make_tasks(fixed, "K")}


def test_an_effect_swept_to_its_baseline_reuses_the_runs_made_without_it(tmp_path):
    """friction 0 is friction off: those runs have the ids of a sweep without friction."""
    plain = make_tasks(_cfg(tmp_path), "K")
    swept = make_tasks(_cfg(tmp_path, {FRICTION: [0, 0.3]}), "K")
    assert [t.key for t in swept[:4]] == [t.key for t in plain]
    assert {dict(t.values)[FRICTION] for t in swept[:4]} == {0.0}
    assert not {t.key for t in swept[4:]} & {t.key for t in plain}


def test_mixed_folder_resumes_each_run_without_duplicates(tmp_path):
    small = _cfg(tmp_path, {FRICTION: [0, 0.3]})
    stored = _store(small, failed={"x"})
    grown = _cfg(tmp_path, {FRICTION: [0, 0.3, 0.6]})
    plan = plan_sweep(grown, "K")
    assert (plan.done_ok, plan.done_failed, len(plan.todo)) == (8, 0, 4) and not plan.changes
    assert {dict(t.values)[FRICTION] for t in plan.todo} == {0.6}
    assert {t.key for t in plan.todo}.isdisjoint({t.key for t in stored})
    # a smaller sweep keeps the other runs and runs nothing
    assert plan_sweep(_cfg(tmp_path, {FRICTION: [0.3]}), "K").kept_other == 4


def test_retry_failed_is_per_run_in_a_mixed_folder(tmp_path):
    cfg = _cfg(tmp_path, {FRICTION: [0, 0.3]})
    victim = make_tasks(cfg, "K")[5].key
    _store(cfg, failed={victim})
    plan = plan_sweep(cfg, "K", retry_failed=True)
    assert [t.key for t in plan.todo] == [victim] and plan.done_failed == 1
    assert plan_sweep(cfg, "K").todo == []


def test_changed_settings_check_ignores_only_the_swept_keys(tmp_path):
    cfg = _cfg(tmp_path, {FRICTION: [0, 0.3]})
    _store(cfg)
    # fixing a swept key to one value is not a change: the column stays, all runs done
    fixed = _cfg(tmp_path, effects={"friction": 0.3})
    plan = plan_sweep(fixed, "K")
    assert plan.columns == [FRICTION] and plan.todo == [] and not plan.changes
    assert [dict(t.values) for t in plan.tasks[:1]] == [{FRICTION: 0.3}]
    # any other setting is a change, named, as for one-setting sweeps
    with pytest.raises(InputError, match=r"fiber\.bead_radius: 2\.0 -> 1\.5"):
        plan_sweep(_cfg(tmp_path, {FRICTION: [0, 0.3]}, bead_radius=1.5), "K")
    with pytest.raises(InputError, match="flow_key: 'K' -> 'K2'"):
        plan_sweep(cfg, "K2")


def test_flow_axes_compare_the_unswept_flow_settings(tmp_path):
    cfg = _cfg(tmp_path, {"flow.geometry.pillar_height": [75, 60]})
    keys = ["K75", "K60"]
    assert len({t.flow_key for t in make_tasks(cfg, keys)}) == 2
    _store(cfg, keys)
    assert plan_sweep(cfg, keys).todo == []
    other = parse_config({**cfg.model_dump(mode="json"), "flow": {"dx": 2.0}})
    with pytest.raises(InputError, match=r"flow\.dx: 4\.0 -> 2\.0"):
        plan_sweep(other, keys)


def test_flow_axes_accept_a_manifest_from_before_keys_were_added(tmp_path):
    """Keys added since (pillar shape, precision) at their old-behaviour values are no change."""
    import json

    from fibersweep.sweep.manifest import MANIFEST

    cfg = _cfg(tmp_path, {"flow.geometry.pillar_height": [75, 60]})
    keys = ["K75", "K60"]
    _store(cfg, keys)
    path = tmp_path / "out" / MANIFEST
    man = json.loads(path.read_text())
    del man["config"]["flow"]["precision"]
    for name in ("pillar_shape", "pillar_rotation", "pillar_vertices"):
        del man["config"]["flow"]["geometry"][name]
    path.write_text(json.dumps(man))
    assert plan_sweep(cfg, keys).todo == []
    # away from the old behaviour the same keys are a change, named
    circle = parse_config(
        {**cfg.model_dump(mode="json"), "flow": {"geometry": {"pillar_shape": "circle"}}}
    )
    with pytest.raises(InputError, match=r"pillar_shape: \(absent\) -> 'circle'"):
        plan_sweep(circle, keys)


def test_runs_table_columns_of_swept_keys_are_typed_with_units(tmp_path):
    cfg = _cfg(tmp_path, {FRICTION: [0, 0.3], "fiber.contact.pillar": ["rough", "smooth"]})
    _store(cfg)
    schema = pq.read_schema(list_parts(tmp_path / "out" / RUNS_DIR)[0])
    assert str(schema.field(FRICTION).type) == "double"
    assert str(schema.field("fiber.contact.pillar").type) == "string"
    assert schema.field(FRICTION).metadata[b"doc"].startswith(b"swept setting")
    df = read_runs(tmp_path / "out")
    assert sorted(df.groupby([FRICTION, "fiber.contact.pillar"]).size()) == [4, 4, 4, 4]


def test_stored_runs_get_the_columns_of_a_later_axis(tmp_path):
    """Runs from before a key was swept are given its column when a sweep reuses them."""
    from fibersweep.sweep.runner import _fill_setting_columns

    _store(_cfg(tmp_path))  # no friction at all
    assert FRICTION not in read_runs(tmp_path / "out")
    cfg = _cfg(tmp_path, {FRICTION: [0, 0.6]})
    plan = plan_sweep(cfg, "K")
    assert plan.done_ok == 4 and len(plan.todo) == 4 and not plan.changes
    _fill_setting_columns(tmp_path / "out", {}, read_runs(tmp_path / "out"), plan)
    df = read_runs(tmp_path / "out")
    assert (df[FRICTION] == 0.0).all() and len(df) == 4 and df["settings"].notna().all()
