"""The flow fields of a sweep: one per distinct flow setting, found or computed once.

Also what the manifest records per setting combination (its field, the
U_center its runs move in, the separatrix).
"""

from __future__ import annotations

import logging
from typing import Any

from fibersweep.config import Config
from fibersweep.sweep.plan import SweepPlan, plan_sweep, sweep_settings

__all__ = [
    "combinations_entry",
    "effective_u_center",
    "flow_field_for",
    "flow_key_for",
    "flow_keys_for",
    "prepare",
]

log = logging.getLogger(__name__)


def flow_field_for(cfg: Config, *, mmap: bool = True) -> tuple[Any, Any]:
    """The flow field of a config from the cache (computed once if missing)."""
    from fibersweep.flow.cache import get_flow_field

    return get_flow_field(cfg.flow, cfg.run.cache_dir, mmap=mmap)


def flow_key_for(cfg: Config) -> tuple[str, bool]:
    """The flow-field key of a config and whether the field is cached (computes nothing)."""
    from fibersweep.flow.cache import cache_key, entry_complete

    return cache_key(cfg.flow), entry_complete(cfg.flow, cfg.run.cache_dir)


def flow_keys_for(cfg: Config) -> dict[str, tuple[Any, bool]]:
    """Each distinct flow setting of a sweep: key -> (FlowSettings, cached?); computes nothing.

    In the order the sweep runs them (one entry without flow axes).
    """
    out: dict[str, tuple[Any, bool]] = {}
    for st in sweep_settings(cfg):
        if st.flow_key not in out:
            out[st.flow_key] = (st.config.flow, flow_key_for(st.config)[1])
    return out


def prepare(
    cfg: Config, *, resume: bool = True, retry_failed: bool = False
) -> tuple[dict[str, tuple[Any, Any]], SweepPlan]:
    """Fields and plan of a sweep.

    Every distinct flow setting's field is found in the cache or computed, once,
    before any fiber runs.

    Returns
    -------
    fields : dict
        Flow key -> (FlowField, CacheInfo), in the order the sweep uses them.
    plan : SweepPlan
    """
    from fibersweep.flow.cache import get_flow_field

    plan = plan_sweep(cfg, None, resume=resume, retry_failed=retry_failed, repair=True)
    fields: dict[str, tuple[Any, Any]] = {}
    for st in plan.settings:
        if st.flow_key not in fields:
            fieldobj, info = get_flow_field(st.config.flow, cfg.run.cache_dir, mmap=True)
            if info.key != st.flow_key:  # the cache's key function is the plan's
                raise RuntimeError(f"flow key {info.key} != planned {st.flow_key}")
            fields[st.flow_key] = (fieldobj, info)
    return fields, plan


def effective_u_center(fieldobj: Any, fiber: Any) -> float:
    """U_center [µm/s] the runs move in: the field's after the effects that change it.

    The classification thresholds are fractions of this speed; ``classify``
    re-applies them later from the manifest, so it must be the run's own.
    """
    from fibersweep.fiber.effects import build_effects
    from fibersweep.flow.cell import CellField

    if isinstance(fieldobj, CellField):  # array effects act in the kernels only
        return fieldobj.u_center
    return float(build_effects(fiber.effects).field(fieldobj).fluid.u_center)


def _separatrix(fieldobj: Any, info: Any, old: dict[str, Any]) -> float | None:
    """Far-upstream separatrix y/h_obs of a field (reused from the stored manifest).

    None for a pillar array's unit cell (no upstream far field).
    """
    from fibersweep.flow.cell import CellField

    if isinstance(fieldobj, CellField):
        return None
    if old.get("provenance", {}).get("flow_key") == info.key and "separatrix" in old:
        return old["separatrix"]
    for entry in (old.get("combinations") or {}).values():
        if entry.get("flow_key") == info.key and "separatrix" in entry:
            return entry["separatrix"]
    try:
        from fibersweep.flow.streamlines import separatrix_y

        return float(separatrix_y(fieldobj))
    except Exception as exc:  # a figure aid: never stop a sweep over it
        log.warning("separatrix not computed: %s", exc)
        return None


def combinations_entry(
    plan: SweepPlan, fields: dict[str, tuple[Any, Any]], old: dict[str, Any]
) -> dict[str, dict[str, Any]]:
    """Manifest entries per settings id: swept values, flow, U_center and separatrix.

    Entries of settings run before in this folder are kept, so ``classify`` and
    the figures find every stored run's own field and speed.
    """
    out = dict(old.get("combinations") or {})
    seps: dict[str, float | None] = {}
    for st in plan.settings:
        fieldobj, info = fields[st.flow_key]
        if st.flow_key not in seps:
            seps[st.flow_key] = _separatrix(fieldobj, info, old)
        out[st.id] = {
            "values": st.combination.values,
            "flow_key": st.flow_key,
            "flow": st.config.flow.model_dump(mode="json"),
            "u_center_effective": effective_u_center(fieldobj, st.config.fiber),
            "separatrix": seps[st.flow_key],
        }
    return out
