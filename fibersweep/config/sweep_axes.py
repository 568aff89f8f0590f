"""The sweep-axis algebra: the ``sweep`` section, its setting axes and their combinations.

:class:`SweepSettings` holds the three start axes (``theta0``, ``y0``,
``length``), any dotted setting key swept as an axis, and ``zip`` groups swept
together; :class:`RefineSettings` the adaptive refinement. Every combination of
the axes is validated as a whole config (:func:`combinations`). What a setting
key names is resolved against the whole config's models, so it lives with them
(:func:`fibersweep.config.schema.setting_annotation`).
"""

from __future__ import annotations

import copy
import difflib
import itertools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from pydantic import (
    ConfigDict,
    Field,
    ValidationError,
    field_validator,
    model_serializer,
    model_validator,
)

from fibersweep.config.axes import (
    Axis,
    _show,
    _Strict,
    axis_count,
    axis_values,
    setting_axis_count,
    setting_axis_values,
)
from fibersweep.config.errors import FieldError, all_checks, error_parts

__all__ = [
    "Combination",
    "RandomStarts",
    "RefineSettings",
    "SweepSettings",
    "combinations",
    "PhysicsChecks",
]


class RefineSettings(_Strict):
    """Adaptive refinement of class boundaries (``sweep.refine``).

    Starting from the grid, each round bisects every pair of neighbouring points
    (neighbours along one refine axis, every other coordinate and setting equal)
    whose classes differ, or whose δ differ by more than ``delta_jump``, until
    every such bracket is at most ``tolerance`` wide on its axis, the budget
    ``max_runs`` is spent or ``rounds`` rounds have run.
    """

    axes: list[str] = Field(
        min_length=1, description="start axes to bisect along (theta0, y0, length)"
    )
    tolerance: dict[str, float] = Field(
        description="largest bracket width per refine axis when a boundary counts as "
        "located [deg for theta0, h_obs for y0, l_obs for length]"
    )
    max_runs: int = Field(ge=1, strict=True, description="most refinement runs (the grid excluded)")
    rounds: int = Field(
        12, ge=1, le=60, strict=True, description="most refinement rounds (round 0 is the grid)"
    )
    delta_jump: float | None = Field(
        None,
        gt=0,
        description="also bisect neighbours of one class whose δ differ by more than this [h_obs]",
    )

    @field_validator("axes")
    @classmethod
    def _known_axes(cls, axes: list[str]) -> list[str]:
        for i, a in enumerate(axes):
            if a not in _START_AXES:
                close = difflib.get_close_matches(str(a), _START_AXES, n=1, cutoff=0.5)
                hint = f"did you mean '{close[0]}'? " if close else ""
                raise FieldError(
                    (i,),
                    f"{a!r} cannot be refined; {hint}valid: {', '.join(_START_AXES)} "
                    "(setting axes are swept on their listed values only)",
                )
        if len(set(axes)) != len(axes):
            raise ValueError(f"an axis is listed twice: {axes}")
        return axes

    @model_validator(mode="after")
    def _tolerances(self) -> RefineSettings:
        """One positive tolerance per refine axis, and none for another key."""
        for key, tol in self.tolerance.items():
            if key not in self.axes:
                raise FieldError(
                    ("tolerance", key),
                    f"not a refine axis; refine axes: {', '.join(self.axes)}",
                )
            if not (np.isfinite(tol) and tol > 0):
                raise FieldError(("tolerance", key), f"must be a positive number; got {tol}")
        missing = [a for a in self.axes if a not in self.tolerance]
        if missing:
            raise FieldError(
                "tolerance",
                f"no tolerance for {', '.join(missing)}; give one per refine axis, "
                f"e.g. tolerance: {{{missing[0]}: {_TOL_EXAMPLE.get(missing[0], 0.01)}}}",
            )
        return self


_TOL_EXAMPLE = {"theta0": 0.5, "y0": 0.005, "length": 0.01}


class RandomStarts(_Strict):
    """Seeded random starts (``sweep.random``): ``count`` per length and setting combination.

    Each start is drawn uniform in the ``theta0`` and ``y0`` ranges ``[lo, hi]``
    (:func:`fibersweep.sweep.draws.start_points`); a start that touches the pillar
    (or a pillar of the array) is drawn again. The same config gives the same starts.
    """

    count: int = Field(ge=1, strict=True, description="random starts per length")
    seed: int = Field(0, ge=0, strict=True, description="seed of the draws")


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
    refine: RefineSettings | None = Field(
        None, description="adaptive refinement of class boundaries (off when absent)"
    )
    random: RandomStarts | None = Field(
        None,
        description="seeded random starts: count per length, uniform in theta0 and y0 given "
        "as [lo, hi] (off when absent: the grid of the three start axes)",
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
        if isinstance(data, dict):
            for key in ("zip", "refine", "random"):  # written only when used
                if data.get(key) is None:
                    data.pop(key, None)
        return data

    @model_validator(mode="after")
    def _checks(self) -> SweepSettings:
        """The refine axes, the random ranges and the setting axes, all checked (each
        failure at its field)."""
        all_checks(self._refine_axes_swept, self._random_ranges, self._setting_axes_valid)
        return self

    def _refine_axes_swept(self) -> SweepSettings:
        """A refine axis needs at least two grid values to bisect between."""
        if self.refine is not None:
            for i, a in enumerate(self.refine.axes):
                if axis_count(getattr(self, a)) < 2:
                    raise FieldError(
                        ("refine", "axes", i),
                        f"{a} has one value in the grid: nothing to bisect; "
                        f"sweep {a} over at least two values or drop it from refine.axes",
                    )
        return self

    def _random_ranges(self) -> SweepSettings:
        """With ``random``: theta0 and y0 are ranges [lo, hi] (or one value); refinement
        along the length only (a pillar array's critical length, checked with the flow)."""
        if self.random is None:
            return self
        if self.refine is not None and self.refine.axes != ["length"]:
            raise FieldError(
                "refine.axes",
                "with sweep.random only the length is refined (a pillar array's critical "
                "length); use axes: [length]",
            )
        for name in ("theta0", "y0"):
            v = axis_values(getattr(self, name))
            if v.size > 2 or (v.size == 2 and v[0] > v[1]):
                raise FieldError(
                    name,
                    f"with sweep.random, {name} is the range the starts are drawn from: "
                    f"[lo, hi] with lo <= hi (or one value); got {_show(v)}",
                )
        return self

    def _setting_axes_valid(self) -> SweepSettings:
        """Keys are dotted, values are axis forms, zipped lists are equally long.

        That a key names a setting is the whole config's to say: :class:`Config`
        (:mod:`fibersweep.config.schema`) checks it.
        """
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
                setting_axis_values(raw)
            except ValueError as exc:
                raise FieldError(loc, str(exc)) from None
            if key in seen:
                where = ".".join(str(p) for p in ("sweep", *seen[key]))
                raise FieldError(loc, f"{key} is swept twice (also at {where}); keep one")
            seen[key] = loc
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
        """Number of start points (product of the three start axes, or random count
        per length), without making them."""
        if self.random is not None:
            return self.random.count * axis_count(self.length)
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


_START_AXES = ("theta0", "y0", "length")


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
    config: Any  # a Config (fibersweep.config.schema)

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
    loc, msg, given = error_parts(exc.errors()[0])
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


def _show_assignment(assignment: dict[str, Any]) -> str:
    return ", ".join(f"{k} = {v!r}" for k, v in assignment.items())


@dataclass(frozen=True)
class PhysicsChecks:
    """The physics checks a config is validated with, handed in by the caller.

    The config is the schema: it imports neither the fiber models nor the flow.
    What needs them (a start clear of the pillar, an effect's value in its range)
    is checked by functions of the sweep, handed in through the validation
    context (``load_config(..., physics=PHYSICS)``, :data:`fibersweep.sweep.starts.PHYSICS`).

    Attributes
    ----------
    check : callable
        ``check(cfg)``: raises :class:`FieldError` at the first field with a bad
        start point (a config without setting axes, or each combination).
    effects_off : callable
        ``effects_off(values, locs) -> list of str``: checks the swept effect
        values (``fiber.effects.*`` keys of ``values``; ``locs`` their fields) and
        returns the keys whose value is the effect's baseline (off).
    """

    check: Callable[[Any], None]
    effects_off: Callable[[dict[str, Any], dict[str, tuple]], list[str]]


def combinations(cfg: Any, physics: PhysicsChecks | None = None) -> list[Combination]:
    """The configs the sweep runs: one per combination of the setting axes.

    Each is ``cfg`` (a :class:`~fibersweep.config.schema.Config`) with the
    combination's values applied and no setting axes left, validated by the same
    schema. Without setting axes: ``[Combination({}, cfg)]``. With ``physics``
    each combination's starts and swept effects are checked too, and an effect
    swept to its baseline is left out of that combination's config.

    Raises
    ------
    FieldError
        A combination is invalid: at the axis whose value is at fault (its
        value named), or at the field that failed with the combination named.
    """
    assignments = cfg.sweep.assignments()
    if assignments == [{}]:
        return [Combination({}, cfg)]
    locs = {k: ("sweep", *loc) for loc, k, _ in cfg.sweep.axis_items()}
    context = {"physics": physics} if physics is not None else None
    base = cfg.model_dump(mode="json")
    # refine: the sweep's; random starts: each combination draws its own
    base["sweep"] = {k: base["sweep"][k] for k in (*_START_AXES, "random") if k in base["sweep"]}
    out = []
    for assignment in assignments:
        data = copy.deepcopy(base)
        for key, value in assignment.items():
            _set_path(data, key.split("."), value)
        try:
            cfg = type(cfg).model_validate(data, context=context)
        except ValidationError as exc:
            raise _combination_error(exc, assignment, locs) from None
        dumped = cfg.model_dump(mode="json")
        values = {k: _get_path(dumped, k.split(".")) for k in assignment}
        off = physics.effects_off(values, locs) if physics is not None else []
        if off:
            # An effect swept to its baseline is off: left out, so those runs keep the
            # ids of runs made without it (a folder swept later reuses them).
            for key in off:
                data["fiber"]["effects"].pop(key.split(".", 2)[2])
            cfg = type(cfg).model_validate(data, context=context)
        out.append(Combination(values, cfg))
    return out
