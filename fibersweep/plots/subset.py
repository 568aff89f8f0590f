"""Choosing runs by an expression: ``--where 'y0 > 0.3 and class == "Trapping"'``.

The expression is a :meth:`pandas.DataFrame.query` over the runs table. Column
names that are not Python identifiers, or are keywords, need backticks in
pandas (`` `class` ``, `` `fiber.effects.friction` ``); here they may be
written bare, as the table prints them, and are quoted before pandas sees them.
"""

from __future__ import annotations

import keyword
import re

import pandas as pd

from fibersweep.errors import InputError

__all__ = ["quote_columns", "select_runs"]

_STRING_OR_TICKS = re.compile(r"""("(?:[^"\\]|\\.)*"|'(?:[^'\\]|\\.)*'|`[^`]*`)""")


def quote_columns(expr: str, columns: list[str]) -> str:
    """``expr`` with every bare column name that pandas cannot read put in backticks.

    Strings and names already in backticks are left alone; a name matches whole
    (``class`` but not ``classes``, ``a.b`` but not ``a.bc``).
    """
    names = sorted(
        (c for c in columns if not c.isidentifier() or keyword.iskeyword(c)), key=len, reverse=True
    )
    if not names:
        return expr
    pattern = re.compile(
        r"(?<![\w.`])(" + "|".join(re.escape(n) for n in names) + r")(?![\w`])(?!\.\w)"
    )
    parts = _STRING_OR_TICKS.split(expr)
    # odd pieces are the strings and backticked names the split kept
    return "".join(p if k % 2 else pattern.sub(r"`\1`", p) for k, p in enumerate(parts))


def select_runs(runs: pd.DataFrame, where: str | None) -> pd.DataFrame:
    """The runs for which ``where`` holds (all runs when it is None or blank).

    Parameters
    ----------
    runs : DataFrame
        The runs table.
    where : str or None
        A pandas query expression over its columns, e.g.
        ``y0 > 0.3 and class == "Trapping"`` or ``length in [0.8, 1.0]``.

    Raises
    ------
    InputError
        The expression does not parse, names an unknown column, does not give
        one true/false per run, or selects no run.
    """
    if where is None or not where.strip():
        return runs
    expr = quote_columns(where, [str(c) for c in runs.columns])
    try:
        mask = runs.eval(expr, engine="python")
    except pd.errors.UndefinedVariableError as exc:
        raise InputError(
            f"--where {where!r}: {exc}; columns: {', '.join(map(str, runs.columns))}"
        ) from None
    except Exception as exc:  # SyntaxError, TypeError of a bad comparison, ...
        raise InputError(f"--where {where!r}: {type(exc).__name__}: {exc}") from None
    if not isinstance(mask, pd.Series) or not pd.api.types.is_bool_dtype(mask):
        raise InputError(f"--where {where!r}: not a condition (true or false for each run)")
    out = runs[mask.to_numpy()]
    if out.empty:
        raise InputError(f"--where {where!r}: no run matches (of {len(runs)})")
    return out
