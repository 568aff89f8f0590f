"""fibersweep: fibers, rigid or flexible, carried by a Stokes flow past pillars.

One pillar in a shallow channel, or a tilted pillar array that sorts fibers by
length: the flow is solved once (lattice Boltzmann, cached), then one fiber run
per point of a sweep, stored as Parquet.

The public Python API (:mod:`fibersweep.api`) is reachable from here, and each
command of the CLI is one call into it::

    import fibersweep
    done = fibersweep.run("configs/quick.yaml", "run.output=results/q")
    res = fibersweep.load("results/q")          # or done.load()
    one = fibersweep.simulate("configs/quick.yaml", theta0=-8, y0=0.39, length=1)

The API is imported when first used, so ``import fibersweep`` stays light (the
worker processes of a sweep import the package too).
"""

from typing import Any

from fibersweep.version import __version__

#: The functions of :mod:`fibersweep.api` offered at the top level. The discrepancy
#: workflow is ``fibersweep.api.discrepancy``: at the top level that name is the
#: subpackage :mod:`fibersweep.discrepancy` once anything has imported it.
API = (
    "load_config", "run", "estimate", "simulate", "flow_field", "sort_report", "classify",
    "load",
)  # fmt: skip

__all__ = ["__version__", *API]


def __getattr__(name: str) -> Any:
    if name in API:
        from fibersweep import api

        return getattr(api, name)
    raise AttributeError(f"module 'fibersweep' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
