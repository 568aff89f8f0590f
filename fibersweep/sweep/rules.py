"""Which pole-vaulting rule labelled the ``class`` of each run, and whether a folder mixes them.

Every run row records the rule behind its ``class`` (column ``class_rule``): the
sweep's ``fiber.classify.rule`` when it ran, or the rule of the last
``fibersweep classify`` that re-labelled it. A folder can end up mixing rules:
``classify --rule pivot`` re-labels every run, then a ``run`` with the config's
head-speed rule adds rows. Counts, phase diagrams and fractions of such a table
compare runs labelled differently, so every reader of the class warns
(:func:`mixed_rules_message`) and names the one command that makes it uniform.
Rows written before the column existed have no rule and are not counted.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

__all__ = ["class_rules", "mixed_rules_message"]


def class_rules(runs: pd.DataFrame) -> dict[str, int]:
    """Labelled (ok, non-empty class) runs per rule that labelled them.

    Parameters
    ----------
    runs : DataFrame
        A runs table (``read_runs``).

    Returns
    -------
    dict
        rule -> number of runs, most frequent first; empty when no row records one.
    """
    if "class_rule" not in runs or runs.empty:
        return {}
    labelled = (runs["status"] == "ok") & runs["class"].fillna("").ne("")
    rules = runs.loc[labelled, "class_rule"].dropna()
    rules = rules[rules.astype(str) != ""]
    return {str(k): int(v) for k, v in rules.value_counts().items()}


def mixed_rules_message(runs: pd.DataFrame, out: Path | str) -> str | None:
    """A warning when the ``class`` column of ``out`` mixes rules, else None."""
    rules = class_rules(runs)
    if len(rules) < 2:
        return None
    parts = ", ".join(f"{n} by {rule}" for rule, n in rules.items())
    first = next(iter(rules))
    return (
        f"{out}: the class column mixes pole-vaulting rules ({parts} runs); counts and "
        f"figures compare runs labelled differently. Re-label them all with one rule: "
        f"fibersweep classify {out} --rule {first}"
    )
