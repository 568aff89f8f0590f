"""Config errors: what the loader raises, and where a cross-field check points."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from fibersweep.errors import (  # FieldError re-exported for config
    FieldError,
    FieldErrors,
    InputError,
)

__all__ = ["ConfigError", "FieldError", "FieldErrors", "all_checks", "error_parts", "expand"]


class ConfigError(InputError):
    """A config problem a user can act on.

    Attributes
    ----------
    problems : list of str
        One message per problem, each naming the field.
    """

    def __init__(self, problems: list[str], source: str = "config") -> None:
        self.problems = problems
        self.source = source
        head = f"{source}: {len(problems)} problem{'s' if len(problems) > 1 else ''}"
        super().__init__(head + "\n" + "\n".join(f"  - {p}" for p in problems))


def all_checks(*checks: Callable[[], Any]) -> None:
    """Run independent checks of one model, all of them, and raise what failed.

    A model validator that raises stops pydantic's chain, so the later checks of
    the model would go unreported; one validator that calls this reports them
    all. One failure is raised as it is (the message of a single problem is
    unchanged); several as :class:`FieldErrors`, which the loader reports each
    at its field and line.

    Raises
    ------
    FieldError, ValueError or FieldErrors
    """
    failed: list[ValueError] = []
    for check in checks:
        try:
            check()
        except FieldErrors as exc:
            failed.extend(exc.errors)
        except ValueError as exc:
            failed.append(exc)
    if len(failed) == 1:
        raise failed[0]
    if failed:
        raise FieldErrors(
            [e if isinstance(e, FieldError) else FieldError((), str(e)) for e in failed]
        )


def expand(err: dict) -> list[dict]:
    """One pydantic error per problem: a :class:`FieldErrors` is split into its errors."""
    raised = (err.get("ctx") or {}).get("error")
    if not isinstance(raised, FieldErrors):
        return [err]
    return [{**err, "msg": str(e), "ctx": {**err["ctx"], "error": e}} for e in raised.errors]


def error_parts(err: dict) -> tuple[tuple, str, Any]:
    """(location, message, given input) of one pydantic error, union-branch names dropped.

    Of a :class:`FieldErrors` (several checks of one model), the first (see :func:`expand`).
    """
    err = expand(err)[0]
    loc = tuple(p for p in err["loc"] if not (isinstance(p, str) and p[:1].isupper()))
    # pydantic inserts union-branch names like 'list[float]'; drop them.
    loc = tuple(
        p for p in loc if not (isinstance(p, str) and ("[" in p or ":" in p or p in {"float"}))
    )
    msg = err["msg"].removeprefix("Value error, ")
    raised = (err.get("ctx") or {}).get("error")
    if isinstance(raised, FieldError):
        # A cross-field check names the field it is about: report it there.
        loc = loc + raised.path
        msg = str(raised)
    return loc, msg, err.get("input")
