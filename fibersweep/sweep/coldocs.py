"""Unit and meaning of the columns the runs table's fixed list does not cover.

Every column fibersweep writes carries ``unit`` and ``doc`` in its Parquet field
metadata, so a table read outside fibersweep says what it holds. The fixed runs
columns have theirs in :data:`fibersweep.sweep.store.COLUMN_DOCS`; this module
holds the trajectories table's and those of the runs columns added by
``classify`` and by the labelling rule, and stamps them on an Arrow table.
"""

from __future__ import annotations

from collections.abc import Mapping

import pyarrow as pa

from fibersweep.analysis.classify import RULES

__all__ = ["RUN_EXTRA_DOCS", "TRAJ_COLUMN_DOCS", "docs_for", "rule_column", "with_docs"]

#: Columns of the trajectories table: (unit, meaning). Positions are in the channel
#: frame (x along the flow from the inlet end, y from the side wall at 0).
TRAJ_COLUMN_DOCS: dict[str, tuple[str, str]] = {
    "id": ("", "run id (joins the runs table)"),
    "sample": ("", "sample index, 0, 1, ... in time order"),
    "t": ("s", "simulated time from the start of the run"),
    "x": ("µm", "centre-of-mass x, channel frame"),
    "y": ("µm", "centre-of-mass y, channel frame"),
    "theta": ("deg", "angle of the tail-to-head vector from +x, unwrapped (starts at theta0)"),
    "head_x": ("µm", "head bead centre x, channel frame"),
    "head_y": ("µm", "head bead centre y, channel frame"),
    "tail_x": ("µm", "tail bead centre x, channel frame"),
    "tail_y": ("µm", "tail bead centre y, channel frame"),
    "head_speed": ("µm/s", "speed of the head bead"),
    "com_speed": ("µm/s", "speed of the centre of mass"),
    "contact": ("", "the contact force is non-zero at the sample"),
    "beads": ("µm", "every bead centre, flattened (x0, y0, x1, y1, ...) per sample"),
}


def rule_column(rule: str) -> str:
    """Runs-table column holding the class under a rule (``head-speed`` -> ``class_head_speed``)."""
    return "class_" + rule.replace("-", "_")


#: Runs-table columns outside the fixed list: the labelling rule and, after
#: ``fibersweep classify``, the class under each rule of the registry.
RUN_EXTRA_DOCS: dict[str, tuple[str, str]] = {
    "class_rule": ("", f"pole-vaulting rule that labelled 'class' (one of {', '.join(RULES)})"),
    **{rule_column(r): ("", f"class under the {r} rule (written by classify)") for r in RULES},
}


def docs_for(name: str, docs: Mapping[str, tuple[str, str]]) -> dict[str, str] | None:
    """Field metadata ``{"unit", "doc"}`` of column ``name``, or None if unknown."""
    if name not in docs:
        return None
    unit, doc = docs[name]
    return {"unit": unit, "doc": doc}


def with_docs(table: pa.Table, docs: Mapping[str, tuple[str, str]]) -> pa.Table:
    """``table`` with the unit and meaning of each known column in its field metadata."""
    fields = []
    for f in table.schema:
        meta = docs_for(f.name, docs)
        fields.append(f.with_metadata({**(f.metadata or {}), **meta}) if meta else f)
    return table.cast(pa.schema(fields, metadata=table.schema.metadata))
