"""``python -m fibersweep``: the same as the ``fibersweep`` console script."""

from fibersweep.cli import entry

entry()
