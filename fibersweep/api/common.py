"""Configs for the API (loaded with the physics checks, the run section from arguments),
the flow-solve bars, and a results folder read back."""

from __future__ import annotations

import logging
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # annotations only: the API imports what it runs when it runs it
    from fibersweep.config import Config
    from fibersweep.results import Results

log = logging.getLogger("fibersweep.api")


def load_config(
    config: str | Path | Config, *overrides: str, max_points: int | None = None
) -> Config:
    """A config resolved as every command sees it: overrides applied, defaults filled in,
    every check made.

    Parameters
    ----------
    config : str, Path or Config
        A YAML config file, or a config already loaded (then only ``overrides`` and
        ``max_points`` are applied and checked).
    *overrides : str
        ``KEY=VALUE`` settings that replace the config's, e.g. ``"flow.dx=2"``,
        ``"sweep.y0=[0.3, 0.4]"`` (values are YAML).
    max_points : int, optional
        Allow sweeps up to this many points (``run.max_points``).

    Returns
    -------
    Config
        Checked against the executors and the physics of the starts (the sweep's
        :data:`~fibersweep.sweep.starts.PHYSICS`).

    Raises
    ------
    ConfigError
        A bad key or value, named with its line or its override.
    """
    from fibersweep.config import Config, apply_overrides, parse_config
    from fibersweep.config import load_config as read_config
    from fibersweep.sweep.executors import EXECUTORS
    from fibersweep.sweep.starts import PHYSICS

    if not isinstance(config, Config):
        return read_config(
            config, overrides, max_points=max_points, executors=EXECUTORS, physics=PHYSICS
        )
    if not overrides and max_points is None:
        return config
    data = apply_overrides(config.model_dump(mode="json"), {}, overrides)
    if max_points is not None:
        data["run"] = {**data.get("run", {}), "max_points": max_points}
    return parse_config(data, source="config", executors=EXECUTORS, physics=PHYSICS)


def _with_run(cfg: Config, **kw: Any) -> Config:
    """``cfg`` with ``run`` settings given as arguments, checked as in the file."""
    from fibersweep.config import parse_config
    from fibersweep.sweep.starts import PHYSICS

    over = {k: v for k, v in kw.items() if v is not None}
    if not over:
        return cfg
    data = cfg.model_dump(mode="json")
    data["run"].update(over)
    return parse_config(data, source="command line", physics=PHYSICS)


def _sweep_config(
    config: str | Path | Config,
    overrides: Sequence[str],
    max_points: int | None,
    output: str | Path | None,
    workers: int | None,
    executor: str | None,
    scheduler: str | None,
) -> Config:
    """The config of a sweep with the run settings given as arguments (a scheduler
    without an executor means Dask)."""
    cfg = load_config(config, *overrides, max_points=max_points)
    if scheduler and executor is None:
        executor = "dask"
    return _with_run(
        cfg, workers=workers, executor=executor, scheduler=scheduler,
        output=None if output is None else str(output),
    )  # fmt: skip


@contextmanager
def _flow_bars(show: bool) -> Iterator[None]:
    """A bar over the LBM steps, with the residual, for any flow solve in the block.

    One bar per solve (the nested solve does the coarser grids first), closed on
    the grid's last report, so whatever is printed next starts on a line of its
    own. Nothing is shown when the field comes from the cache, or when ``show`` is
    false (the solver then logs its progress).
    """
    if not show:
        yield
        return
    from fibersweep.flow.progress import SolveProgress, on_progress
    from fibersweep.progressbar import progress_bar

    open_: list = []  # the bar of the grid being solved, if any

    def close() -> None:
        while open_:
            open_.pop().close()

    def report(p: SolveProgress) -> None:
        if p.steps == 0 or not open_:  # every solve reports step 0 first
            close()
            open_.append(
                progress_bar(
                    desc=f"flow field, dx = {p.dx:g} µm ({p.cells / 1e6:.2g} M cells)",
                    unit=" steps",
                    postfix="starting (the first solve also compiles the kernels)",
                )
            )
        bar = open_[0]
        if p.steps == 0:
            return
        bar.set_postfix_str(
            f"residual {p.residual:.1e} (stops at {p.tolerance:.0e})", refresh=False
        )
        bar.update(p.steps - bar.n)
        if p.finished:
            close()

    try:
        with on_progress(report):
            yield
    finally:
        close()


# --------------------------------------------------------------------------- run


def load(results: str | Path, trajectories: bool = True) -> Results:
    """A sweep's output folder in one call: runs, trajectories, settings and units.

    Parameters
    ----------
    results : str or Path
        The output folder (``run.output``).
    trajectories : bool
        Also read the trajectories (the larger table).

    Returns
    -------
    Results
        ``.runs`` and ``.trajectories`` (pandas), ``.settings`` (the resolved config),
        ``.units`` and ``.docs`` (per column), ``.provenance``; see
        :func:`fibersweep.results.load_results`.
    """
    from fibersweep.results import load_results

    return load_results(results, trajectories)
