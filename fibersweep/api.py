"""The public Python API: what each command of the CLI does, as a function.

Filled in by the API change; ``load`` reads a results folder.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["load"]


def load(results: str | Path, trajectories: bool = True):
    """A sweep's output folder in one call: runs, trajectories, settings and units.

    ``res = fibersweep.load("results/quick")`` gives ``res.runs`` and
    ``res.trajectories`` (pandas), ``res.settings`` (the resolved config),
    ``res.units`` and ``res.docs`` (per column) and ``res.provenance``; see
    :func:`fibersweep.results.load_results`.
    """
    from fibersweep.results import load_results

    return load_results(results, trajectories)
