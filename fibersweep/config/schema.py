"""The config schema: the four sections of a YAML config and the run section.

A config has four sections, each optional: ``flow`` (:class:`FlowSettings`),
``fiber`` (:class:`FiberSettings`), ``sweep`` (:class:`SweepSettings`, in
:mod:`.sweep_axes` with the sweep-axis algebra) and ``run``
(:class:`RunSettings`). Unknown keys are errors. The physics checks of the
start points live in :mod:`.starts`. The config does not import the sweep: the
executor registry is handed in by the caller (:func:`.loading.load_config`).
"""

from __future__ import annotations

import difflib
from typing import Any

from pydantic import Field, ValidationInfo, model_validator

from fibersweep.config.axes import DEFAULT_MAX_POINTS, _Strict
from fibersweep.config.errors import FieldError
from fibersweep.config.starts import check_starts
from fibersweep.config.sweep_axes import (
    Combination,
    RefineSettings,
    SweepSettings,
    combinations,
    setting_annotation,
    setting_column,
)
from fibersweep.fiber.settings import FiberSettings
from fibersweep.flow.settings import FlowSettings

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

    @model_validator(mode="after")
    def _scheduler_address(self) -> RunSettings:
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

    @model_validator(mode="after")
    def _size_within_limit(self) -> Config:
        """Refuse huge sweeps at once, before any point is made (counted, not listed).

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
        axes left, validated by the same schema (its start points checked by
        :func:`fibersweep.config.starts.check_starts`). Without setting axes:
        ``[Combination({}, self)]`` (:func:`fibersweep.config.sweep_axes.combinations`).

        Raises
        ------
        FieldError
            A combination is invalid: at the axis whose value is at fault (its
            value named), or at the field that failed with the combination named.
        """
        return combinations(self)

    @model_validator(mode="after")
    def _random_refine_in_arrays_only(self) -> Config:
        """Random starts are refined along the length by the mean displacement fraction,
        which only pillar-array runs have (:mod:`fibersweep.sweep.refine_lengths`)."""
        sw = self.sweep
        if sw.random is not None and sw.refine is not None and self.flow.array is None:
            raise FieldError(
                "sweep.refine",
                "with sweep.random, refinement locates a pillar array's critical length "
                "(flow.array); a channel sweep refines a grid of starts (no sweep.random)",
            )
        return self

    @model_validator(mode="after")
    def _starts_fit(self) -> Config:
        """Every sweep point must be a fiber the grid resolves, in the channel, off the pillar.

        Checked here, before any flow field is computed (:func:`check_starts`).
        """
        check_starts(self)
        return self
