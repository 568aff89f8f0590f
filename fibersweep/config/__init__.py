"""A fibersweep config: its YAML schema, sweep axes, and loader.

Modules: :mod:`.axes` (the forms of a sweep axis, their counts and values),
:mod:`.schema` (the four sections ``flow``, ``fiber``, ``sweep``, ``run``, and
what a swept setting key names: its type and its column),
:mod:`.sweep_axes` (the sweep-axis algebra: the sweep over starts and settings,
combinations), :mod:`.starts` (physics checks of the start
points), :mod:`.loading` (YAML
with line numbers, command-line overrides, error messages that name each
field) and :mod:`.errors`. Every public name is importable from here.
"""

from __future__ import annotations

from fibersweep.config.axes import (
    DEFAULT_MAX_POINTS,
    MAX_AXIS_VALUES,
    Axis,
    LinspaceSpec,
    RangeSpec,
    axis_count,
    axis_values,
    setting_axis_count,
    setting_axis_values,
)
from fibersweep.config.errors import ConfigError, FieldError
from fibersweep.config.loading import apply_overrides, load_config, parse_config
from fibersweep.config.schema import (
    Combination,
    Config,
    RefineSettings,
    RunSettings,
    SweepSettings,
    setting_annotation,
    setting_column,
)

__all__ = [
    "DEFAULT_MAX_POINTS",
    "MAX_AXIS_VALUES",
    "Axis",
    "Combination",
    "Config",
    "ConfigError",
    "FieldError",
    "LinspaceSpec",
    "RangeSpec",
    "RefineSettings",
    "RunSettings",
    "SweepSettings",
    "apply_overrides",
    "axis_count",
    "axis_values",
    "load_config",
    "parse_config",
    "setting_annotation",
    "setting_axis_count",
    "setting_axis_values",
    "setting_column",
]
