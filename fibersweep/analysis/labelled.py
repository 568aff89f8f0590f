"""A labelled set of trajectories, and a rule's agreement with its labels.

A labelled set is a CSV (``id, set, theta0, y0, length, label, reason``: one start,
the class a person gave it from its chronophotograph and why) and the runs'
trajectories, stored as concatenated columns with offsets in a compressed npz.
The set the pole-vaulting rules are judged on lives in ``tests/data/vault_labels``
(docs/fidelity.md, "The pole-vault a person sees"); ``scripts/vault_labels.py``
builds it and prints every rule's confusion table.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from fibersweep.analysis.classify import ClassifySettings, classify
from fibersweep.analysis.trajectory import CLASSES, Trajectory
from fibersweep.units import Geometry

__all__ = ["FIELDS", "save_trajectories", "load_trajectories", "rule_labels", "confusion"]

#: Trajectory columns kept per sample.
FIELDS = ("t", "x", "y", "theta", "head", "tail", "head_speed", "com_speed", "contact")


def save_trajectories(path: Path, ids: list[int], trajs: list[Trajectory]) -> None:
    """Store trajectories as concatenated columns with offsets (compressed npz)."""
    lens = np.array([len(tr.t) for tr in trajs])
    out: dict[str, np.ndarray] = {
        "id": np.asarray(ids, dtype=np.int64),
        "offsets": np.r_[0, np.cumsum(lens)].astype(np.int64),
    }
    for f in FIELDS:
        out[f] = np.concatenate([np.asarray(getattr(tr, f)) for tr in trajs])
    np.savez_compressed(path, **out)


def load_trajectories(path: Path) -> dict[int, Trajectory]:
    """Stored trajectories by label id."""
    with np.load(path) as z:
        off = z["offsets"]
        cols = {f: z[f] for f in FIELDS}
        return {
            int(i): Trajectory(**{f: cols[f][off[k] : off[k + 1]] for f in FIELDS})
            for k, i in enumerate(z["id"])
        }


def rule_labels(
    starts: pd.DataFrame,
    trajs: dict[int, Trajectory],
    geometry: Geometry,
    u_center: float,
    thresholds: ClassifySettings,
    rules,
) -> pd.DataFrame:
    """Class of every stored trajectory of ``starts`` under each rule (a column per rule).

    ``u_center`` is the channel's centreline speed [µm/s].
    """
    out = {
        name: [classify(trajs[int(i)], geometry, u_center, thresholds, name) for i in starts["id"]]
        for name in rules
    }
    return pd.DataFrame(out, index=starts.index)


def confusion(labels: pd.Series, predicted: pd.Series) -> pd.DataFrame:
    """Counts, rows = the label by eye, columns = the rule's class (the four, + undetermined)."""
    cols = [*CLASSES, ""] if (predicted == "").any() else list(CLASSES)
    table = pd.crosstab(labels, predicted).reindex(index=list(CLASSES), columns=cols).fillna(0)
    return table.astype(int).rename(columns={"": "undet."})
