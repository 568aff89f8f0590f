"""Re-label stored runs from their trajectories with new thresholds (no simulation)."""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np
import pandas as pd
from pydantic import ValidationError

from fibersweep.analysis.classify import RULES, classify_all
from fibersweep.analysis.tables import per_combination, trajectory_from_frame
from fibersweep.config.fiber import ClassifySettings
from fibersweep.config.flow import FlowSettings
from fibersweep.errors import InputError
from fibersweep.fiber.result import CLASSES
from fibersweep.sorting.modes import is_array_table, mode_counts, relabel_modes
from fibersweep.sweep.coldocs import rule_column
from fibersweep.sweep.lock import output_lock
from fibersweep.sweep.manifest import read_manifest
from fibersweep.sweep.relabel import Reclassified, classified_meta, replace_labels
from fibersweep.sweep.store import RUNS_DIR, list_parts, read_runs, read_trajectories

__all__ = [
    "class_counts",
    "reclassify",
    "rule_column",
    "thresholds_for",
]

log = logging.getLogger(__name__)


def _beyond_simulated(
    thresholds: ClassifySettings, simulated: ClassifySettings, n_unclassified: int
) -> tuple[str, ...]:
    """Why runs may be unclassifiable: the runs stopped on the *simulated* trap rule.

    A run ends once it has been stopped in contact for the simulated trap_time, so a
    longer trap_time (or a stricter trap_speed) asks about time that was never simulated.
    """
    if (
        thresholds.trap_time <= simulated.trap_time
        and thresholds.trap_speed >= simulated.trap_speed
    ):
        return ()
    return (
        f"the runs were simulated with the trap stop rule trap_time = {simulated.trap_time} s, "
        f"trap_speed = {simulated.trap_speed}: a run stopped in contact that long ended there, "
        f"so trap_time = {thresholds.trap_time} s / trap_speed = {thresholds.trap_speed} cannot "
        f"be decided from its trajectory ({n_unclassified} runs unclassified). To decide them, "
        "set fiber.classify to the new values and run the sweep again with --no-resume.",
    )


def thresholds_for(
    out: Path, base: ClassifySettings | None = None, **overrides: float | None
) -> ClassifySettings:
    """Thresholds: ``base`` (or the stored config's), then the non-None ``overrides``."""
    if base is None:
        man = read_manifest(Path(out)) or {}
        stored = man.get("config", {}).get("fiber", {}).get("classify")
        base = ClassifySettings.model_validate(stored) if stored else ClassifySettings()
    upd = {k: v for k, v in overrides.items() if v is not None}
    try:
        return ClassifySettings.model_validate({**base.model_dump(), **upd})
    except ValidationError as exc:
        raise InputError(f"classification thresholds: {exc}") from None


def class_counts(runs: pd.DataFrame, by: list[str] | None = None) -> pd.DataFrame:
    """Runs per class (ok runs) and failures, with fractions.

    Parameters
    ----------
    runs : DataFrame
        The runs table.
    by : list of str, optional
        Swept-setting columns: one block of counts per combination of their
        values (fractions within it), the key columns first.

    Returns
    -------
    DataFrame
        Columns ``*by``, class, runs, fraction.
    """
    by = [k for k in (by or []) if k in runs]
    if by:
        return per_combination(runs, by, class_counts)
    ok = runs[runs["status"] == "ok"]
    rows = [(c, int((ok["class"] == c).sum())) for c in CLASSES]
    # ok runs the thresholds cannot place (e.g. a trap no longer long enough to count)
    other = int((~ok["class"].isin(CLASSES)).sum())
    if other:
        rows.append(("unclassified", other))
    rows.append(("failed", int((runs["status"] != "ok").sum())))
    df = pd.DataFrame(rows, columns=["class", "runs"])
    total = max(1, int(df["runs"].sum()))
    df["fraction"] = (df["runs"] / total).round(4)
    return df


def reclassify(out: Path, thresholds: ClassifySettings) -> Reclassified:
    """Re-classify every stored trajectory and rewrite the runs table atomically.

    Holds the output folder's lock (:mod:`fibersweep.sweep.lock`): a sweep
    running there is never rewritten under its feet. Every part is read before
    any is replaced; an unreadable one stops it with nothing changed.

    Runs without a stored trajectory keep their class (their count is logged);
    a run re-labelled Trapping gets δ = NaN (no displacement is defined).

    Raises
    ------
    InputError
        No results, or no trajectories were recorded.
    """
    out = Path(out)
    if not out.is_dir():
        raise InputError(f"{out}: no sweep results here (no such folder)")
    with output_lock(out, "classify"):
        return _reclassify(out, thresholds)


def _run_context(man: dict, out: Path) -> tuple[object, float]:
    """Geometry and effective U_center [µm/s] of the stored (first) setting."""
    flow = FlowSettings.model_validate(man["config"]["flow"])
    geometry = flow.geometry.to_geometry()
    # The speed the runs moved in (effects such as inlet_speed change it); manifests
    # written before it was recorded only hold the nominal one.
    u_center = man.get("u_center_effective")
    if u_center is None:
        u_center = flow.fluid.u_center
        if man["config"]["fiber"].get("effects"):
            log.warning(
                "%s: the manifest predates the effective U_center; classifying with the "
                "nominal %.4g µm/s although effects were on",
                out,
                u_center,
            )
    return geometry, u_center


def _reclassify(out: Path, thresholds: ClassifySettings) -> Reclassified:
    man = read_manifest(out)
    runs = read_runs(out)
    if man is None or runs.empty:
        raise InputError(f"{out}: no sweep results here (expected manifest.json and runs/)")
    # The thresholds the runs were simulated with (the trap rule also stops a run);
    # kept apart from the config's, which later re-classifications overwrite.
    simulated = man.setdefault("simulated_classify", man["config"]["fiber"]["classify"])
    if is_array_table(runs):  # pillar-array runs: their transport modes
        meta = classified_meta(list_parts(out / RUNS_DIR), man, thresholds)
        traj = read_trajectories(out, list(runs["id"]))
        if traj.empty:
            raise InputError(f"{out}: no trajectories stored for its array runs")
        runs, changed = relabel_modes(runs, traj, man, thresholds)
        counts, counts_path = replace_labels(out, runs, meta, man, thresholds, mode_counts)
        return Reclassified(len(runs), changed, counts, counts_path)
    geometry, u_center = _run_context(man, out)
    # A folder of several settings: each run's own geometry and speed, by its settings id.
    per_setting = {
        sid: (
            FlowSettings.model_validate(e["flow"]).geometry.to_geometry(),
            e["u_center_effective"],
        )
        for sid, e in (man.get("combinations") or {}).items()
        if "flow" in e and e.get("u_center_effective") is not None
    }
    sids = runs["settings"] if "settings" in runs else pd.Series([None] * len(runs))
    ok = runs["status"] == "ok"
    traj = read_trajectories(out, list(runs.loc[ok, "id"]))
    if traj.empty:
        raise InputError(
            f"{out}: no trajectories were recorded; set fiber.record.trajectories: true "
            "and run the sweep again"
        )
    groups = dict(tuple(traj.groupby("id", sort=False)))
    new_cls = runs["class"].copy()
    # One column per rule (class_head_speed, class_pivot, class_switch), so rules can be
    # compared run by run; 'class' is the chosen rule's. Empty where no trajectory.
    by_rule = {name: pd.Series([""] * len(runs), dtype=object) for name in RULES}
    missing = 0
    for i in np.flatnonzero(ok.to_numpy()):
        rid = runs.at[i, "id"]
        if rid not in groups:
            missing += 1
            continue
        geo, u = per_setting.get(sids.iat[i], (geometry, u_center))
        labels = classify_all(
            trajectory_from_frame(groups[rid].sort_values("sample")), geo, u, thresholds
        )
        for name, label in labels.items():
            by_rule[name].iat[i] = label
        new_cls.iat[i] = labels[thresholds.rule]
    if missing:
        log.warning("%d ok runs have no stored trajectory and keep their class", missing)
    changed = int((new_cls != runs["class"]).sum())
    # the rule behind each row's 'class': this one where it was re-labelled
    labelled = pd.Series(by_rule[thresholds.rule] != "", index=runs.index)
    rule_col = runs["class_rule"] if "class_rule" in runs else pd.Series([None] * len(runs))
    rule_col = rule_col.astype(object).where(~labelled.to_numpy(), thresholds.rule)
    runs = runs.assign(
        **{"class": new_cls, "class_rule": rule_col.to_numpy()},
        **{rule_column(name): col.to_numpy() for name, col in by_rule.items()},
    )
    runs.loc[runs["class"] == "Trapping", "delta"] = math.nan
    meta = classified_meta(list_parts(out / RUNS_DIR), man, thresholds)
    counts, counts_path = replace_labels(out, runs, meta, man, thresholds, class_counts)
    unclassified = int(((runs["status"] == "ok") & ~runs["class"].isin(CLASSES)).sum())
    warnings = _beyond_simulated(
        thresholds, ClassifySettings.model_validate(simulated), unclassified
    )
    return Reclassified(len(runs), changed, counts, counts_path, warnings)
