"""Exception types the CLI maps to exit codes (input problems -> 2, failures -> 1)."""

from __future__ import annotations

__all__ = [
    "RUN_ERRORS",
    "FibersweepError",
    "FieldError",
    "FieldErrors",
    "InputError",
    "ResultsError",
    "RunBug",
    "SolverError",
    "Terminated",
    "UnreadableResults",
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


class FieldErrors(ValueError):
    """Several independent checks of one model that failed, each a :class:`FieldError`.

    Raised by a model validator that runs all its checks (instead of stopping at the
    first); the config loader reports each at its own field and line.
    """

    def __init__(self, errors: list[FieldError]) -> None:
        super().__init__("; ".join(str(e) for e in errors))
        self.errors = list(errors)


class SolverError(FibersweepError, RuntimeError):
    """A computation that failed (divergence, NaN). CLI exit code 1."""


class ResultsError(FibersweepError, OSError):
    """Stored results that cannot be written (a full disk) or read. Exit 1, but see
    :class:`UnreadableResults` (exit 2).

    The message names the file and the cause; nothing that was not read is deleted.
    """


class UnreadableResults(ResultsError, InputError):
    """A stored part (or other results file) a command was given and cannot read. Exit 2.

    Bad input to the command that reads it (an :class:`InputError`), named once in
    the message with the cause and the repair; still a :class:`ResultsError` (and
    an OSError) for the code that handles broken results.
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
