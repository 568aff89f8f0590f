"""``python -m fibersweep.cli``: run the command line."""

from fibersweep.cli import entry

entry()
