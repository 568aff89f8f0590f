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
import re
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
    model_validator,
)

from fibersweep.errors import InputError
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.settings import FiberSettings
from fibersweep.flow.settings import FlowSettings

__all__ = [
    "Axis",
    "Config",
    "ConfigError",
    "FieldError",
    "RunSettings",
    "SweepSettings",
    "apply_overrides",
    "load_config",
    "parse_config",
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

    def __init__(self, path: str, message: str) -> None:
        super().__init__(message)
        self.path = tuple(path.split("."))


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
    """Sweep over the start angle, lateral position and length.

    Each axis is a number, a list, ``{start, stop, step}`` or ``{start, stop, num}``.
    """

    theta0: Axis = Field(0.0, description="start angle from +x [degrees]")
    y0: Axis = Field(0.5, description="start lateral position from the base / h_obs")
    length: Axis = Field(1.0, description="fiber length / l_obs")

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

    @property
    def size(self) -> int:
        """Number of sweep points (product of the axis sizes), without making them."""
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
        """Refuse huge sweeps at once, before any point is made (counted, not listed)."""
        n = self.sweep.size
        if n > self.run.max_points:
            raise FieldError(
                "sweep",
                f"{n:,} points, more than run.max_points ({self.run.max_points:,}); "
                "use fewer points, or raise run.max_points (or --max-points) if you mean it",
            )
        return self

    @model_validator(mode="after")
    def _starts_fit(self) -> Config:
        """Every sweep point must be a fiber the grid resolves, in the channel, off the pillar.

        Checked here, before any flow field is computed, with the same check a run
        makes (:func:`fibersweep.fiber.setup.check_start`); effects that move the
        start (start noise, pillar scale) are applied per run and checked there.
        """
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


def _describe(err: dict, lines: dict[tuple, int]) -> str:
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
    given = err.get("input")
    given_s = "" if isinstance(given, dict) else f"; given {given!r}"
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
