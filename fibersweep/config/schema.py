"""The config schema: the four sections of a YAML config and the run section.

A config has four sections, each optional: ``flow`` (:class:`FlowSettings`),
``fiber`` (:class:`FiberSettings`), ``sweep`` (:class:`SweepSettings`, in
:mod:`.sweep_axes` with the sweep-axis algebra) and ``run``
(:class:`RunSettings`). Unknown keys are errors. A swept setting key is resolved
here, against the whole config's models (:func:`setting_annotation`), and stored
as a typed, documented column (:func:`setting_column`). The physics checks of
the start points live in :mod:`.starts`. The config does not import the sweep:
the executor registry is handed in by the caller (:func:`.loading.load_config`).
"""

from __future__ import annotations

import difflib
import re
import types
import typing
from typing import Any

from pydantic import BaseModel, Field, ValidationInfo, field_validator, model_validator

from fibersweep.config.axes import DEFAULT_MAX_POINTS, _Strict
from fibersweep.config.errors import FieldError, all_checks
from fibersweep.config.fiber import FiberSettings
from fibersweep.config.flow import FlowSettings
from fibersweep.config.sweep_axes import (
    Combination,
    PhysicsChecks,
    RefineSettings,
    SweepSettings,
    combinations,
)

__all__ = [
    "Combination",
    "Config",
    "RefineSettings",
    "RunSettings",
    "SweepSettings",
    "setting_annotation",
    "setting_column",
]


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
    options: dict[str, Any] = Field(
        {},
        description="further options of the executor (its Options model), e.g. chunk_size for dask",
    )
    compact: bool = Field(True, description="merge part files into one at the end of a sweep")
    max_points: int = Field(
        DEFAULT_MAX_POINTS,
        ge=1,
        description="refuse sweeps with more points than this (raise it on purpose)",
    )

    @model_validator(mode="after")
    def _checks(self, info: ValidationInfo) -> RunSettings:
        """The executor and the scheduler, both checked (each failure at its field)."""
        all_checks(lambda: self._known_executor(info), self._scheduler_address)
        return self

    def _known_executor(self, info: ValidationInfo) -> RunSettings:
        """Check the executor's name and options against the registry the caller passes.

        The config does not import the sweep: ``load_config(..., executors=EXECUTORS)``
        (the CLI) hands the registry in as validation context; without it, the
        executor is checked when it is made (:func:`fibersweep.sweep.executors.make_executor`).
        """
        executors = (info.context or {}).get("executors")
        if not executors:
            return self
        if self.executor not in executors:
            close = difflib.get_close_matches(self.executor, list(executors), n=1)
            hint = f"did you mean '{close[0]}'? " if close else ""
            raise FieldError("executor", f"unknown executor; {hint}valid: {', '.join(executors)}")
        known = executors[self.executor].Options.model_fields
        for key in self.options:
            if key not in known:
                raise FieldError(
                    f"options.{key}",
                    f"not an option of the {self.executor} executor; valid: "
                    f"{', '.join(k for k in known if k not in ('retries', 'keep'))}",
                )
        return self

    def _scheduler_address(self) -> RunSettings:
        """A scheduler is an address like tcp://HOST:PORT."""
        if self.scheduler is not None and "://" not in self.scheduler:
            raise FieldError(
                "scheduler", f"expected an address like tcp://HOST:PORT, got {self.scheduler!r}"
            )
        return self


class DiscrepancySection(_Strict):
    """Settings of ``fibersweep discrepancy`` and ``fibersweep power`` kept with the config."""

    candidates: list[str] = Field(
        default_factory=list,
        description="candidate explanations from any setting, besides the library's effects: "
        "KEY=LO..HI (fitted), KEY=VALUE (an alternative), or a model switch with its "
        "parameter (docs/discrepancy.md, 'Is my fiber flexible?')",
    )


class Config(_Strict):
    """A whole fibersweep config."""

    flow: FlowSettings = FlowSettings()
    fiber: FiberSettings = FiberSettings()
    sweep: SweepSettings = SweepSettings()
    run: RunSettings = RunSettings()
    discrepancy: DiscrepancySection = DiscrepancySection()

    @field_validator("sweep")
    @classmethod
    def _swept_keys_are_settings(cls, sweep: SweepSettings) -> SweepSettings:
        """Every setting axis names a setting of this config that changes results.

        A field validator, so that the other sections' problems are reported with it.
        """
        for loc, key, _ in sweep.axis_items():
            try:
                setting_annotation(key)
            except ValueError as exc:
                raise FieldError(loc, str(exc)) from None
        return sweep

    @model_validator(mode="after")
    def _whole_config(self, info: ValidationInfo) -> Config:
        """The checks across sections, all of them (each failure at its field).

        Each runs when the sections it reads are valid: the loader validates a
        config whose sections failed again with those at their defaults, naming them
        in the context (``failed_sections``), so the other checks still report
        (:func:`fibersweep.config.loading.parse_config`). The checks that make the
        sweep's points (combinations, starts) run only on a sweep within
        ``run.max_points``.
        """
        context = info.context or {}
        failed = set(context.get("failed_sections") or ())
        physics = context.get("physics")

        def ready(*sections: str) -> bool:
            return not failed.intersection(sections)

        checks = []
        size = self._size_problem()
        if size is not None and ready("sweep", "run"):
            checks.append(lambda: _raise(size))
        if ready("sweep", "flow"):
            checks.append(self._random_refine_in_arrays_only)
        # the points are made only for a sweep of a size allowed (by the default limit
        # when the run section failed)
        if size is None and ready("flow", "fiber", "sweep"):
            checks.append(lambda: self._combinations_valid(physics))
            checks.append(lambda: self._starts_fit(physics))
        all_checks(*checks)
        return self

    def _size_problem(self) -> FieldError | None:
        """Huge sweeps are refused at once, before any point is made (counted, not listed).

        Every setting combination counts: the limit is on start points times
        combinations.
        """
        starts, combos = self.sweep.size, self.sweep.n_combinations
        extra = self.sweep.refine.max_runs if self.sweep.refine is not None else 0
        n = starts * combos + extra
        if n > self.run.max_points:
            how = f" ({starts:,} starts x {combos:,} setting combinations)" if combos > 1 else ""
            if extra:
                how += f" (with the {extra:,} refinement runs of sweep.refine.max_runs)"
            return FieldError(
                "sweep",
                f"{n:,} points{how}, more than run.max_points ({self.run.max_points:,}); "
                "use fewer points, or raise run.max_points (or --max-points) if you mean it",
            )
        return None

    def _combinations_valid(self, physics: PhysicsChecks | None) -> None:
        """Every setting combination is a valid config (same schema, same physics checks)."""
        if self.sweep.setting_keys:
            self.combinations(physics)

    def combinations(self, physics: PhysicsChecks | None = None) -> list[Combination]:
        """The configs the sweep runs: one per combination of the setting axes.

        Each is this config with the combination's values applied and no setting
        axes left, validated by the same schema (its start points checked by
        :func:`fibersweep.sweep.starts.check_starts`). Without setting axes:
        ``[Combination({}, self)]`` (:func:`fibersweep.config.sweep_axes.combinations`).

        Raises
        ------
        FieldError
            A combination is invalid: at the axis whose value is at fault (its
            value named), or at the field that failed with the combination named.
        """
        return combinations(self, physics)

    def _random_refine_in_arrays_only(self) -> None:
        """Random starts are refined along the length by the mean displacement fraction,
        which only pillar-array runs have (:mod:`fibersweep.sorting.lengths`)."""
        sw = self.sweep
        if sw.random is not None and sw.refine is not None and self.flow.array is None:
            raise FieldError(
                "sweep.refine",
                "with sweep.random, refinement locates a pillar array's critical length "
                "(flow.array); a channel sweep refines a grid of starts (no sweep.random)",
            )

    def _starts_fit(self, physics: PhysicsChecks | None) -> None:
        """Every sweep point must be a fiber the grid resolves, in the channel, off the pillar.

        Checked here, before any flow field is computed, when the caller hands in the
        physics checks (``load_config(..., physics=PHYSICS)``; the config imports no
        fiber model).
        """
        if physics is not None:
            physics.check(self)


def _raise(exc: Exception) -> None:
    raise exc


def _unwrap(ann: Any) -> Any:
    """``X | None`` -> X (the other members of a union are kept)."""
    args = [a for a in typing.get_args(ann) if a is not type(None)]
    if typing.get_origin(ann) in (typing.Union, types.UnionType) and len(args) == 1:
        return args[0]
    return ann


def setting_annotation(key: str) -> tuple[Any, Any]:
    """Type annotation and pydantic field of a dotted setting key that may be swept.

    Walks the models of :class:`Config` from the root; inside a mapping setting
    (``fiber.effects``) the next part is a mapping key and the value type is
    returned (field None).

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
