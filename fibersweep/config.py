"""The YAML schema of a fibersweep config, its loader, and sweep expansion.

A config has four sections, each optional: ``flow`` (:class:`FlowSettings`),
``fiber`` (:class:`FiberSettings`), ``sweep`` (:class:`SweepSettings`) and
``run`` (:class:`RunSettings`). Unknown keys are errors. :func:`load_config`
turns every validation problem into a :class:`ConfigError` that names the full
path of the field, what was expected, what was given, the YAML line, and a
did-you-mean for misspelled keys.
"""

from __future__ import annotations

import difflib
import itertools
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
import yaml
from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    Tag,
    ValidationError,
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
    "RunSettings",
    "SweepSettings",
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


class RangeSpec(_Strict):
    """Inclusive range ``start, start+step, ... <= stop``."""

    start: float
    stop: float
    step: float = Field(gt=0)

    @model_validator(mode="after")
    def _not_empty(self) -> RangeSpec:
        if self.stop < self.start:
            raise ValueError(f"empty range: start {self.start} > stop {self.stop}")
        return self

    def values(self) -> np.ndarray:
        n = int(np.floor((self.stop - self.start) / self.step + 1e-9)) + 1
        if n < 1:
            raise ValueError(f"empty range: start {self.start} > stop {self.stop}")
        return self.start + self.step * np.arange(n)


class LinspaceSpec(_Strict):
    """``num`` evenly spaced values from ``start`` to ``stop`` inclusive."""

    start: float
    stop: float
    num: int = Field(ge=1, le=100_000)

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
    Annotated[float, Tag("axis:number")]
    | Annotated[list[float], Tag("axis:list")]
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

    @model_validator(mode="after")
    def _finite(self) -> SweepSettings:
        for name in ("theta0", "y0", "length"):
            v = axis_values(getattr(self, name))
            if not np.all(np.isfinite(v)):
                raise ValueError(f"{name}: values must be finite")
            if len(v) == 0:
                raise ValueError(f"{name}: no values")
        if np.any(axis_values(self.length) <= 0):
            raise ValueError("length: values must be positive")
        return self

    def starts(self) -> list[FiberStart]:
        """Cartesian product of the axes, ordered length, y0, theta0."""
        return [
            FiberStart(theta0=float(t), y0=float(y), length=float(L))
            for L, y, t in itertools.product(
                axis_values(self.length), axis_values(self.y0), axis_values(self.theta0)
            )
        ]


class RunSettings(_Strict):
    """How a sweep is executed and where it writes."""

    workers: int = Field(2, ge=1, description="worker processes")
    output: str = Field("results/run", description="output directory")
    cache_dir: str = Field(".fibersweep-cache", description="flow-field cache directory")
    executor: Literal["local", "dask"] = Field("local", description="local pool or Dask")
    scheduler: str | None = Field(None, description="Dask scheduler address tcp://HOST:PORT")
    flush_every: int = Field(
        32, ge=1, description="finished runs per Parquet part file (also flushed on exit)"
    )
    flush_seconds: float = Field(
        30.0, gt=0, description="write a part at least this often while runs finish [s]"
    )
    retries: int = Field(
        2, ge=0, description="re-runs of a task whose worker died (local pool and Dask)"
    )
    compact: bool = Field(True, description="merge part files into one at the end of a sweep")

    @model_validator(mode="after")
    def _scheduler_address(self) -> RunSettings:
        if self.scheduler is not None and "://" not in self.scheduler:
            raise ValueError(
                f"scheduler: expected an address like tcp://HOST:PORT, got {self.scheduler!r}"
            )
        return self


class Config(_Strict):
    """A whole fibersweep config."""

    flow: FlowSettings = FlowSettings()
    fiber: FiberSettings = FiberSettings()
    sweep: SweepSettings = SweepSettings()
    run: RunSettings = RunSettings()

    @model_validator(mode="after")
    def _starts_fit(self) -> Config:
        """Every sweep point must be a fiber the grid resolves, in the channel, off the pillar.

        Checked here, before any flow field is computed, with the same check a run
        makes (:func:`fibersweep.fiber.setup.check_start`); effects that move the
        start (start noise, pillar scale) are applied per run and checked there.
        """
        from fibersweep.fiber.setup import check_start  # numba-backed: import lazily

        geo = self.flow.geometry.to_geometry()
        bad: dict[str, str] = {}
        for start in self.sweep.starts():
            try:
                check_start(geo, self.flow.dx, self.fiber, start)
            except InputError as exc:
                name, _, msg = str(exc).partition(": ")
                # x0 is a fiber setting; the other names are sweep axes.
                path = "fiber.x0" if name == "x0" else f"sweep.{name}"
                bad.setdefault(path, msg)  # first problem per field is enough to act on
        if bad:
            path, msg = next(iter(bad.items()))
            raise ValueError(f"{path}: {msg}")
        return self


# --------------------------------------------------------------------------- loading


@dataclass(frozen=True)
class _Located:
    data: Any
    lines: dict[tuple, int]


def _yaml_with_lines(text: str) -> _Located:
    """Parse YAML and record the 1-based line of every key path."""
    lines: dict[tuple, int] = {}

    def walk(node: yaml.Node, path: tuple) -> None:
        lines.setdefault(path, node.start_mark.line + 1)
        if isinstance(node, yaml.MappingNode):
            for k, v in node.value:
                key = (*path, k.value)
                lines[key] = k.start_mark.line + 1
                walk(v, key)
        elif isinstance(node, yaml.SequenceNode):
            for i, v in enumerate(node.value):
                walk(v, (*path, i))

    root = yaml.compose(text)
    if root is not None:
        walk(root, ())
    return _Located(yaml.safe_load(text), lines)


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
    named = re.match(r"^([a-z_0-9]+(?:\.[a-z_0-9]+)+): (.*)$", msg, flags=re.S)
    if named and not loc:
        # A whole-config check that names its field: report it at that field.
        loc = tuple(named.group(1).split("."))
        msg = named.group(2)
    dotted = ".".join(str(p) for p in loc) or "<top level>"
    line = None
    for k in range(len(loc), -1, -1):
        if loc[:k] in lines:
            line = lines[loc[:k]]
            break
    where = f" (line {line})" if line else ""
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
    data: Any, lines: dict[tuple, int] | None = None, source: str = "config"
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


def load_config(path: str | Path) -> Config:
    """Read and validate a YAML config file.

    Raises
    ------
    ConfigError
        Unreadable file, invalid YAML, or invalid settings (each named).
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
    return parse_config(located.data, located.lines, str(p))
