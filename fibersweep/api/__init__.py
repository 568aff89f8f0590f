"""The public Python API: what each command of the CLI does, as a function.

Every function takes the config as a path or a :class:`~fibersweep.config.Config`,
with ``KEY=VALUE`` overrides (dotted keys, YAML values) as further positional
arguments, exactly as the command line does; it returns what the command prints or
writes, as objects (frozen dataclasses, pandas tables). The command line
(:mod:`fibersweep.cli`) parses its options, calls one of these functions and
prints the result.

>>> import fibersweep
>>> res = fibersweep.run("configs/quick.yaml", "sweep.y0=[0.3, 0.4]")  # doctest: +SKIP
>>> res.load().runs[["theta0", "y0", "class", "delta"]]                 # doctest: +SKIP

Nothing here prints: what a function has to say goes to :mod:`logging` (logger
``fibersweep.api``), and progress bars are off unless ``progress=True`` is given
(they then take the form that suits the output: a terminal, a log file or a
notebook, :mod:`fibersweep.progressbar`). Bad input raises
:class:`~fibersweep.errors.InputError` (a config error,
:class:`~fibersweep.config.ConfigError`, names the field), a failed computation
:class:`~fibersweep.errors.FibersweepError`.

Units are those of the config and the results tables: lengths in µm, angles in
degrees, times in s; past one pillar ``y0`` is in h_obs and ``length`` in l_obs,
in a pillar array ``y0`` is a fraction of ``period_y`` and ``length`` is in µm
(``docs/reference/columns.md``).
"""

from __future__ import annotations

from fibersweep.api.common import load, load_config
from fibersweep.api.compare import DiscrepancyPlan, DiscrepancyReport, discrepancy
from fibersweep.api.fiber import FiberRun, simulate
from fibersweep.api.flow import FieldReport, FlowFields, flow_field
from fibersweep.api.progress import SweepBar, SweepProgress
from fibersweep.api.sorting import Classified, SortReport, classify, sort_report
from fibersweep.api.sweep import SweepEstimate, SweepRun, estimate, run

__all__ = [
    "load_config",
    "run",
    "estimate",
    "simulate",
    "flow_field",
    "sort_report",
    "classify",
    "discrepancy",
    "load",
    "Classified",
    "DiscrepancyPlan",
    "DiscrepancyReport",
    "FieldReport",
    "FiberRun",
    "FlowFields",
    "SortReport",
    "SweepBar",
    "SweepEstimate",
    "SweepProgress",
    "SweepRun",
]
