"""Sweep axes: their YAML forms (number, list, range, linspace), counts and values.

Pure functions of an axis; nothing here knows the rest of the config.
"""

from __future__ import annotations

from typing import Annotated, Any

import numpy as np
from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    StrictFloat,
    Tag,
    ValidationError,
    model_validator,
)


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


#: Most values one sweep axis may have (a range with a tiny step is refused before


#: any array is made).


MAX_AXIS_VALUES = 1_000_000


#: Default limit on the number of sweep points (``run.max_points`` raises it).


DEFAULT_MAX_POINTS = 200_000


class RangeSpec(_Strict):
    """Inclusive range ``start, start+step, ... <= stop``."""

    start: StrictFloat
    stop: StrictFloat
    step: StrictFloat = Field(gt=0)

    @model_validator(mode="after")
    def _not_empty(self) -> RangeSpec:
        if not all(np.isfinite([self.start, self.stop, self.step])):
            raise ValueError(
                f"range bounds must be finite; got start {self.start}, stop {self.stop}, "
                f"step {self.step}"
            )
        if self.stop < self.start:
            raise ValueError(f"empty range: start {self.start} > stop {self.stop}")
        if self.count() > MAX_AXIS_VALUES:
            raise ValueError(
                f"range has {self.count():,} values (more than {MAX_AXIS_VALUES:,}); "
                "use a larger step"
            )
        return self

    def count(self) -> int:
        """Number of values, computed without making them."""
        return int(np.floor((self.stop - self.start) / self.step + 1e-9)) + 1

    def values(self) -> np.ndarray:
        n = self.count()
        if n < 1:
            raise ValueError(f"empty range: start {self.start} > stop {self.stop}")
        return self.start + self.step * np.arange(n)


class LinspaceSpec(_Strict):
    """``num`` evenly spaced values from ``start`` to ``stop`` inclusive."""

    start: StrictFloat
    stop: StrictFloat
    num: int = Field(ge=1, le=100_000, strict=True)

    def count(self) -> int:
        """Number of values."""
        return self.num

    def values(self) -> np.ndarray:
        return np.linspace(self.start, self.stop, self.num)


def _axis_kind(v: Any) -> str | None:
    """Which form an axis is written in, so a bad one gets one clear message."""
    if isinstance(v, RangeSpec) or (isinstance(v, dict) and "step" in v):
        return "axis:range"
    if isinstance(v, LinspaceSpec) or (isinstance(v, dict) and "num" in v):
        return "axis:linspace"
    if isinstance(v, (list, tuple)):
        return "axis:list"
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        return "axis:number"
    return None


Axis = Annotated[
    Annotated[StrictFloat, Tag("axis:number")]
    | Annotated[list[StrictFloat], Tag("axis:list")]
    | Annotated[RangeSpec, Tag("axis:range")]
    | Annotated[LinspaceSpec, Tag("axis:linspace")],
    Discriminator(
        _axis_kind,
        custom_error_type="axis_form",
        custom_error_message=(
            "expected a number, a list of numbers, {start, stop, step} or {start, stop, num}"
        ),
    ),
]


def axis_count(axis: Axis) -> int:
    """Number of values of one sweep axis, without making them."""
    if isinstance(axis, (RangeSpec, LinspaceSpec)):
        return axis.count()
    return len(axis) if isinstance(axis, (list, tuple)) else 1


def axis_values(axis: Axis) -> np.ndarray:
    """Values of one sweep axis, shape (k,), rounded to 12 digits for stable ids."""
    if isinstance(axis, (RangeSpec, LinspaceSpec)):
        vals = axis.values()
    else:
        vals = np.atleast_1d(np.asarray(axis, dtype=np.float64))
    return np.round(vals, 12)


def _range_form(raw: dict) -> RangeSpec | LinspaceSpec | None:
    keys = set(raw)
    if keys == {"start", "stop", "step"}:
        return RangeSpec.model_validate(raw)
    if keys == {"start", "stop", "num"}:
        return LinspaceSpec.model_validate(raw)
    return None


def setting_axis_count(raw: Any) -> int:
    """Number of values of a setting axis, without making them (form assumed valid)."""
    if isinstance(raw, dict):
        spec = _range_form(raw)
        return spec.count() if spec is not None else 1
    return len(raw) if isinstance(raw, list) else 1


def setting_axis_values(raw: Any) -> list[Any]:
    """The values of a setting axis, in order.

    Parameters
    ----------
    raw : Any
        A single value (number, string, boolean), a list of values of any type
        (each element one value), ``{start, stop, step}`` or ``{start, stop, num}``
        (numbers rounded to 12 digits, as for the start axes).

    Raises
    ------
    ValueError
        Another mapping, an empty list, or a bad range.
    """
    if isinstance(raw, dict):
        try:
            spec = _range_form(raw)
        except ValidationError as exc:
            first = exc.errors()[0]
            where = ".".join(str(p) for p in first["loc"])
            msg = first["msg"].removeprefix("Value error, ")
            raise ValueError(f"bad range{' ' + where if where else ''}: {msg}") from None
        if spec is None:
            raise ValueError(
                "expected a value, a list of values, {start, stop, step} or {start, stop, num}; "
                f"got a mapping with keys {', '.join(map(str, raw))}"
            )
        return [float(v) for v in np.round(spec.values(), 12)]
    if isinstance(raw, list):
        if not raw:
            raise ValueError("no values")
        return list(raw)
    return [raw]


def _show(values: np.ndarray, most: int = 3) -> str:
    """A few offending values for an error message."""
    shown = ", ".join(f"{x:g}" for x in values[:most])
    return shown + (f" (and {values.size - most} more)" if values.size > most else "")
