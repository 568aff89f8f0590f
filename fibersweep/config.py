"""The YAML schema of a fibersweep config, its loader, and sweep expansion.

A config has four sections, each optional: ``flow`` (:class:`FlowSettings`),
``fiber`` (:class:`FiberSettings`), ``sweep`` (:class:`SweepSettings`) and
``run`` (:class:`RunSettings`). Unknown keys are errors. :func:`load_config`
turns every validation problem into a :class:`ConfigError` that names the full
path of the field, what was expected, what was given, the YAML line, and a
did-you-mean for misspelled keys.
"""

from __future__ import annotations

import copy
import difflib
import itertools
import re
import types
import typing
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import yaml
from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    StrictFloat,
    Tag,
    ValidationError,
    field_validator,
    model_serializer,
    model_validator,
)

from fibersweep.errors import InputError
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.settings import FiberSettings
from fibersweep.flow.settings import FlowSettings

__all__ = [
    "Axis",
    "Combination",
    "Config",
    "ConfigError",
    "FieldError",
    "RunSettings",
    "SweepSettings",
    "apply_overrides",
    "load_config",
    "parse_config",
    "setting_annotation",
    "setting_axis_values",
    "setting_column",
]


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


class SweepSettings(_Strict):
    """Sweep over the start angle, lateral position and length, and any other setting.

    Each start axis is a number, a list, ``{start, stop, step}`` or ``{start, stop, num}``.
    Any other key is a dotted setting key (``fiber.effects.friction``,
    ``flow.geometry.pillar_height``) swept as an axis in the same forms, or a list
    of values of any type (``fiber.contact.pillar: [rough, smooth]``); the setting
    axes are combined as a product. ``zip`` holds a mapping of setting keys (or a
    list of such mappings) whose value lists are swept together, one combination
    per position. Every combination is validated as a whole config
    (:meth:`Config.combinations`).
    """

    model_config = ConfigDict(extra="allow", frozen=True)

    theta0: Axis = Field(0.0, description="start angle from +x [degrees]")
    y0: Axis = Field(0.5, description="start lateral position from the base / h_obs")
    length: Axis = Field(1.0, description="fiber length / l_obs")
    zip: Any = Field(
        None,
        description="setting keys swept together: a mapping key -> values (same lengths), "
        "or a list of such mappings",
    )

    @field_validator("theta0", "y0", "length")
    @classmethod
    def _finite(cls, axis: Axis, info: Any) -> Axis:
        # A field validator, so the error is reported at the axis's own line.
        v = axis_values(axis)
        if len(v) == 0:
            raise ValueError("no values")
        bad = v[~np.isfinite(v)]
        if bad.size:
            raise ValueError(f"values must be finite; got {_show(bad)}")
        if info.field_name == "length" and np.any(v <= 0):
            raise ValueError(f"lengths must be positive; got {_show(v[v <= 0])}")
        return axis

    @field_validator("zip", mode="before")
    @classmethod
    def _zip_shape(cls, value: Any) -> Any:
        if value is None or (isinstance(value, dict) and value):
            return value
        if isinstance(value, list) and value and all(isinstance(g, dict) and g for g in value):
            return value
        raise ValueError(
            "expected a mapping of setting keys to value lists (swept together), "
            "or a list of such mappings"
        )

    @model_serializer(mode="wrap")
    def _without_empty_zip(self, handler: Any) -> dict[str, Any]:
        data = handler(self)
        if isinstance(data, dict) and data.get("zip") is None:
            data.pop("zip", None)  # written only when used
        return data

    @model_validator(mode="after")
    def _setting_axes_valid(self) -> SweepSettings:
        """Keys name settings, values are axis forms, zipped lists are equally long."""
        seen: dict[str, tuple] = {}
        for loc, key, raw in self.axis_items():
            if "." not in key:
                close = difflib.get_close_matches(key, _START_AXES + ("zip",), n=1, cutoff=0.5)
                hint = f"; did you mean '{close[0]}'?" if close else "."
                if key in ("fiber", "flow"):
                    example = (
                        "flow.dx: [4, 2]" if key == "flow" else "fiber.contact.chi: [1.1, 1.2]"
                    )
                    hint = f"; write a swept setting as one dotted key, e.g. {example}."
                raise FieldError(
                    loc,
                    f"unknown key{hint} Valid keys here: {', '.join(_START_AXES)}, zip, "
                    "or a dotted setting key such as fiber.effects.friction",
                )
            try:
                setting_annotation(key)
                values = setting_axis_values(raw)
            except ValueError as exc:
                raise FieldError(loc, str(exc)) from None
            if key in seen:
                where = ".".join(str(p) for p in ("sweep", *seen[key]))
                raise FieldError(loc, f"{key} is swept twice (also at {where}); keep one")
            seen[key] = loc
            del values
        for gloc, group in self._zip_groups():
            sizes = {k: len(setting_axis_values(v)) for k, v in group.items()}
            if len(set(sizes.values())) > 1:
                shown = ", ".join(f"{k}: {n}" for k, n in sizes.items())
                raise FieldError(
                    gloc, f"zipped keys need value lists of the same length; got {shown}"
                )
        return self

    def _zip_groups(self) -> list[tuple[tuple, dict[str, Any]]]:
        """(location relative to ``sweep``, mapping) of each zip group."""
        if self.zip is None:
            return []
        if isinstance(self.zip, dict):
            return [(("zip",), self.zip)]
        return [(("zip", i), g) for i, g in enumerate(self.zip)]

    def axis_items(self) -> list[tuple[tuple, str, Any]]:
        """Every setting axis as (location relative to ``sweep``, dotted key, raw value).

        Product axes first (in the order written), then each zip group's keys.
        """
        out = [((k,), k, v) for k, v in (self.model_extra or {}).items()]
        for gloc, group in self._zip_groups():
            out.extend(((*gloc, k), k, v) for k, v in group.items())
        return out

    @property
    def setting_keys(self) -> list[str]:
        """The swept setting keys (dotted), product axes first, then zipped ones."""
        return [k for _, k, _ in self.axis_items()]

    def assignments(self) -> list[dict[str, Any]]:
        """Every combination of the setting axes as {dotted key: raw value}.

        The product of the product axes and the zip groups, the first written
        varying slowest. ``[{}]`` when no setting is swept.
        """
        factors: list[list[dict[str, Any]]] = [
            [{k: v} for v in setting_axis_values(raw)]
            for k, raw in (self.model_extra or {}).items()
        ]
        for _, group in self._zip_groups():
            cols = {k: setting_axis_values(v) for k, v in group.items()}
            n = len(next(iter(cols.values()))) if cols else 0
            factors.append([{k: vals[i] for k, vals in cols.items()} for i in range(n)])
        out = []
        for combo in itertools.product(*factors):
            merged: dict[str, Any] = {}
            for part in combo:
                merged.update(part)
            out.append(merged)
        return out

    @property
    def n_combinations(self) -> int:
        """Number of setting combinations, without making them."""
        n = 1
        for raw in (self.model_extra or {}).values():
            n *= setting_axis_count(raw)
        for _, group in self._zip_groups():
            n *= setting_axis_count(next(iter(group.values()))) if group else 1
        return n

    @property
    def size(self) -> int:
        """Number of start points (product of the three start axes), without making them."""
        return axis_count(self.theta0) * axis_count(self.y0) * axis_count(self.length)

    def grid(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The sweep points as arrays, in the order of :meth:`starts`.

        Returns
        -------
        theta0, y0, length : ndarray, shape (size,)
            θ0 [deg], y0/h_obs, L/l_obs; length varies slowest, theta0 fastest.
        """
        L, y, t = np.meshgrid(
            axis_values(self.length), axis_values(self.y0), axis_values(self.theta0),
            indexing="ij",
        )  # fmt: skip
        return t.ravel(), y.ravel(), L.ravel()

    def starts(self) -> list[FiberStart]:
        """Cartesian product of the axes, ordered length, y0, theta0."""
        return [
            FiberStart(theta0=float(t), y0=float(y), length=float(L))
            for t, y, L in zip(*self.grid(), strict=True)
        ]


_START_AXES = ("theta0", "y0", "length")


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


def _unwrap(ann: Any) -> Any:
    """``X | None`` -> X (the other members of a union are kept)."""
    args = [a for a in typing.get_args(ann) if a is not type(None)]
    if typing.get_origin(ann) in (typing.Union, types.UnionType) and len(args) == 1:
        return args[0]
    return ann


def setting_annotation(key: str) -> tuple[Any, Any]:
    """Type annotation and pydantic field of a dotted setting key that may be swept.

    Walks the config models; inside a mapping setting (``fiber.effects``) the
    next part is a mapping key and the value type is returned (field None).

    Raises
    ------
    ValueError
        Not a setting that changes results, or an unknown key (did-you-mean).
    """
    parts = key.split(".")
    if any(not p for p in parts):
        raise ValueError(f"{key!r}: empty part in the dotted key")
    if parts[0] in ("run", "sweep"):
        raise ValueError(
            f"{parts[0]}.* settings do not change a run's result; they cannot be a sweep axis"
        )
    if parts[:2] == ["fiber", "classify"]:
        raise ValueError(
            "classification thresholds are not part of a run's id: re-label stored runs "
            "with `fibersweep classify` instead of sweeping them"
        )
    model: Any = Config
    ann: Any = Config
    field: Any = None
    for i, part in enumerate(parts):
        if isinstance(model, type) and issubclass(model, BaseModel):
            if part not in model.model_fields:
                here = ".".join(parts[:i]) or "<top level>"
                close = difflib.get_close_matches(part, list(model.model_fields), n=1, cutoff=0.5)
                hint = f"; did you mean '{close[0]}'?" if close else ""
                valid = ", ".join(k for k in model.model_fields if i or k in ("fiber", "flow"))
                raise ValueError(
                    f"unknown setting '{part}' in {here}{hint} Valid keys there: {valid}"
                )
            field = model.model_fields[part]
            ann = _unwrap(field.annotation)
        elif typing.get_origin(model) is dict:
            ann, field = _unwrap(typing.get_args(model)[1]), None
        else:
            here = ".".join(parts[:i])
            raise ValueError(f"{here} is a value, not a section: no '{part}' inside it")
        model = ann
    return ann, field


def setting_column(key: str) -> tuple[str, str, str]:
    """How a swept setting is stored as a runs-table column.

    Returns
    -------
    kind : {'float', 'int', 'bool', 'string', 'json'}
        Column type (``json``: a section or list, stored as its JSON text).
    unit : str
        From the ``[unit]`` in the field's description ('' if none).
    doc : str
        The field's description.
    """
    try:
        ann, field = setting_annotation(key)
    except ValueError:
        return "json", "", f"swept setting {key}"
    kind = "json"
    if ann is bool:
        kind = "bool"
    elif ann is int:
        kind = "int"
    elif ann is float:
        kind = "float"
    elif ann is str or typing.get_origin(ann) is typing.Literal:
        kind = "string"
    desc = (field.description if field is not None else None) or ""
    if field is None and key.startswith("fiber.effects."):
        desc = f"strength of the effect {key.rsplit('.', 1)[1]} (0 = off)"
    m = re.search(r"\[([^\]]+)\]", desc)
    unit = m.group(1) if m else ""
    return kind, unit, f"swept setting {key}: {desc}" if desc else f"swept setting {key}"


def _show(values: np.ndarray, most: int = 3) -> str:
    """A few offending values for an error message."""
    shown = ", ".join(f"{x:g}" for x in values[:most])
    return shown + (f" (and {values.size - most} more)" if values.size > most else "")


class RunSettings(_Strict):
    """How a sweep is executed and where it writes."""

    workers: int = Field(2, ge=1, description="worker processes")
    output: str = Field("results/run", description="output directory")
    cache_dir: str = Field(".fibersweep-cache", description="flow-field cache directory")
    executor: str = Field("local", description="executor name (local pool or dask)")
    scheduler: str | None = Field(None, description="Dask scheduler address tcp://HOST:PORT")
    flush_every: int = Field(
        32, ge=1, description="finished runs per Parquet part file (also flushed on exit)"
    )
    flush_seconds: float = Field(
        5.0,
        gt=0,
        description="a finished run waits at most this long before it is written [s]",
    )
    retries: int = Field(
        2, ge=0, description="re-runs of a task whose worker died (local pool and Dask)"
    )
    compact: bool = Field(True, description="merge part files into one at the end of a sweep")
    max_points: int = Field(
        DEFAULT_MAX_POINTS,
        ge=1,
        description="refuse sweeps with more points than this (raise it on purpose)",
    )

    @field_validator("executor")
    @classmethod
    def _known_executor(cls, name: str) -> str:
        from fibersweep.sweep.executors import EXECUTORS  # the registry decides

        if name not in EXECUTORS:
            close = difflib.get_close_matches(name, list(EXECUTORS), n=1)
            hint = f"did you mean '{close[0]}'? " if close else ""
            raise ValueError(f"unknown executor; {hint}valid: {', '.join(EXECUTORS)}")
        return name

    @model_validator(mode="after")
    def _scheduler_address(self) -> RunSettings:
        if self.scheduler is not None and "://" not in self.scheduler:
            raise FieldError(
                "scheduler", f"expected an address like tcp://HOST:PORT, got {self.scheduler!r}"
            )
        return self


class Config(_Strict):
    """A whole fibersweep config."""

    flow: FlowSettings = FlowSettings()
    fiber: FiberSettings = FiberSettings()
    sweep: SweepSettings = SweepSettings()
    run: RunSettings = RunSettings()

    @model_validator(mode="after")
    def _size_within_limit(self) -> Config:
        """Refuse huge sweeps at once, before any point is made (counted, not listed).

        Every setting combination counts: the limit is on start points times
        combinations.
        """
        starts, combos = self.sweep.size, self.sweep.n_combinations
        n = starts * combos
        if n > self.run.max_points:
            how = f" ({starts:,} starts x {combos:,} setting combinations)" if combos > 1 else ""
            raise FieldError(
                "sweep",
                f"{n:,} points{how}, more than run.max_points ({self.run.max_points:,}); "
                "use fewer points, or raise run.max_points (or --max-points) if you mean it",
            )
        return self

    @model_validator(mode="after")
    def _combinations_valid(self) -> Config:
        """Every setting combination is a valid config (same schema, same start check)."""
        if self.sweep.setting_keys:
            self.combinations()
        return self

    def combinations(self) -> list[Combination]:
        """The configs the sweep runs: one per combination of the setting axes.

        Each is this config with the combination's values applied and no setting
        axes left, validated by the same schema (its start points checked with
        :meth:`_starts_to_check`). Without setting axes: ``[Combination({}, self)]``.

        Raises
        ------
        FieldError
            A combination is invalid: at the axis whose value is at fault (its
            value named), or at the field that failed with the combination named.
        """
        assignments = self.sweep.assignments()
        if assignments == [{}]:
            return [Combination({}, self)]
        locs = {k: ("sweep", *loc) for loc, k, _ in self.sweep.axis_items()}
        base = self.model_dump(mode="json")
        base["sweep"] = {k: base["sweep"][k] for k in _START_AXES}
        out = []
        for assignment in assignments:
            data = copy.deepcopy(base)
            for key, value in assignment.items():
                _set_path(data, key.split("."), value)
            try:
                cfg = Config.model_validate(data)
            except ValidationError as exc:
                raise _combination_error(exc, assignment, locs) from None
            dumped = cfg.model_dump(mode="json")
            values = {k: _get_path(dumped, k.split(".")) for k in assignment}
            off = _check_effects(values, locs)
            if off:
                # An effect swept to its baseline is off: left out, so those runs keep the
                # ids of runs made without it (a folder swept later reuses them).
                for key in off:
                    data["fiber"]["effects"].pop(key.split(".", 2)[2])
                cfg = Config.model_validate(data)
            out.append(Combination(values, cfg))
        return out

    @model_validator(mode="after")
    def _starts_fit(self) -> Config:
        """Every sweep point must be a fiber the grid resolves, in the channel, off the pillar.

        Checked here, before any flow field is computed, with the same check a run
        makes (:func:`fibersweep.fiber.setup.check_start`); effects that move the
        start (start noise, pillar scale) are applied per run and checked there.
        """
        if self.sweep.setting_keys:
            return self  # each setting combination is checked as a config of its own
        from fibersweep.fiber.contact import make_pillar  # numba-backed: import lazily
        from fibersweep.fiber.setup import check_start

        geo = self.flow.geometry.to_geometry()
        pillar = make_pillar(geo, self.fiber.contact, self.fiber.bead_radius, 1.0)
        bad: dict[str, str] = {}
        for start in self._starts_to_check(geo, pillar.r_cut):
            try:
                check_start(geo, self.flow.dx, self.fiber, start, pillar)
            except InputError as exc:
                name, _, msg = str(exc).partition(": ")
                # x0 is a fiber setting; the other names are sweep axes.
                path = "fiber.x0" if name == "x0" else f"sweep.{name}"
                bad.setdefault(path, msg)  # first problem per field is enough to act on
        if bad:
            path, msg = next(iter(bad.items()))
            raise FieldError(path, msg)
        return self

    def _starts_to_check(self, geo: Any, r_cut: float) -> list[FiberStart]:
        """The sweep points that could fail :func:`check_start`, in sweep order.

        A point is skipped only when it provably passes: its length was checked on
        another point (the length rules depend on L alone), and a disc around its
        centre that holds every bead, with the pillar's cutoff and a grid spacing
        to spare, lies inside the channel and clear of the pillar's bounding box.
        So the first failing point per field is the same as checking every point,
        and a 200 000-point sweep is checked in a fraction of a second.
        """
        t, y, L = self.sweep.grid()
        a = self.fiber.bead_radius
        x0 = geo.length / 4.0 if self.fiber.x0 is None else float(self.fiber.x0)
        yc = np.array([geo.y_from_base(v) for v in (0.0, 1.0)])
        y_abs = yc[0] + y * (yc[1] - yc[0])  # y_from_base is affine in y0
        reach = L * geo.pillar_base_length / 2.0 + 2.0 * a + self.flow.dx
        lo, hi = geo.vertices.min(axis=0), geo.vertices.max(axis=0)
        gap_x = np.maximum(np.maximum(lo[0] - x0, x0 - hi[0]), 0.0)
        gap_y = np.maximum(np.maximum(lo[1] - y_abs, y_abs - hi[1]), 0.0)
        clear = (
            (y_abs - reach > 0.0)
            & (y_abs + reach < geo.width)
            & (x0 - reach > 0.0)
            & (x0 + reach < geo.length)
            & (np.hypot(gap_x, gap_y) > reach + r_cut)
        )
        _, first_of_length = np.unique(L, return_index=True)
        clear[first_of_length] = False
        idx = np.flatnonzero(~clear)
        return [FiberStart(theta0=float(t[i]), y0=float(y[i]), length=float(L[i])) for i in idx]


@dataclass(frozen=True)
class Combination:
    """One combination of the setting axes and the config it makes.

    Attributes
    ----------
    values : dict
        Swept dotted key -> the value as validated (JSON types: ``0.3``, ``"rough"``).
    config : Config
        The whole config with these values, no setting axes left.
    """

    values: dict[str, Any]
    config: Config

    @property
    def label(self) -> str:
        """``key=value, ...`` for messages ('' without setting axes)."""
        return ", ".join(f"{k}={v}" for k, v in self.values.items())


def _set_path(data: dict, parts: list[str], value: Any) -> None:
    node = data
    for part in parts[:-1]:
        child = node.get(part)
        if not isinstance(child, dict):
            child = node[part] = {}
        node = child
    node[parts[-1]] = value


def _get_path(data: Any, parts: list[str]) -> Any:
    for part in parts:
        data = data.get(part) if isinstance(data, dict) else None
    return data


def _combination_error(
    exc: ValidationError, assignment: dict[str, Any], locs: dict[str, tuple]
) -> FieldError:
    """The first problem of an invalid combination, at the axis to blame when there is one."""
    loc, msg, given = _error_parts(exc.errors()[0])
    for key in assignment:
        path = tuple(key.split("."))
        n = min(len(path), len(loc))
        if n and path[:n] == loc[:n]:
            others = {k: v for k, v in assignment.items() if k != key}
            with_ = f" (with {_show_assignment(others)})" if others else ""
            return FieldError(locs[key], f"value {assignment[key]!r}{with_}: {msg}")
    dotted = ".".join(str(p) for p in loc) or "<top level>"
    given_s = "" if given is None or isinstance(given, dict) else f"; given {given!r}"
    first = next(iter(assignment))
    return FieldError(locs[first], f"with {_show_assignment(assignment)}: {dotted}: {msg}{given_s}")


def _check_effects(values: dict[str, Any], locs: dict[str, tuple]) -> list[str]:
    """Swept effects exist and take the value (the registry checks names and ranges).

    Returns
    -------
    list of str
        The swept effect keys whose value is the effect's baseline (inactive).
    """
    keys = [k for k in values if k.startswith("fiber.effects.")]
    if not keys:
        return []
    from fibersweep.fiber.effects import build_effects  # numba-backed: import lazily

    off = []
    for key in keys:
        try:
            made = build_effects({key.split(".", 2)[2]: values[key]})
        except InputError as exc:
            msg = str(exc).removeprefix("effects: ")
            raise FieldError(locs[key], f"value {values[key]!r}: {msg}") from None
        if not made.effects:
            off.append(key)
    return off


def _show_assignment(assignment: dict[str, Any]) -> str:
    return ", ".join(f"{k} = {v!r}" for k, v in assignment.items())


# --------------------------------------------------------------------------- loading


@dataclass(frozen=True)
class _Located:
    data: Any
    lines: dict[tuple, int]


class _Loader(yaml.SafeLoader):
    """Safe loader (no tags run) that reads ``3e-1`` and ``1e5`` as numbers, as YAML 1.2 does.

    YAML 1.1 (PyYAML's default) needs a dot in a float, so ``y0: 3e-1`` was a string
    while the same in a list was coerced: one rule for every number here.
    """


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"),
)


def _yaml_with_lines(text: str) -> _Located:
    """Parse YAML and record the 1-based line of every key path.

    Raises
    ------
    ConfigError
        A key written twice in one mapping (YAML would silently keep the last).
    """
    lines: dict[tuple, int] = {}
    duplicates: list[str] = []

    def walk(node: yaml.Node, path: tuple) -> None:
        lines.setdefault(path, node.start_mark.line + 1)
        if isinstance(node, yaml.MappingNode):
            first: dict[Any, int] = {}
            for k, v in node.value:
                key = (*path, k.value)
                line = k.start_mark.line + 1
                if k.value in first:
                    dotted = ".".join(str(p) for p in key)
                    duplicates.append(
                        f"{dotted}: key written twice (lines {first[k.value]} and {line}); keep one"
                    )
                    continue
                first[k.value] = line
                lines[key] = line
                walk(v, key)
        elif isinstance(node, yaml.SequenceNode):
            for i, v in enumerate(node.value):
                walk(v, (*path, i))

    root = yaml.compose(text, Loader=_Loader)
    if root is not None:
        walk(root, ())
    if duplicates:
        raise ConfigError(duplicates)
    return _Located(yaml.load(text, Loader=_Loader), lines)


def _model_at(path: tuple) -> type[BaseModel] | None:
    """The pydantic model that owns the mapping at ``path`` (for did-you-mean)."""
    model: type[BaseModel] | None = Config
    for part in path:
        if model is None or not isinstance(part, str) or part not in model.model_fields:
            return None
        ann = model.model_fields[part].annotation
        model = ann if isinstance(ann, type) and issubclass(ann, BaseModel) else None
    return model


def _error_parts(err: dict) -> tuple[tuple, str, Any]:
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


def _describe(err: dict, lines: dict[tuple, int]) -> str:
    loc, msg, given = _error_parts(err)
    dotted = ".".join(str(p) for p in loc) or "<top level>"
    line = None
    for k in range(len(loc), -1, -1):
        if loc[:k] in lines:
            line = lines[loc[:k]]
            break
    # a YAML line number, or the label of a command-line override
    where = f" (line {line})" if isinstance(line, int) else (f" ({line})" if line else "")
    if err["type"] == "extra_forbidden":
        parent = _model_at(loc[:-1])
        hint = ""
        if parent is not None:
            close = difflib.get_close_matches(
                str(loc[-1]), list(parent.model_fields), n=1, cutoff=0.5
            )
            if close:
                hint = f"; did you mean '{close[0]}'?"
            valid = ", ".join(parent.model_fields)
            hint += f" Valid keys here: {valid}"
        return f"{dotted}{where}: unknown key{hint}"
    raised = (err.get("ctx") or {}).get("error")
    given_s = (
        "" if isinstance(given, dict) or isinstance(raised, FieldError) else f"; given {given!r}"
    )
    return f"{dotted}{where}: {msg}{given_s}"


def parse_config(
    data: Any, lines: dict[tuple, int | str] | None = None, source: str = "config"
) -> Config:
    """Validate a config mapping.

    Raises
    ------
    ConfigError
        With one message per problem, naming each field.
    """
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError([f"<top level>: expected a mapping, got {type(data).__name__}"], source)
    try:
        return Config.model_validate(data)
    except ValidationError as exc:
        seen: list[str] = []
        for err in exc.errors():
            msg = _describe(err, lines or {})
            if msg not in seen:
                seen.append(msg)
        raise ConfigError(seen, source) from None


def apply_overrides(
    data: dict[str, Any], lines: dict[tuple, int | str], overrides: Sequence[str]
) -> dict[str, Any]:
    """Apply ``KEY=VALUE`` overrides (dotted keys, YAML values) to a config mapping.

    Parameters
    ----------
    data : dict
        The config as read from YAML (not modified).
    lines : dict
        Key path -> YAML line; each overridden path is relabelled with its
        override, so a problem with it is reported as ``(override KEY=VALUE)``.
    overrides : sequence of str
        E.g. ``fiber.contact.chi=1.2``, ``sweep.y0=[0.3, 0.4]``, ``flow.dx=2``.
        Values are YAML: numbers, booleans, strings, ``[lists]`` and ``{maps}``.

    Returns
    -------
    dict
        A new mapping with the overrides applied, in order (a later one wins).

    Raises
    ------
    ConfigError
        Malformed overrides, each named (the schema then checks keys and values).
    """
    out: dict[str, Any] = copy.deepcopy(data)
    problems = []
    for item in overrides:
        key, sep, raw = item.partition("=")
        path = tuple(p.strip() for p in key.split("."))
        if len(path) > 2 and path[0] == "sweep":
            # a swept setting is one dotted key inside sweep (or inside sweep.zip)
            cut = 3 if path[1] == "zip" and len(path) > 3 else 2
            path = (*path[: cut - 1], ".".join(path[cut - 1 :]))
        if not sep or not all(path):
            problems.append(
                f"override {item!r}: expected KEY=VALUE with a dotted key, "
                "e.g. fiber.contact.chi=1.2"
            )
            continue
        try:
            value = yaml.load(raw, Loader=_Loader) if raw.strip() else None
        except yaml.YAMLError as exc:
            problems.append(f"override {item!r}: the value is not valid YAML ({exc})")
            continue
        node = out
        for depth, part in enumerate(path[:-1]):
            child = node.setdefault(part, {})
            if child is None:
                child = node[part] = {}
            if not isinstance(child, dict):
                where = ".".join(path[: depth + 1])
                problems.append(f"override {item!r}: {where} is a value, not a section")
                break
            node = child
        else:
            node[path[-1]] = value
            label = f"override {item}"
            lines[path] = label
            for k in range(1, len(path)):
                lines.setdefault(path[:k], label)
    if problems:
        raise ConfigError(problems)
    return out


def load_config(
    path: str | Path, overrides: Sequence[str] = (), *, max_points: int | None = None
) -> Config:
    """Read and validate a YAML config file, with command-line overrides.

    ``overrides`` are ``KEY=VALUE`` strings (:func:`apply_overrides`), validated by
    the same schema with the same messages. ``max_points`` (the command line's
    ``--max-points``) replaces ``run.max_points`` before validation, so a large
    sweep can be allowed without editing the file.

    Raises
    ------
    ConfigError
        Unreadable file, invalid YAML, bad overrides or invalid settings (each named).
    """
    p = Path(path)
    try:
        text = p.read_text()
    except OSError as exc:
        raise ConfigError([f"cannot read config: {exc.strerror}"], str(p)) from None
    try:
        located = _yaml_with_lines(text)
    except yaml.YAMLError as exc:
        raise ConfigError([f"invalid YAML: {exc}"], str(p)) from None
    except ConfigError as exc:
        raise ConfigError(exc.problems, str(p)) from None
    data = located.data
    if overrides:
        if data is None:
            data = {}
        if isinstance(data, dict):
            try:
                data = apply_overrides(data, located.lines, overrides)
            except ConfigError as exc:
                raise ConfigError(exc.problems, str(p)) from None
    if max_points is not None and isinstance(data, dict):
        run = data.get("run") if isinstance(data.get("run"), dict) else {}
        data = {**data, "run": {**run, "max_points": max_points}}
    return parse_config(data, located.lines, str(p))
