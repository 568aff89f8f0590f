"""fibersweep: fibers, rigid or flexible, carried by a Stokes flow past pillars.

One pillar in a shallow channel, or a tilted pillar array that sorts fibers by
length: the flow is solved once (lattice Boltzmann, cached), then one fiber run
per point of a sweep, stored as Parquet; ``fibersweep.load`` reads a results
folder back with the unit and meaning of every column.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("fibersweep")
except PackageNotFoundError:  # running from a source tree without install
    __version__ = "0.0.0+unknown"

__all__ = ["__version__", "load"]


def load(results, trajectories: bool = True):
    """A sweep's output folder in one call: runs, trajectories, settings and units.

    ``res = fibersweep.load("results/quick")`` gives ``res.runs`` and
    ``res.trajectories`` (pandas), ``res.settings`` (the resolved config),
    ``res.units`` and ``res.docs`` (per column) and ``res.provenance``; see
    :func:`fibersweep.results.load_results`.
    """
    from fibersweep.results import load_results

    return load_results(results, trajectories)
