"""Config errors: what the loader raises, and where a cross-field check points."""

from __future__ import annotations

from typing import Any

from fibersweep.errors import FieldError, InputError  # FieldError re-exported for config


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


def error_parts(err: dict) -> tuple[tuple, str, Any]:
    """(location, message, given input) of one pydantic error, union-branch names dropped."""
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
