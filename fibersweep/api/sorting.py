"""Re-labelling a results folder (``fibersweep classify``) and the sort report of an array sweep."""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from dataclasses import field as attr
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # annotations only: the API imports what it runs when it runs it
    import pandas as pd

    from fibersweep.config import Config
    from fibersweep.config.fiber import ClassifySettings
    from fibersweep.sorting.design import GroupAnswer
    from fibersweep.sorting.measured import Measured
    from fibersweep.sorting.report import ShortRows

from fibersweep.api.common import load_config

log = logging.getLogger("fibersweep.api")


@dataclass(frozen=True)
class Classified:
    """What :func:`classify` did to a results folder.

    Attributes
    ----------
    path : Path
        The results folder.
    thresholds : ClassifySettings
        The thresholds and rule applied.
    array : bool
        Pillar-array runs (their modes were re-derived with the trap rule).
    n_runs, n_changed : int
        Runs re-labelled, and how many changed.
    counts : DataFrame
        Runs per class (or mode) per swept combination; written to ``counts_path``.
    counts_path : Path
    warnings : tuple of str
    simulated_trap_time : float or None
        The trap time the runs were simulated with [s] (a run trapped then stopped).
    trapped : int
        Pillar-array runs now trapped.
    """

    path: Path
    thresholds: ClassifySettings
    array: bool
    n_runs: int
    n_changed: int
    counts: pd.DataFrame = attr(repr=False)
    counts_path: Path = attr(repr=False)
    warnings: tuple[str, ...] = ()
    simulated_trap_time: float | None = None
    trapped: int = 0

    @property
    def beyond_simulated(self) -> bool:
        """Whether a longer trap time than the runs' own is asked where some run is
        trapped: a run stopped by its own trap rule cannot tell whether it would have
        moved on."""
        ran = self.simulated_trap_time
        return ran is not None and self.thresholds.trap_time > ran and self.trapped > 0


def classify(
    results: str | Path,
    config: str | Path | Config | None = None,
    *,
    head_blocked_speed: float | None = None,
    trap_time: float | None = None,
    trap_speed: float | None = None,
    rule: str | None = None,
    pivot_fraction: float | None = None,
) -> Classified:
    """Re-classify stored trajectories with new thresholds or rule, no simulation
    (``fibersweep classify``).

    The runs table gets one class column per rule (``class_head_speed``,
    ``class_pivot``, ``class_switch``); ``class`` is the chosen rule's. A pillar
    array's runs get their modes re-derived with the trap rule (``trap_time``,
    ``trap_speed``).

    Parameters
    ----------
    results : str or Path
        Output folder of a sweep (rewritten atomically, under its lock).
    config : str, Path or Config, optional
        Take the thresholds from this config's ``fiber.classify`` [default: the sweep's].
    head_blocked_speed : float, optional
        Head blocked below this fraction of U_center.
    trap_time : float, optional
        In contact and stopped this long [s] -> Trapping.
    trap_speed : float, optional
        'Stopped': centre-of-mass speed below this fraction of U_center.
    rule : str, optional
        Pole-vaulting rule: ``switch``, ``head-speed``, ``pivot`` or ``corner``.
    pivot_fraction : float, optional
        ``pivot`` rule: head travel below this fraction of L while turning.

    Returns
    -------
    Classified

    Raises
    ------
    InputError
        No results there, a bad threshold, or a channel-only option (``rule``,
        ``pivot_fraction``, ``head_blocked_speed``) on pillar-array runs.
    """
    from fibersweep.errors import InputError
    from fibersweep.sweep.manifest import read_manifest
    from fibersweep.sweep.reclassify import reclassify, thresholds_for

    results = Path(results)
    base = load_config(config).fiber.classify if config is not None else None
    man = read_manifest(results) or {}
    run_cfg = man.get("config") or {}
    array = (run_cfg.get("flow") or {}).get("array") is not None
    channel_only = {"--rule": rule, "--pivot-fraction": pivot_fraction,
                    "--head-blocked-speed": head_blocked_speed}  # fmt: skip
    given = [k for k, v in channel_only.items() if v is not None]
    if array and given:
        raise InputError(
            f"{', '.join(given)}: pillar-array runs have modes, not a channel's classes; "
            "classify re-derives their trap rule (--trap-time, --trap-speed), and "
            "sort-report's --zigzag-max and --displacement-min set the other modes"
        )
    th = thresholds_for(
        results, base, head_blocked_speed=head_blocked_speed, trap_time=trap_time,
        trap_speed=trap_speed, rule=rule, pivot_fraction=pivot_fraction,
    )  # fmt: skip
    res = reclassify(results, th)
    is_modes = "mode" in res.counts.columns  # a pillar array: modes
    ran = trapped = None
    if is_modes:
        # the thresholds the runs were simulated with (a re-labelling rewrites the config's)
        simulated = man.get("simulated_classify") or (run_cfg.get("fiber") or {}).get("classify")
        ran = (simulated or {}).get("trap_time")
        counts = res.counts
        trapped = int(counts.loc[counts["mode"] == "trapped", "runs"].sum())
    log.info("re-labelled %d runs (%d changed) with %s", res.n_runs, res.n_changed, th)
    return Classified(
        path=results, thresholds=th, array=is_modes, n_runs=res.n_runs,
        n_changed=res.n_changed, counts=res.counts, counts_path=res.counts_path,
        warnings=tuple(res.warnings), simulated_trap_time=None if ran is None else float(ran),
        trapped=trapped or 0,
    )  # fmt: skip


# --------------------------------------------------------------------------- sort report


@dataclass(frozen=True)
class SortReport:
    """A sorter designer's page of an array sweep (:func:`sort_report`).

    Attributes
    ----------
    path : Path
        The results folder.
    runs : DataFrame
        The array runs, modes re-derived with the report's thresholds, with their
        ``setting`` and thinned trajectories (:func:`fibersweep.results.load_array_results`).
    settings : list of dict
        Per setting combination: ``id``, ``label``, ``values``, ``array``, ``flow``...
    config : dict
        The sweep's stored config.
    migration : DataFrame
        Per setting and length: f and the migration angle over the runs that were not
        trapped, the trapped share, the modes (``migration.csv``;
        :data:`fibersweep.sorting.report.MIGRATION_DOCS`).
    critical : DataFrame
        Every length where the mean f crosses 1/2, with its statistical error, its
        interval (scatter and interpolation, ``ci_lo``, ``ci_hi``) and its bracket [µm]
        (:func:`fibersweep.sorting.report.critical_table`).
    outlets : DataFrame
        Recovery and purity per outlet and length of a ``rows``-row device
        (``outlets.csv``).
    rows : int
        Rows of the device.
    array_rows : int
        Rows the runs crossed (``fiber.array_rows``).
    bead : float
        One bead's length, 2a [µm].
    narrowing : dict
        Setting -> lengths [µm] to add that halve a critical length's bracket wider
        than one bead.
    short : tuple of ShortRows
        Settings whose runs crossed too few rows for f to tell zigzag from displacement.
    key : str or None
        The swept setting the critical length is read against (None: none swept).
    curve : DataFrame or None
        The critical length against ``key`` (``critical.csv``).
    target : float or None
        The critical length asked for [µm].
    separate : tuple of float or None
        The two lengths to separate [µm] (the target is halfway).
    answers : tuple of GroupAnswer
        Per group of the other swept values: the value of ``key`` that gives the target.
    tables : tuple of Path
        The CSV files written.
    figures : tuple of Path
        The figures written.
    notes : tuple of str
        What the figures left out.
    warnings : tuple of str
        Where the sweep's settings (or ``rows``) leave the validated range, each naming
        the setting to change and its source page (:mod:`fibersweep.sweep.validity`).
    caveats : dict
        Setting -> the lengths that decide its critical lengths on few moving runs,
        named with their counts (:func:`fibersweep.sorting.report.thin_crossings`).
    measured : Measured or None
        A measured table beside the model (``measured``): f and the trapped share per
        length bin with their intervals, the measured critical length, the model's runs
        per bin (``measured.csv``; :mod:`fibersweep.sorting.measured`).
    """

    path: Path
    runs: pd.DataFrame = attr(repr=False)
    settings: list[dict] = attr(repr=False)
    config: dict = attr(repr=False)
    migration: pd.DataFrame = attr(repr=False)
    critical: pd.DataFrame = attr(repr=False)
    outlets: pd.DataFrame = attr(repr=False)
    rows: int
    array_rows: int
    bead: float
    narrowing: dict[int, list[float]]
    short: tuple[ShortRows, ...]
    key: str | None = None
    curve: pd.DataFrame | None = None
    target: float | None = None
    separate: tuple[float, float] | None = None
    answers: tuple[GroupAnswer, ...] = ()
    tables: tuple[Path, ...] = ()
    figures: tuple[Path, ...] = ()
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()
    caveats: dict[int, list[str]] = attr(default_factory=dict)
    measured: Measured | None = None


def sort_report(
    results: str | Path,
    *,
    rows: int | None = None,
    outlets: str | float | Sequence[float] = 0.5,
    target_length: float | None = None,
    separate: str | Sequence[float] | None = None,
    setting: str | None = None,
    figures: bool = True,
    zigzag_max: float = 0.25,
    displacement_min: float = 0.75,
    write: bool = True,
    measured: str | Path | pd.DataFrame | None = None,
    edges: str | Sequence[float] | None = None,
) -> SortReport:
    """A sorter designer's page: critical lengths, outlets, and the array setting to
    choose (``fibersweep sort-report``).

    Per setting and fiber length: the displacement fraction f and migration angle
    over the runs that were not trapped, the trapped share and the modes; the
    critical lengths (mean f = 1/2) with their interval (the runs' scatter and the
    interpolation between simulated lengths, :mod:`fibersweep.sorting.interval`),
    and the lengths that decide them on few moving runs; recovery and purity per
    outlet of a device of ``rows`` rows. With a swept array setting: the critical
    length against it, and with ``target_length`` or ``separate``, the value that
    gives it, its interval and the runs to add to be sure. Where the settings leave
    the validated range, ``warnings`` say so. With a ``measured`` table of fibers
    through the fabricated array: its f and trapped share per length bin beside the
    model's, and its critical length beside the model's
    (:mod:`fibersweep.sorting.measured`).

    Parameters
    ----------
    results : str or Path
        Output folder of an array sweep.
    rows : int, optional
        Rows of the device [default: ``fiber.array_rows``].
    outlets : str, float or sequence of float
        Outlet edges, each a fraction of the full displacement strictly between 0 and
        1 (0: straight on, 1: the tilt at every row); text as ``"0.3,0.7"``.
    target_length : float, optional
        Critical length wanted [µm].
    separate : str or pair of float, optional
        Two lengths to separate, ``"L1,L2"`` [µm]: the target is halfway between them.
    setting : str, optional
        The swept setting to read the critical length against [default: the first
        swept array setting].
    figures : bool
        Write the figures (``RESULTS/figures/``).
    zigzag_max : float
        Mode rule: |f| below this is zigzag.
    displacement_min : float
        Mode rule: f above this is displacement.
    write : bool
        Write the tables (``RESULTS/migration.csv``, ``outlets.csv``, ``critical.csv``,
        and with ``measured``, ``measured.csv``).
    measured : str, Path or DataFrame, optional
        An array measured table (Parquet or CSV, read by
        :func:`fibersweep.discrepancy.array_schema.load_array_measured`), or its
        DataFrame: one row per measured fiber with ``length`` [µm], ``fraction`` and
        ``trapped``.
    edges : str or sequence of float, optional
        Length bin edges of the measured fibers [µm], ``"4,10,14,30"`` [default: one bin
        per simulated length].

    Returns
    -------
    SortReport
    """
    from fibersweep.analysis.modes import ModeSettings
    from fibersweep.config.fiber import ARRAY_ROWS
    from fibersweep.errors import InputError
    from fibersweep.results import load_array_results
    from fibersweep.sorting import design as sd
    from fibersweep.sorting import report as sr
    from fibersweep.sweep.validity import facts_from_dict, warnings_for

    results = Path(results)
    out_edges = sr.parse_edges(outlets)
    target = sd.target_length(target_length, separate)
    if edges is not None:  # checked before the runs are read
        from fibersweep.sorting.measured import parse_length_edges

        if measured is None:
            raise InputError("--edges: bins the measured fibers; give a table with --measured")
        edges = parse_length_edges(edges)
    fibers = None if measured is None else _measured_table(measured)
    runs, settings, cfg = load_array_results(results)
    modes = ModeSettings(zigzag_max=zigzag_max, displacement_min=displacement_min)
    runs = sr.relabel(runs, settings, modes, cfg["fiber"]["classify"]["trap_speed"])
    key = sd.report_key(settings, setting, target)
    array_rows = int(cfg["fiber"].get("array_rows", ARRAY_ROWS))
    n_rows = rows or cfg["fiber"].get("array_rows", ARRAY_ROWS)
    table = sr.migration_table(runs, settings)
    crit = sr.critical_table(table)
    bead = 2.0 * cfg["fiber"]["bead_radius"]
    out = sr.outlet_table(runs, settings, n_rows, out_edges)
    written = []
    if write:
        written = [results / "migration.csv", results / "outlets.csv"]
        table.to_csv(written[0], index=False)
        out.to_csv(written[1], index=False)
    meas = None
    if fibers is not None:
        from fibersweep.sorting.measured import compare

        meas = compare(fibers, table, edges)
        if write:
            meas.table().to_csv(results / "measured.csv", index=False)
            written.append(results / "measured.csv")
    curve, found = None, []
    thin = sr.thin_crossings(table, crit, settings)
    if key is not None:
        curve = sd.critical_curve(crit, table, settings, key)
        if target is not None:
            found = sd.answers(curve, settings, key, target, bead, table=table, caveats=thin)
        if write:
            curve.to_csv(results / "critical.csv", index=False)
            written.append(results / "critical.csv")
    pair = None
    if separate is not None:
        parts = separate.split(",") if isinstance(separate, str) else separate
        pair = (float(parts[0]), float(parts[1]))
    combos = [
        facts_from_dict(cfg["fiber"], s["array"], s["values"], s["label"],
                        device_rows=rows, trapped=int((g["mode"] == "trapped").sum()),
                        runs=len(g))
        for i, s in enumerate(settings) for g in [runs[runs["setting"] == i]]
    ]  # fmt: skip
    warned = warnings_for(combos)
    for w in warned:
        log.info("outside the validated range: %s", w)
    report = SortReport(
        path=results, runs=runs, settings=settings, config=cfg, migration=table,
        critical=crit, outlets=out, rows=n_rows, array_rows=array_rows, bead=bead,
        narrowing=sr.narrowing_lengths(table, crit, bead),
        short=tuple(sr.short_rows(settings, array_rows)), key=key, curve=curve,
        target=target, separate=pair, answers=tuple(found), tables=tuple(written),
        warnings=warned, caveats=thin, measured=meas,
    )  # fmt: skip
    if figures:
        drawn, notes = _sort_figures(report)
        from dataclasses import replace

        report = replace(report, figures=tuple(drawn), notes=tuple(notes))
    return report


def _measured_table(measured: str | Path | pd.DataFrame) -> pd.DataFrame:
    """The measured fibers: a DataFrame as given, or read from a Parquet or CSV file.

    Either way only ``length``, ``fraction`` and ``trapped`` are read and checked
    (:func:`fibersweep.sorting.measured.check_measured`): the starts, which the
    discrepancy workflow needs, are not used here.
    """
    import pandas as pd

    if isinstance(measured, pd.DataFrame):
        return measured
    from fibersweep.discrepancy.schema import read_table

    return read_table(Path(measured))


def _slug(values: dict) -> str:
    """File-name part of a setting combination: 'shift=0.1_young_modulus=1e+04'."""
    import re

    parts = [
        f"{k.rsplit('.', 1)[-1]}={v:g}"
        if isinstance(v, int | float)
        else f"{k.rsplit('.', 1)[-1]}={v}"
        for k, v in values.items()
    ]
    return re.sub(r"[^A-Za-z0-9_.=+-]", "_", "_".join(parts))


#: Most settings drawn in one chronophotograph (one panel each).
MAX_PANELS = 6


def _sort_figures(rep: SortReport) -> tuple[list[Path], list[str]]:
    """The sort report's figures, into ``RESULTS/figures/``; and what they left out."""
    from fibersweep.analysis.modes import MODES
    from fibersweep.config.flow import FlowSettings
    from fibersweep.flow.cache import get_flow_field
    from fibersweep.plots import array as pa
    from fibersweep.plots import array_design as pd_
    from fibersweep.plots.labels import describe
    from fibersweep.plots.shapes import ShapeNotStored
    from fibersweep.plots.style import paper_style, save_figure
    from fibersweep.sorting.modes import pick_run

    settings, runs, cfg = rep.settings, rep.runs, rep.config
    fig_dir = rep.path / "figures"
    written, notes = [], []
    with paper_style():
        arrays, shifts, periods, drawn = {}, {}, {}, set()
        for i, s in enumerate(settings):
            # the sweep's cell field, from the cache (solved again if it was removed)
            flow = FlowSettings.model_validate(s["flow"])
            field_, _ = get_flow_field(flow, cfg["run"]["cache_dir"])
            arrays[i] = field_.array
            shifts[i] = field_.array.lateral_shift
            periods[i] = field_.array.period_x
            if s["flow_key"] in drawn:  # settings that share a flow share its figure
                continue
            drawn.add(s["flow_key"])
            flow_values = {k: v for k, v in s["values"].items() if k.startswith("flow.")}
            name = f"cell-flow-{_slug(flow_values)}.png" if flow_values else "cell-flow.png"
            written.append(save_figure(pa.cell_flow_figure(field_), fig_dir / name, dpi=110))
        tilts = {i: math.degrees(math.atan(s["array"]["shift"])) for i, s in enumerate(settings)}
        labels = describe(settings)  # in words with units: "E = 10 kPa"
        written.append(
            save_figure(
                pd_.migration_figure(
                    rep.migration, tilts, labels, rep.critical, measured=rep.measured
                ),
                fig_dir / "migration.png",
            )  # fmt: skip
        )
        written.append(save_figure(pd_.outlets_figure(rep.outlets, labels),
                                   fig_dir / "outlets.png"))  # fmt: skip
        written.append(
            save_figure(
                pa.overlay_figure(runs, periods, shifts=shifts, labels=labels),
                fig_dir / "sort-tracks.png",
                dpi=130,
            )
        )
        shown = list(range(len(settings)))
        if len(shown) > MAX_PANELS:
            shown = [
                shown[round(k * (len(shown) - 1) / (MAX_PANELS - 1))] for k in range(MAX_PANELS)
            ]
            notes.append(f"chronophotographs show {MAX_PANELS} of the {len(settings)} settings")
        for mode in MODES:
            picks = [(i, pick_run(runs[runs["setting"] == i], mode)) for i in shown]
            picks = [(i, {**p, "setting_label": labels[i]}) for i, p in picks if p is not None]
            if not picks:
                continue
            try:
                fig = pa.chrono_figure(
                    None,
                    [p for _, p in picks],
                    cfg["fiber"]["bead_radius"],
                    arrays=[arrays[i] for i, _ in picks],
                )
            except ShapeNotStored as exc:
                notes.append(f"no chronophotograph of the {mode} runs: {exc}")
                continue
            written.append(save_figure(fig, fig_dir / f"chrono-{mode}.png", dpi=130))
        if rep.curve is not None:
            from fibersweep.config import setting_column

            key = rep.key
            ans = rep.answers[-1].answer if rep.answers else None
            unit = setting_column(key)[1]
            fig = pd_.critical_figure(rep.curve, key, unit, ans, rep.target, rep.critical)
            written.append(save_figure(fig, fig_dir / f"critical-{key.rsplit('.', 1)[-1]}.png"))
    for n in notes:
        log.info("sort report: %s", n)
    return written, notes


# --------------------------------------------------------------------------- discrepancy
