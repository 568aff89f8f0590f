"""One fiber run (``fibersweep simulate``), with its chronophotograph."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from dataclasses import field as attr
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # annotations only: the API imports what it runs when it runs it
    from fibersweep.config import Config
    from fibersweep.config.fiber import FiberSettings
    from fibersweep.fiber.result import RunResult

from fibersweep.api.common import _flow_bars, load_config

log = logging.getLogger("fibersweep.api")


@dataclass(frozen=True)
class FiberRun:
    """One fiber run of :func:`simulate`.

    Attributes
    ----------
    result : RunResult
        The run: past one pillar its class, δ [h_obs], contact...; through a pillar
        array its mode, rows, shift per row [µm], f and migration angle [deg];
        ``trajectory`` when recorded (:mod:`fibersweep.fiber.result`).
    config : Config
        The resolved config.
    fiber : FiberSettings
        The fiber settings the run used (with ``plot``: the trajectory recorded).
    field : FlowField
        The flow field it ran in (a pillar array's unit cell: ``field.array``).
    returned : float
        With ``reversible``: how far from its start the fiber returned when the flow
        was reversed [µm]; NaN otherwise.
    ready_s : float
        Seconds to make the fiber kernels ready before the run [s]: compiled on first
        use (then loaded from the disk cache).
    figure : Path or None
        The chronophotograph written (``plot``).
    warnings : tuple of str
        Where the settings leave the validated range, each naming the setting to
        change and its source page (:mod:`fibersweep.sweep.validity`).
    """

    result: RunResult
    config: Config = attr(repr=False)
    fiber: FiberSettings = attr(repr=False)
    field: Any = attr(repr=False)
    returned: float = math.nan
    ready_s: float = 0.0
    figure: Path | None = None
    warnings: tuple[str, ...] = ()

    @property
    def array(self) -> Any:
        """The pillar array the fiber crossed (None past one pillar)."""
        return getattr(self.field, "array", None)


def simulate(
    config: str | Path | Config,
    *overrides: str,
    theta0: float,
    y0: float,
    length: float,
    model: str | None = None,
    reversible: bool = False,
    seed: int | None = None,
    plot: str | Path | None = None,
    progress: bool = False,
) -> FiberRun:
    """Run one fiber (``fibersweep simulate``): past one pillar, or through a pillar array.

    Parameters
    ----------
    config : str, Path or Config
        The config (its flow, fiber and run sections; the sweep is not used).
    *overrides : str
        ``KEY=VALUE`` settings, e.g. ``"fiber.model=bead-spring"``.
    theta0 : float
        Start angle from +x [deg].
    y0 : float
        Start lateral position: y0/h_obs past one pillar; in a pillar array a fraction
        of ``period_y`` in the gap before row 0.
    length : float
        Fiber length: L/l_obs past one pillar; in a pillar array L [µm].
    model : str, optional
        Fiber model (the override ``fiber.model=MODEL``, checked with the others).
    reversible : bool
        Also reverse the flow and measure how far from the start the fiber returns
        (not in a pillar array).
    seed : int, optional
        Seed of random effects.
    plot : str or Path, optional
        Write a chronophotograph here (PNG/PDF/SVG by suffix); a flexible fiber is
        drawn through all its beads.
    progress : bool
        Show a bar while a flow field is computed.

    Returns
    -------
    FiberRun
        ``.result`` is the run's :class:`~fibersweep.fiber.result.RunResult`; a run that
        failed has ``result.status != "ok"`` and its ``reason``.

    Raises
    ------
    InputError
        A bad start, before any flow field is solved or kernel compiled when it is a
        start that touches a pillar: the message names the free ranges of y0 at that
        angle and length (:func:`fibersweep.sweep.draws.free_text`).
    """
    import time

    from fibersweep.errors import InputError
    from fibersweep.fiber.result import FiberStart
    from fibersweep.fiber.run import simulate as run_one
    from fibersweep.fiber.run import simulate_reversible
    from fibersweep.flow.cache import get_flow_field
    from fibersweep.plots.shapes import is_flexible
    from fibersweep.sweep.draws import check_start_of, free_text
    from fibersweep.sweep.validity import facts, warnings_for
    from fibersweep.sweep.worker import _warm

    extra = [f"fiber.model={model}"] if model is not None else []
    cfg = load_config(config, *overrides, *extra)
    check_start_of(cfg, theta0, y0, length)  # before the field and the kernels: seconds saved
    warned = warnings_for([facts(cfg.fiber, cfg.flow.array)])
    for w in warned:
        log.info("outside the validated range: %s", w)
    fiber = cfg.fiber
    if plot is not None:  # the drawing needs the trajectory, and a bent fiber its beads
        rec = fiber.record.model_copy(
            update={
                "trajectories": True,
                "samples": max(fiber.record.samples, 2000),
                "all_beads": fiber.record.all_beads or is_flexible(fiber.model),
            }
        )
        fiber = fiber.model_copy(update={"record": rec})
    with _flow_bars(progress):
        flow, _ = get_flow_field(cfg.flow, cfg.run.cache_dir)
    array = getattr(flow, "array", None)
    start = FiberStart(theta0=theta0, y0=y0, length=length)
    if array is not None and reversible:
        raise InputError("--reversible: not available in a pillar array (flow.array)")
    t0 = time.perf_counter()
    _warm(flow, fiber)  # a short run: the kernels compiled on first use, else loaded
    ready_s = time.perf_counter() - t0
    back = math.nan
    try:
        if reversible:
            res, back = simulate_reversible(flow, fiber, start, rng_seed=seed)
        else:
            res = run_one(flow, fiber, start, rng_seed=seed)
    except InputError as exc:  # a start the check above could not see (an effect moved it)
        text = str(exc)
        if text.startswith("y0") and ("touches a pillar" in text or "overlaps" in text):
            raise InputError(f"{text}; {free_text(cfg, theta0, length)}") from None
        raise
    outcome = getattr(res, "mode", None) or res.cls or res.status
    log.info("%s: %s in %.2f s", start, outcome, res.wall_time)
    figure = None if plot is None else _chronophotograph(res, flow, fiber, Path(plot))
    return FiberRun(res, cfg, fiber, flow, float(back), ready_s, figure, warned)


def _chronophotograph(res: RunResult, flow: Any, fiber: FiberSettings, plot: Path) -> Path:
    """The chronophotograph: past one pillar, or through the rows of an array."""
    array = getattr(flow, "array", None)
    if array is None:
        from fibersweep.plots.chrono import chronophotograph

        return chronophotograph(res, flow.geometry, plot)
    from fibersweep.plots.array_chrono import run_dict, run_figure
    from fibersweep.plots.style import paper_style, save_figure

    with paper_style():
        fig = run_figure(array, run_dict(res, fiber.bead_radius), fiber.bead_radius)
        return save_figure(fig, plot)


# --------------------------------------------------------------------------- flow field
