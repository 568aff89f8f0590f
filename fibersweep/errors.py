"""Exception types the CLI maps to exit codes (input problems -> 2, failures -> 1)."""

from __future__ import annotations

__all__ = [
    "RUN_ERRORS",
    "FibersweepError",
    "FieldError",
    "InputError",
    "ResultsError",
    "RunBug",
    "SolverError",
    "Terminated",
]


class FibersweepError(Exception):
    """Base class of every error fibersweep raises on purpose."""


class InputError(FibersweepError, ValueError):
    """Bad input a user can fix (config, arguments, data files). CLI exit code 2."""


class FieldError(ValueError):
    """A check across several fields that fails at one of them.

    Raised by model validators with the field's dotted ``path`` relative to the
    model that raised it; the config loader reports the problem at that field's
    line instead of at the model's.
    """

    def __init__(self, path: str | tuple, message: str) -> None:
        super().__init__(message)
        # a tuple keeps parts that hold dots themselves (a swept setting key)
        self.path = tuple(path) if isinstance(path, tuple) else tuple(path.split("."))


class SolverError(FibersweepError, RuntimeError):
    """A computation that failed (divergence, NaN). CLI exit code 1."""


class ResultsError(FibersweepError, OSError):
    """Stored results that cannot be read or written (a broken part, a full disk). Exit 1.

    The message names the file and the cause; nothing that was not read is deleted.
    """


class Terminated(KeyboardInterrupt):
    """SIGTERM arrived: stop like Ctrl-C (finished runs saved, manifest 'interrupted').

    A KeyboardInterrupt, so every clean-up path that handles Ctrl-C handles it too;
    the CLI exits with 143 (128 + SIGTERM) instead of 130.
    """


class RunBug(RuntimeError):
    """A fiber run raised an error no run should raise: a bug, not a failed run.

    Raised in a worker (with the run's id and the original traceback in the
    message); the executors stop the sweep on it instead of recording a failed
    row, so a programming error is never mistaken for physics.
    """


#: Errors a fiber run can legitimately raise, recorded as a failed run: bad input
#: (e.g. start noise pushing a start onto the pillar), a computation that failed,
#: and arithmetic failures. Anything else is a :class:`RunBug`.
RUN_ERRORS: tuple[type[BaseException], ...] = (FibersweepError, ArithmeticError)
