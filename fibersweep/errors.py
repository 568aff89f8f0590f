"""Exception types the CLI maps to exit codes (input problems -> 2, failures -> 1)."""

from __future__ import annotations

__all__ = ["FibersweepError", "InputError", "SolverError"]


class FibersweepError(Exception):
    """Base class of every error fibersweep raises on purpose."""


class InputError(FibersweepError, ValueError):
    """Bad input a user can fix (config, arguments, data files). CLI exit code 2."""


class SolverError(FibersweepError, RuntimeError):
    """A computation that failed (divergence, NaN). CLI exit code 1."""
