"""Tables of stored runs: a trajectory rebuilt from its stored samples, counts per combination.

Pure functions over pandas tables, shared by the re-labelling of classes (the
channel) and of transport modes (the pillar array).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from fibersweep.analysis.trajectory import Trajectory

__all__ = ["per_combination", "trajectory_from_frame"]


def trajectory_from_frame(df: pd.DataFrame) -> Trajectory:
    """Rebuild a :class:`Trajectory` from its stored samples (one id, sorted by sample)."""

    def col(name: str) -> np.ndarray:
        return df[name].to_numpy(dtype=np.float64)

    beads = None
    if "beads" in df and df["beads"].notna().all():
        flat = np.stack([np.asarray(b, dtype=np.float64) for b in df["beads"]])
        beads = flat.reshape(len(df), -1, 2)
    return Trajectory(
        t=col("t"),
        x=col("x"),
        y=col("y"),
        theta=col("theta"),
        head=np.column_stack([col("head_x"), col("head_y")]),
        tail=np.column_stack([col("tail_x"), col("tail_y")]),
        head_speed=col("head_speed"),
        com_speed=col("com_speed"),
        contact=df["contact"].to_numpy(dtype=bool),
        beads=beads,
    )


def per_combination(runs: pd.DataFrame, by: list[str], counts) -> pd.DataFrame:
    """``counts(group)`` for each combination of the ``by`` columns' values, stacked,
    the key columns first (one block per combination, fractions within it)."""
    blocks = []
    for values, group in runs.groupby(by, sort=True, dropna=False):
        values = values if isinstance(values, tuple) else (values,)
        block = counts(group)
        for k, v in reversed(list(zip(by, values, strict=True))):
            block.insert(0, k, v)
        blocks.append(block)
    return pd.concat(blocks, ignore_index=True)
