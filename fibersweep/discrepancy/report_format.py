"""Numbers of the report's Markdown, rounded to what they can tell.

3 significant digits for values, 2 for p-values and gaps (the callers' ``spec``);
'–' for a number that is missing (None).
"""

from __future__ import annotations

from typing import Any

__all__ = ["ci_text", "num"]


def num(x: Any, spec: str = ".3g") -> str:
    """``x`` formatted with ``spec``; '–' for None."""
    return "–" if x is None else format(x, spec)


def ci_text(d: dict[str, Any] | None, spec: str = ".2g") -> str:
    """'mean [lo95, hi95]' of a summary's interval dict; '–' for none."""
    if not d:
        return "–"
    return f"{num(d.get('mean'), spec)} [{num(d.get('lo95'), spec)}, {num(d.get('hi95'), spec)}]"
