"""The ``fibersweep`` command line (typer). The only package that prints or exits.

Library errors map to exit codes here: bad input (:class:`InputError`, including
config errors) exits 2, a failed computation (:class:`FibersweepError`) exits 1.

A command that has a function in :mod:`fibersweep.api` (run, simulate, flow,
classify, sort-report, discrepancy, config) is one call into it: the command parses
its options, calls the function, prints what it returns and sets the exit code.

Layout: :mod:`._app` holds the ``app`` and the shared helpers; one module per
concept adds its commands to it: :mod:`.flow` (flow), :mod:`.fiber` (simulate),
:mod:`.sweep` (run, classify, plot-phase), :mod:`.view` (plot-fractions,
plot-delta, plot-tracks, animate, explore), :mod:`.discrepancy` (synth,
discrepancy, power).
"""

from fibersweep.cli._app import (
    ConfigArg,
    Verbose,
    _errors,
    _load,
    _setup_logging,
    app,
    entry,
    main,
)

# Imported to register their commands on ``app``. The import order is the order of
# the commands in ``fibersweep --help``, so keep it (and keep isort off it).
# isort: off
from fibersweep.cli import flow
from fibersweep.cli import fiber
from fibersweep.cli import sweep
from fibersweep.cli import view
from fibersweep.cli import discrepancy
from fibersweep.cli import array
from fibersweep.cli import show
from fibersweep.cli import init

# isort: on

__all__ = [
    "ConfigArg",
    "array",
    "Verbose",
    "_errors",
    "_load",
    "_setup_logging",
    "app",
    "discrepancy",
    "entry",
    "fiber",
    "flow",
    "init",
    "show",
    "main",
    "sweep",
    "view",
]
