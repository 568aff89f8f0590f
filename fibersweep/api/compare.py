"""Measured fibers against the model (``fibersweep discrepancy``)."""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from dataclasses import field as attr
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # annotations only: the API imports what it runs when it runs it
    from fibersweep.config import Config
    from fibersweep.discrepancy.workflow import DiscrepancyResult, DiscrepancySettings

from fibersweep.api.common import load_config

log = logging.getLogger("fibersweep.api")


def is_array(cfg: Config) -> bool:
    """Whether ``cfg`` is a pillar array (``flow.array`` set): the array workflow."""
    return cfg.flow.array is not None


def refuse_array(cfg: Config, command: str, what: str = "") -> None:
    """Refuse a pillar array for a part of the workflow that is the channel's only.

    Parameters
    ----------
    cfg : Config
    command : str
        The command or option named in the message.
    what : str
        What has no meaning in an array (e.g. 'trajectories in the channel frame').

    Raises
    ------
    InputError
        ``cfg`` has ``flow.array``.
    """
    from fibersweep.errors import InputError

    if cfg.flow.array is not None:
        raise InputError(
            f"{command}: {what or 'this'} is the single-pillar channel's; a pillar array "
            "(flow.array) is compared by its array observables (fraction, trapped, mode, "
            "bend; docs/discrepancy.md, 'In a pillar array')"
        )


def array_settings_parts(
    cfg: Config, effects: Sequence[str] | None, declared: tuple
) -> dict[str, Any]:
    """What a pillar array changes in :class:`DiscrepancySettings`: noise, library, candidates.

    InputError for a library effect or declared candidate an array cannot apply.
    """
    from fibersweep.discrepancy.array_workflow import array_effect_names, check_array_candidates
    from fibersweep.discrepancy.copies import array_noise

    check_array_candidates(declared)
    return {"noise": array_noise(cfg.fiber), "effects": array_effect_names(effects, cfg.fiber)}


def check_array_lengths(length: Any, bead_radius: float, source: str) -> None:
    """Every measured length [µm] holds at least one bead of the config's fiber.

    Parameters
    ----------
    length : ndarray, shape (n,)
        Measured lengths [µm].
    bead_radius : float
        The config's bead radius a [µm]; the shortest fiber is one bead, 2a.
    source : str
        The table, for the message.

    Raises
    ------
    InputError
        Naming the rows; lengths that all lie below 2 µm are said to look like
        fractions L / l_obs (the channel's unit).
    """
    import numpy as np

    from fibersweep.discrepancy.schema import rows_text
    from fibersweep.errors import InputError

    length = np.asarray(length, dtype=np.float64)
    short = length < 2.0 * bead_radius * (1.0 - 1e-9)
    if not short.any():
        return
    hint = (
        "; every length is below 2 µm: they look like fractions L / l_obs (a pillar array "
        "takes the length in µm)"
        if (length < 2.0).all()
        else ""
    )
    raise InputError(
        f"{source}: length: shorter than one bead (2a = {2.0 * bead_radius:g} µm) in "
        f"{rows_text(short)} (e.g. {length[short][0]:g} µm){hint}"
    )


def load_measured_for(
    cfg: Config, path: str | Path, trajectories: str | Path | None = None,
    ignore_extra: bool = False,
) -> Any:  # fmt: skip
    """The measured fibers as the workflow takes them (``MeasuredData``).

    An array measured table for an array config (:mod:`fibersweep.discrepancy.array_schema`),
    the channel's otherwise (:func:`fibersweep.discrepancy.measured.load_measured`).
    """
    if is_array(cfg):
        from fibersweep.discrepancy.array_schema import array_measured_data, load_array_measured

        if trajectories is not None:
            refuse_array(cfg, "--trajectories", "measured tracks in the channel frame")
        table = load_array_measured(path, ignore_extra)
        check_array_lengths(table["length"].to_numpy(), cfg.fiber.bead_radius, str(path))
        return array_measured_data(table, str(path))
    from fibersweep.discrepancy.measured import load_measured

    return load_measured(path, trajectories, ignore_extra=ignore_extra,
                         geometry=cfg.flow.geometry.to_geometry())  # fmt: skip


def sweep_box(cfg: Config) -> dict[str, tuple[float, float]]:
    """The range of the config's start axes: theta0 [deg], y0 [h_obs], length [l_obs]."""
    from fibersweep.config import axis_values

    box = {}
    for name in ("theta0", "y0", "length"):
        v = axis_values(getattr(cfg.sweep, name))
        box[name] = (float(v.min()), float(v.max()))
    return box


def declared_candidates(cfg: Config, candidates: Sequence[str] | None) -> tuple:
    """Declared candidates: the config's ``discrepancy.candidates``, then ``candidates``
    (``--candidate`` texts: ``KEY=LO..HI``, ``KEY=VALUE``, or a switch with its parameter)."""
    from fibersweep.discrepancy.declared import parse_candidates
    from fibersweep.errors import InputError

    texts = list(cfg.discrepancy.candidates)
    where = [f"discrepancy.candidates[{i}]:" for i in range(len(texts))]
    texts += list(candidates or [])
    where += ["--candidate"] * len(candidates or [])
    declared = tuple(parse_candidates(texts, cfg.fiber, cfg.flow, where))
    if cfg.flow.array is None:
        for c, w in zip(declared, where, strict=False):
            keys = [c.key, *(k for k, _ in c.switch)] if c.key else [k for k, _ in c.switch]
            if any(k.startswith("flow.array") for k in keys):
                raise InputError(
                    f"{w} {c.name}: flow.array settings are a pillar array's; this config "
                    "has no flow.array (it is the single-pillar channel)"
                )
    return declared


@dataclass(frozen=True)
class DiscrepancyPlan:
    """What :func:`discrepancy` is about to run (handed to its ``on_plan``).

    Attributes
    ----------
    fibers : int
        Measured fibers.
    settings : DiscrepancySettings
        The workflow's settings (its budget plan:
        :func:`fibersweep.discrepancy.settings.plan_budget`).
    followup : int or None
        Follow-up fibers, if given.
    starts : ndarray, shape (fibers, 3), optional
        The measured starts (θ0 [deg], y0 [h_obs], L [l_obs]; in an array y0 [/period_y],
        L [µm]): what the follow-up stages cost follows from them
        (:func:`fibersweep.discrepancy.followup.followup_costs`).
    fields : tuple of str
        In a pillar array, a line per declared flow candidate: its unit-cell field
        found in the cache, or solved once at the cost stated
        (:func:`fibersweep.discrepancy.array_workflow.field_plan`).
    """

    fibers: int
    settings: DiscrepancySettings
    followup: int | None = None
    starts: Any = attr(default=None, repr=False, compare=False)
    fields: tuple[str, ...] = ()


@dataclass(frozen=True)
class DiscrepancyReport:
    """The discrepancy workflow's result and the report written (:func:`discrepancy`).

    Attributes
    ----------
    result : DiscrepancyResult
        Everything the report is made of: the verdict, the gap, the fits...
    summary : dict
        The report's JSON summary (``summary.json``): ``verdict`` (``kind``,
        ``text``), ``simulations``, ``seconds`` [s], ``updated_configs``...
    path : Path
        The report folder (``report.md``, ``summary.json``, figures, updated configs).
    """

    result: DiscrepancyResult = attr(repr=False)
    summary: dict[str, Any] = attr(repr=False)
    path: Path = Path("report")

    @property
    def verdict(self) -> dict[str, Any]:
        """``kind`` (named, ambiguous, no gap, unexplained...) and ``text``."""
        return self.summary["verdict"]

    @property
    def files(self) -> tuple[Path, ...]:
        """The report and summary, and the updated configs written."""
        return (self.path / "report.md", self.path / "summary.json",
                *(self.path / c for c in self.summary.get("updated_configs", [])))  # fmt: skip


def discrepancy(
    measured: str | Path,
    config: str | Path | Config,
    *overrides: str,
    output: str | Path = "report",
    budget: int | None = None,
    seed: int = 0,
    copies: int = 8,
    effects: Sequence[str] | None = None,
    candidates: Sequence[str] = (),
    alpha: float = 0.05,
    pairs: int = 3,
    power: bool = True,
    propose_next: bool = True,
    trajectories: str | Path | None = None,
    followup: str | Path | None = None,
    ignore_extra_columns: bool = False,
    workers: int | None = None,
    progress: bool = False,
    on_plan: Callable[[DiscrepancyPlan], None] | None = None,
) -> DiscrepancyReport:
    """Where the model disagrees with fibers measured past one pillar or through a pillar
    array, which effects explain it, and the gap left (``fibersweep discrepancy``); writes
    the report.

    With ``followup``, ``measured`` is analysed as without it (same seed, same
    verdict), then the two hypotheses the verdict leaves are tested on the
    follow-up fibers.

    Parameters
    ----------
    measured : str or Path
        Measured fibers (.parquet or .csv; ``docs/reference/columns.md``).
    config : str, Path or Config
        The model's config: one pillar in a channel, or a pillar array (``flow.array``:
        ``measured`` is then an array measured table, :mod:`fibersweep.discrepancy.array_schema`).
    *overrides : str
        ``KEY=VALUE`` settings.
    output : str or Path
        Report folder.
    budget : int, optional
        Most simulations in total.
    seed : int
        Random seed.
    copies : int
        Jittered baseline copies per fiber.
    effects : sequence of str, optional
        Library effects to consider [default: all].
    candidates : sequence of str
        Settings as candidate explanations: ``KEY=LO..HI`` (fitted), ``KEY=VALUE``, or a
        switch with its parameter; the config's ``discrepancy.candidates`` too.
    alpha : float
        Family-wise error rate.
    pairs : int
        Pairs of effects tried (0: single effects only).
    power : bool
        Power analysis when the verdict is no gap or unexplained.
    propose_next : bool
        Propose starts that separate two candidates when undecided.
    trajectories : str or Path, optional
        Measured tracks of every fiber (``docs/trajectories.md``).
    followup : str or Path, optional
        Fibers measured after a first analysis (same schema).
    ignore_extra_columns : bool
        Ignore columns the schema does not know.
    workers : int, optional
        Worker processes [default: ``run.workers``].
    progress : bool
        Show a progress bar over the simulations.
    on_plan : callable, optional
        Called with the :class:`DiscrepancyPlan` before anything runs.

    Returns
    -------
    DiscrepancyReport
    """
    from fibersweep.discrepancy.report import write_report
    from fibersweep.discrepancy.workflow import DiscrepancySettings, run_discrepancy
    from fibersweep.flow.cache import get_flow_field

    cfg = load_config(config, *overrides)
    data = load_measured_for(cfg, measured, trajectories, ignore_extra_columns)
    more = (
        load_measured_for(cfg, followup, ignore_extra=ignore_extra_columns)
        if followup is not None
        else None
    )
    declared = declared_candidates(cfg, candidates)
    # a pillar array: its noise model, and the library effects that act in it
    arr = array_settings_parts(cfg, effects, declared) if is_array(cfg) else {}
    settings = DiscrepancySettings(
        copies=copies, budget=budget, seed=seed, alpha=alpha, pairs=pairs,
        power_fibers=40 if power else 0, next_copies=2 if propose_next else 0,
        workers=workers or cfg.run.workers,
        executor=cfg.run.executor, scheduler=cfg.run.scheduler,
        **{"effects": tuple(effects) if effects else None, "declared": declared, **arr},
    )  # fmt: skip
    fields: list[str] = []
    if is_array(cfg):  # a unit cell costs seconds: solved first, its cost scales the plan's
        from fibersweep.discrepancy.array_workflow import field_plan

        field_, _ = get_flow_field(cfg.flow, cfg.run.cache_dir)
        fields = field_plan(declared, cfg.fiber, cfg.flow, cfg.run.cache_dir, field_.meta)
    plan = DiscrepancyPlan(len(data), settings, None if more is None else len(more), data.starts,
                           tuple(fields))  # fmt: skip
    if on_plan is not None:
        on_plan(plan)
    if not is_array(cfg):
        field_, _ = get_flow_field(cfg.flow, cfg.run.cache_dir)
    res = run_discrepancy(data, field_, cfg.fiber, settings, progress=progress, flow=cfg.flow,
                          cache_dir=cfg.run.cache_dir, followup=more)  # fmt: skip
    out = Path(output)
    summary = write_report(res, out, cfg.model_dump(mode="json"))
    log.info("discrepancy: %s (%d simulations) -> %s", summary["verdict"]["kind"],
             summary["simulations"], out)  # fmt: skip
    return DiscrepancyReport(res, summary, out)


# --------------------------------------------------------------------------- load
