"""The flow field of a config, one per distinct flow setting (``fibersweep flow``)."""

from __future__ import annotations

import logging
from collections.abc import Iterator
from dataclasses import dataclass
from dataclasses import field as attr
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # annotations only: the API imports what it runs when it runs it
    from fibersweep.config import Config
    from fibersweep.config.flow import FlowSettings
    from fibersweep.flow.cache import CacheInfo
    from fibersweep.flow.uncertainty import SeparatrixEstimate

from fibersweep.api.common import _flow_bars, load_config

log = logging.getLogger("fibersweep.api")


@dataclass(frozen=True)
class FieldReport:
    """One flow field of :func:`flow_field`, and what the solver and the analysis say.

    Attributes
    ----------
    key : str
        Cache key of its settings.
    label : str
        The swept flow values that make it (``"base flow settings"`` without any).
    settings : FlowSettings
    field : FlowField
        Velocities [µm/s] on the lattice, with interpolation; a pillar array's unit
        cell (``CellField``, with ``.array``).
    info : CacheInfo
        Where it came from (cache hit or computed), the solver's steps, convergence,
        residual and seconds, the centreline speed reached [µm/s], the grid.
    seconds : float
        Seconds this call took to get it (a load, or the solve) [s].
    separatrix : SeparatrixEstimate or None
        Past one pillar: the far-upstream separatrix [h_obs] with its error (model
        spread, grid error when another level is cached); None in a pillar array or
        when not located (``separatrix_error`` says why).
    separatrix_error : str or None
    figure : Path or None
        The figure written (``plot``).
    """

    key: str
    label: str
    settings: FlowSettings = attr(repr=False)
    field: Any = attr(repr=False)
    info: CacheInfo = attr(repr=False)
    seconds: float
    separatrix: SeparatrixEstimate | None = None
    separatrix_error: str | None = None
    figure: Path | None = None


@dataclass(frozen=True)
class FlowFields:
    """The flow fields of a config (:func:`flow_field`): one, or one per distinct flow
    setting of a sweep over flow settings.

    Attributes
    ----------
    config : Config
    reports : tuple of FieldReport
        In sweep order; the first is the base settings' field when flow is not swept.
    """

    config: Config = attr(repr=False)
    reports: tuple[FieldReport, ...] = ()

    @property
    def field(self) -> Any:
        """The (first) flow field."""
        return self.reports[0].field

    def __iter__(self) -> Iterator[FieldReport]:
        return iter(self.reports)

    def __len__(self) -> int:
        return len(self.reports)


def flow_field(
    config: str | Path | Config,
    *overrides: str,
    force: bool = False,
    plot: str | Path | None = None,
    progress: bool = False,
) -> FlowFields:
    """Compute (or load from the cache) the steady flow field of a config
    (``fibersweep flow``): a channel's, or a pillar array's unit cell.

    A sweep over flow settings (``sweep: {flow.dx: [4, 2]}``) has one field per
    distinct flow setting: each is computed (or found) once.

    Parameters
    ----------
    config : str, Path or Config
        The config (its flow section, and the sweep's flow axes if any).
    *overrides : str
        ``KEY=VALUE`` settings, e.g. ``"flow.dx=2"``.
    force : bool
        Recompute the field even if it is cached.
    plot : str or Path, optional
        Write a figure of the field (PNG/PDF/SVG by suffix); with several fields, one
        per field, its key added to the name.
    progress : bool
        Show a bar over the solver's steps.

    Returns
    -------
    FlowFields
        ``.field`` is the (first) :class:`~fibersweep.flow.field.FlowField`;
        ``.reports`` say, per field, where it came from and its separatrix.
    """
    from fibersweep.flow.cache import cache_key
    from fibersweep.sweep.starts import PHYSICS

    cfg = load_config(config, *overrides)
    distinct: dict[str, tuple[Any, str]] = {}
    for combo in cfg.combinations(PHYSICS):
        key = cache_key(combo.config.flow)
        if key not in distinct:
            values = {k: v for k, v in combo.values.items() if k.startswith("flow.")}
            label = ", ".join(f"{k}={v}" for k, v in values.items()) or "base flow settings"
            distinct[key] = (combo.config.flow, label)
    reports = []
    with _flow_bars(progress):
        for key, (settings, label) in distinct.items():
            where = None if plot is None else Path(plot)
            if where is not None and len(distinct) > 1:
                where = where.with_name(f"{where.stem}-{key}{where.suffix}")
            reports.append(_one_field(key, label, settings, cfg.run.cache_dir, force, where))
    return FlowFields(cfg, tuple(reports))


def _one_field(key: str, label: str, settings: FlowSettings, cache_dir: str, force: bool,
               plot: Path | None) -> FieldReport:  # fmt: skip
    """Compute or load one field; its separatrix (past one pillar) and figure."""
    import time

    from fibersweep.flow.cache import get_flow_field

    t0 = time.perf_counter()
    flow, info = get_flow_field(settings, cache_dir, force=force)
    took = time.perf_counter() - t0
    log.info("flow field %s: %s in %.1f s", key, "cached" if info.hit else "computed", took)
    if settings.array is not None:  # a pillar array's unit cell: no far upstream
        figure = None
        if plot is not None:
            from fibersweep.plots.array import cell_flow_figure
            from fibersweep.plots.style import paper_style, save_figure

            with paper_style():
                figure = save_figure(cell_flow_figure(flow), plot, dpi=110)
        return FieldReport(key, label, settings, flow, info, took, figure=figure)
    from fibersweep.flow.uncertainty import other_level, separatrix_estimate

    est, why = None, None
    try:
        level = other_level(settings, cache_dir)
        est = separatrix_estimate(flow, None if level is None else level[1])
    except ValueError as exc:  # no streamline bracket (e.g. a toy channel)
        why = str(exc)
    figure = None
    if plot is not None:
        from fibersweep.plots.flow import plot_flow

        figure = plot_flow(flow, plot)
    return FieldReport(key, label, settings, flow, info, took, est, why, figure)


# --------------------------------------------------------------------------- classify
