"""What a sorter designer reads from an array sweep: migration vs length, critical lengths,
purity and recovery per outlet. Pure functions of the tables of the results store.

An array sweep is an ordinary ``fibersweep run`` with ``flow.array`` set: its
runs table (``runs/``, one row per run with the array columns), its
trajectories (``trajectories/``) and its manifest (each setting combination's
flow settings and U_center). :func:`fibersweep.results.load_array_results` reads them; the modes
are re-derived from the stored trajectories (:func:`relabel`), so other
thresholds can be applied without simulating again.

**f summaries leave trapped runs out.** A trapped fiber's ``fraction`` counts
only the rows it crossed before it stopped, and it leaves through no outlet; a
mean of f over every run would mix the two. Every summary here gives f over the
runs that were not trapped (``moving``) and, beside it, the share of runs that
were trapped (``trapped``): :func:`migration_table` per length, and
:func:`outlet_table`, whose recoveries over the outlets and the trapped share add
up to 1 for each length.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from fibersweep.analysis.modes import MODES, ModeSettings, summarise_rows
from fibersweep.errors import InputError

__all__ = [
    "LEVEL",
    "MIGRATION_DOCS",
    "with_settings",
    "MIN_PERIODS",
    "ShortRows",
    "check_edges",
    "CRITICAL_COLUMNS",
    "critical_lengths",
    "critical_table",
    "critical_text",
    "with_tracks",
    "located",
    "migration_table",
    "narrowing_lengths",
    "outlet_table",
    "parse_edges",
    "refine_lengths",
    "relabel",
    "short_rows",
    "thin_crossings",
]

#: Mean displacement fraction that defines a critical length.
LEVEL = 0.5


def with_tracks(runs: pd.DataFrame, traj: pd.DataFrame) -> pd.DataFrame:
    """``runs`` with each run's stored trajectory as list columns.

    Parameters
    ----------
    runs : DataFrame
        Array runs (``id`` ...), each with samples in ``traj``.
    traj : DataFrame
        Stored trajectory samples (``id``, ``t``, ``x``, ``y``, ``theta`` [deg],
        ``contact``, ``com_speed``, and ``beads`` for flexible fibers).

    Returns
    -------
    DataFrame
        ``runs`` (index reset) with ``traj_t`` [s], ``traj_xc``, ``traj_yc`` [µm],
        ``traj_th`` [rad], ``traj_contact`` (0/1), ``traj_speed`` [µm/s] and, with
        bead positions stored, ``traj_beads``.
    """
    runs = runs.copy()
    by_id = {rid: g for rid, g in traj.groupby("id", sort=False)}
    cols = {"traj_t": "t", "traj_xc": "x", "traj_yc": "y", "traj_speed": "com_speed"}
    for name, c in cols.items():
        runs[name] = [by_id[r][c].to_numpy(np.float64) for r in runs["id"]]
    runs["traj_th"] = [np.radians(by_id[r]["theta"].to_numpy(np.float64)) for r in runs["id"]]
    runs["traj_contact"] = [by_id[r]["contact"].to_numpy(np.float64) for r in runs["id"]]
    if "beads" in traj.columns:  # bead-spring runs with fiber.record.all_beads
        runs["traj_beads"] = [_beads(by_id[r]["beads"]) for r in runs["id"]]
    return runs.reset_index(drop=True)


def with_settings(runs: pd.DataFrame, manifest: dict) -> tuple[pd.DataFrame, list[dict]]:
    """``runs`` with ``setting`` (index, in the order of the swept values) and
    ``setting_label``, and the settings of :func:`load_array_results`."""
    combos = manifest.get("combinations") or {}
    settings = []
    sids = sorted(pd.unique(runs["settings"]), key=lambda sid: _order(combos.get(sid, {})))
    for sid in sids:
        entry = combos.get(sid, {})
        flow = entry.get("flow") or manifest["config"]["flow"]
        values = entry.get("values") or {}
        settings.append(
            {
                "id": sid,
                "label": ", ".join(_value_label(k, v) for k, v in values.items()),
                "values": values,
                "array": flow["array"],
                "flow": flow,
                "flow_key": entry.get("flow_key", ""),
                "u_center": entry.get("u_center_effective") or flow["fluid"]["u_center"],
            }
        )
    index = {s["id"]: i for i, s in enumerate(settings)}
    runs["setting"] = runs["settings"].map(index).astype(int)
    runs["setting_label"] = runs["setting"].map(lambda i: settings[i]["label"])
    return runs, settings


def _order(entry: dict) -> tuple:
    """Sort key of a setting combination: its swept values (numbers by value)."""
    vals = (entry.get("values") or {}).values()
    return tuple(
        (0, float(v), "") if isinstance(v, int | float) else (1, 0.0, str(v)) for v in vals
    )


def _value_label(key: str, value) -> str:
    """'young_modulus = 1e+06 Pa': the setting's last part, its value and unit."""
    from fibersweep.config import setting_column

    unit = setting_column(key)[1]
    text = f"{value:g}" if isinstance(value, int | float) else str(value)
    return f"{key.rsplit('.', 1)[-1]} = {text}{' ' + unit if unit else ''}"


def _beads(column: pd.Series) -> np.ndarray | None:
    """Stored bead positions of one run as (samples, n_beads, 2) [µm], or None."""
    rows = [np.asarray(v, dtype=np.float64) for v in column if v is not None]
    if len(rows) != len(column) or not rows or rows[0].size < 4:
        return None
    return np.stack(rows).reshape(len(rows), -1, 2)


def relabel(
    runs: pd.DataFrame, settings_meta: list[dict], modes: ModeSettings, trap_speed: float
) -> pd.DataFrame:
    """Runs with ``mode``, ``fraction``, ``shift_per_row``, ``migration_angle`` recomputed.

    ``trap_speed``: ``fiber.classify.trap_speed`` (a fraction of each setting's U_center).
    """
    import dataclasses

    out = runs.copy()
    for i, row in out.iterrows():
        meta = settings_meta[int(row["setting"])]
        arr = meta["array"]
        rule = dataclasses.replace(modes, trap_speed=trap_speed * meta["u_center"])
        traj = {
            c: np.asarray(row[f"traj_{c}"]) for c in ("t", "xc", "yc", "th", "contact", "speed")
        }
        summ = summarise_rows(traj, arr["period_x"], arr["shift"] * arr["period_y"], rule)
        out.at[i, "mode"] = summ.mode
        out.at[i, "fraction"] = summ.fraction
        out.at[i, "shift_per_row"] = summ.shift_per_row
        out.at[i, "migration_angle"] = summ.angle_deg
    return out


#: Meaning of the columns of :func:`migration_table` (its CSV and ``Results.fraction_summary``).
MIGRATION_DOCS = {
    "setting": "index of the setting combination (sort order of its swept values)",
    "setting_label": "the swept values of the setting combination (the array when none is swept)",
    "length": "fiber length L [µm]",
    "runs": "runs at this setting and length",
    "moving": "runs that were not trapped: the runs f and the angle are averaged over",
    "trapped": "share of the runs that were trapped (left out of f and the angle)",
    "angle_mean": "mean migration angle of the moving runs [deg]",
    "angle_std": "standard deviation of the migration angle of the moving runs [deg]",
    "fraction_mean": "mean displacement fraction f of the moving runs (1: follows the tilt)",
    "fraction_std": "standard deviation of f over the moving runs",
    "fraction_se": "standard error of the mean f (fraction_std / sqrt(moving))",
    **{m: f"share of the runs in mode {m}" for m in MODES if m != "trapped"},
}


def setting_name(setting: dict) -> str:
    """A setting combination's label (its swept values), or the array itself when
    nothing is swept (a setting of :func:`with_settings`)."""
    if setting["label"]:
        return setting["label"]
    a = setting["array"]
    return (f"the array: {a['pillar_shape']} {a['pillar_size']:g} µm, periods "
            f"{a['period_x']:g} x {a['period_y']:g} µm, shift {a['shift']:g}")  # fmt: skip


def migration_table(runs: pd.DataFrame, settings: list[dict] | None = None) -> pd.DataFrame:
    """Per (setting, length): the f summary (see the module docstring).

    ``settings`` (of :func:`with_settings`) names each combination in
    ``setting_label`` (:func:`setting_name`); without it the runs' own label.

    Returns
    -------
    DataFrame
        The columns of :data:`MIGRATION_DOCS`: runs, moving runs, trapped share, mean
        and spread of the migration angle [deg] and of the displacement fraction f over
        the moving runs, and the share of runs in each other mode.
    """
    rows = []
    for (s, L), g in runs.groupby(["setting", "length"], sort=True):
        moving = g[g["mode"] != "trapped"]
        n = len(moving)
        f_std = float(moving["fraction"].std(ddof=1)) if n > 1 else math.nan
        label = setting_name(settings[int(s)]) if settings else g["setting_label"].iloc[0]
        r = {
            "setting": s,
            "setting_label": label,
            "length": L,
            "runs": len(g),
            "moving": n,
            "trapped": float((g["mode"] == "trapped").mean()),
            "angle_mean": float(moving["migration_angle"].mean()) if n else math.nan,
            "angle_std": float(moving["migration_angle"].std(ddof=1)) if n > 1 else math.nan,
            "fraction_mean": float(moving["fraction"].mean()) if n else math.nan,
            "fraction_std": f_std,
            "fraction_se": f_std / math.sqrt(n) if n > 1 else math.nan,
        }
        for m in MODES:
            if m != "trapped":
                r[m] = float((g["mode"] == m).mean())
        rows.append(r)
    return pd.DataFrame(rows, columns=list(MIGRATION_DOCS))


def critical_table(table: pd.DataFrame, level: float = LEVEL) -> pd.DataFrame:
    """Every length where the mean fraction crosses ``level``, with its uncertainty.

    Between neighbouring lengths L_k < L_k+1 whose mean f lie on either side of
    ``level``, the crossing is interpolated linearly: L_c = L_k + w (L_k+1 − L_k),
    w = (level − f_k) / (f_k+1 − f_k). Its statistical error propagates the
    standard errors of the two means: σ = (L_k+1 − L_k) / |f_k+1 − f_k| ×
    sqrt((1 − w)² se_k² + w² se_k+1²). That error leaves out the interpolation
    between the simulated lengths, which near a sorter's step is most of it; the
    interval ``ci_lo``–``ci_hi`` holds both (:mod:`fibersweep.sorting.interval`:
    the posterior of a sigmoid through the runs around the crossing, at
    :data:`~fibersweep.sorting.interval.INTERVAL_LEVEL`). Whatever the
    interpolation, the crossing lies between the two simulated lengths (``lo``,
    ``hi``): the bracket a refinement halves.

    Parameters
    ----------
    table : DataFrame
        :func:`migration_table`.
    level : float
        The mean f that defines a critical length.

    Returns
    -------
    DataFrame
        ``setting``, ``critical`` [µm], ``se`` [µm] (the statistical error alone; NaN
        when a mean has one run), ``lo``, ``hi`` [µm] (the bracket), ``rising`` (f
        grows with L there), ``ci_lo``, ``ci_hi`` [µm] (the interval: scatter and
        interpolation; from the bracket and ``se`` alone when ``table`` has no
        ``moving`` and ``fraction_std`` columns).
    """
    from fibersweep.sorting.interval import bracket_draws, critical_draws, interval

    rows = []
    for s, g in table.groupby("setting"):
        g = g.sort_values("length")
        L = g["length"].to_numpy(float)
        f = g["fraction_mean"].to_numpy(float)
        se = g["fraction_se"].to_numpy(float)
        ok = np.isfinite(f)
        L, f, se = L[ok], f[ok], se[ok]
        for k in range(len(L) - 1):
            d0, d1 = f[k] - level, f[k + 1] - level
            if d0 * d1 >= 0:
                continue
            w = (level - f[k]) / (f[k + 1] - f[k])
            span = L[k + 1] - L[k]
            sig = span / abs(f[k + 1] - f[k]) * math.hypot((1 - w) * se[k], w * se[k + 1])
            rows.append(
                {
                    "setting": int(s),
                    "critical": float(L[k] + w * span),
                    "se": float(sig),
                    "lo": float(L[k]),
                    "hi": float(L[k + 1]),
                    "rising": bool(d1 > 0),
                }
            )
    for r in rows:
        if {"moving", "fraction_std"} <= set(table.columns):
            x = critical_draws(table, r["setting"], r["lo"], r["hi"], r["rising"], at=level)
        else:
            x = bracket_draws(r["lo"], r["hi"], r["se"], (r["setting"],))
        r["ci_lo"], r["ci_hi"] = interval(x)
    return pd.DataFrame(rows, columns=CRITICAL_COLUMNS)


#: Columns of :func:`critical_table`.
CRITICAL_COLUMNS = ["setting", "critical", "se", "lo", "hi", "rising", "ci_lo", "ci_hi"]


def critical_text(critical: float, ci_lo: float, ci_hi: float, level: float | None = None) -> str:
    """'22.3 µm (95 %: 20.2 to 23.9 µm)': a critical length and its interval
    (:func:`critical_table`); the value alone where the interval is NaN."""
    from fibersweep.sorting.interval import INTERVAL_LEVEL, level_text

    if not math.isfinite(critical):
        return "-"
    if not (math.isfinite(ci_lo) and math.isfinite(ci_hi)):
        return f"{critical:.1f} µm"
    lev = level_text(INTERVAL_LEVEL if level is None else level)
    return f"{critical:.1f} µm ({lev}: {ci_lo:.1f} to {ci_hi:.1f} µm)"


def thin_crossings(
    table: pd.DataFrame,
    crit: pd.DataFrame,
    settings: list[dict] | None = None,
    few: int | None = None,
) -> dict[int, list[str]]:
    """Per setting, the lengths that decide a crossing on fewer than ``few`` moving runs.

    A crossing is decided by the mean f at the two lengths of its bracket; one that
    rests on a few runs (most trapped) can move the crossing by a bracket, and the
    interval holds that only as far as those runs go. Each is named with its setting,
    its length and its count; a length inside a bracket whose runs were all trapped
    (no f, so the bracket spans it) is named too.

    Parameters
    ----------
    table : DataFrame
        :func:`migration_table`.
    crit : DataFrame
        :func:`critical_table` of ``table``.
    settings : list of dict, optional
        The settings, to name them (:func:`setting_name`).
    few : int, optional
        Fewest moving runs not named [default:
        :data:`~fibersweep.sorting.interval.FEW_MOVING`].

    Returns
    -------
    dict
        Setting -> lines, each once.
    """
    from fibersweep.sorting.interval import FEW_MOVING

    few = FEW_MOVING if few is None else few
    out: dict[int, list[str]] = {}
    for r in crit.itertuples():
        s = int(r.setting)
        name = setting_name(settings[s]) if settings else f"setting {s}"
        g = table[table["setting"] == s]
        lines = out.setdefault(s, [])
        for row in g.itertuples():
            L = float(row.length)
            trapped = int(round(row.trapped * row.runs))
            if L in (r.lo, r.hi) and row.moving < few:
                line = (
                    f"{name}: f at {L:g} µm rests on {row.moving} moving run"
                    f"{'' if row.moving == 1 else 's'} ({trapped} of {row.runs} trapped), and "
                    f"decides the crossing between {r.lo:g} and {r.hi:g} µm; more starts "
                    "there (sweep.random.count) would firm it up"
                )
            elif r.lo < L < r.hi and row.moving == 0:
                line = (
                    f"{name}: no f at {L:g} µm (all {row.runs} runs trapped), inside the "
                    f"bracket {r.lo:g} to {r.hi:g} µm, which spans it"
                )
            else:
                continue
            if line not in lines:
                lines.append(line)
    return {s: lines for s, lines in out.items() if lines}


def critical_lengths(table: pd.DataFrame, level: float = LEVEL) -> dict[int, list[float]]:
    """Per setting, the lengths [µm] where the mean fraction crosses ``level`` (linear in L)."""
    crit = critical_table(table, level)
    return {
        int(s): [float(c) for c in crit.loc[crit["setting"] == s, "critical"]]
        for s in sorted(table["setting"].unique())
    }


def refine_lengths(table: pd.DataFrame, level: float = LEVEL) -> dict[int, list[float]]:
    """Per setting, the midpoints [µm] of neighbouring lengths whose mean fraction brackets
    ``level``: the lengths to add to ``sweep.length`` to bisect the critical length.

    A pure function of :func:`migration_table` (trapped runs are out of its means).
    Running the same config with them added into the same folder runs only them: the
    draws of a length depend on it alone, so the other runs keep their ids.
    """
    out: dict[int, list[float]] = {}
    for s, g in table.groupby("setting"):
        g = g.sort_values("length")
        L = g["length"].to_numpy()
        d = g["fraction_mean"].to_numpy() - level
        out[int(s)] = [
            float(0.5 * (L[k] + L[k + 1]))
            for k in range(len(L) - 1)
            if np.isfinite(d[k] * d[k + 1]) and d[k] * d[k + 1] < 0
        ]
    return out


def located(lo: float, hi: float, bead: float) -> bool:
    """Whether a bracket of simulated lengths [µm] is one bead (2a) wide or less: the
    critical length is located as closely as lengths go (a fiber has round(L / 2a) beads)."""
    return hi - lo <= bead * (1 + 1e-9)


def narrowing_lengths(
    table: pd.DataFrame, crit: pd.DataFrame, bead: float, level: float = LEVEL
) -> dict[int, list[float]]:
    """Per setting, the lengths [µm] to add that halve a critical length's bracket wider
    than one bead: the midpoints of :func:`refine_lengths` that lie inside such a bracket.

    Parameters
    ----------
    table : DataFrame
        :func:`migration_table`.
    crit : DataFrame
        :func:`critical_table` of ``table``.
    bead : float
        Length of one bead, 2a [µm].
    """
    out: dict[int, list[float]] = {}
    for s, lengths in refine_lengths(table, level).items():
        c = crit[crit["setting"] == s]
        out[s] = [
            L for L in lengths
            if any(r.lo < L < r.hi and not located(r.lo, r.hi, bead) for r in c.itertuples())
        ]  # fmt: skip
    return out


#: Zigzag periods (1/ε rows each) a run should cross for its f to tell the modes apart.
MIN_PERIODS = 2.0


@dataclass(frozen=True)
class ShortRows:
    """A setting whose runs crossed too few rows for f to separate zigzag from displacement.

    A zigzagging fiber follows the tilt for 1/ε rows, then jumps back one column: its
    f averages to 0 only over whole periods of 1/ε rows; over one period it can read
    anything between 0 and 1.

    Attributes
    ----------
    setting : int
        Index into the settings.
    name : str
        The setting's name (:func:`setting_name`).
    rows : int
        Rows the runs crossed.
    shift : float
        The row shift ε.
    periods : float
        Zigzag periods in those rows, rows × ε.
    needed : int
        Rows that make :data:`MIN_PERIODS` periods.
    """

    setting: int
    name: str
    rows: int
    shift: float
    periods: float
    needed: int


def short_rows(settings: list[dict], rows: int) -> list[ShortRows]:
    """The settings whose ``rows`` rows are fewer than :data:`MIN_PERIODS` zigzag periods."""
    out = []
    for i, meta in enumerate(settings):
        eps = meta["array"]["shift"]
        if eps > 0 and rows * eps < MIN_PERIODS:
            out.append(ShortRows(i, setting_name(meta), rows, eps, rows * eps,
                                 math.ceil(MIN_PERIODS / eps)))  # fmt: skip
    return out


def parse_edges(outlets: str | float | Sequence[float]) -> list[float]:
    """Outlet edges from ``--outlets`` text (``"0.3,0.7"``) or numbers, checked and sorted
    (:func:`check_edges`).

    Raises
    ------
    InputError
        Naming ``--outlets``: not numbers, or an edge out of range or repeated.
    """
    if isinstance(outlets, str):
        try:
            edges = [float(e) for e in outlets.split(",") if e.strip()]
        except ValueError:
            raise InputError(f"--outlets: not a list of numbers: {outlets!r}") from None
    elif isinstance(outlets, int | float):
        edges = [float(outlets)]
    else:
        edges = [float(e) for e in outlets]
    return check_edges(edges)


def check_edges(edges: list[float]) -> list[float]:
    """Outlet edges, sorted: each strictly between 0 and 1, no two equal.

    Raises
    ------
    InputError
        Naming ``--outlets`` and the edge that is out of range or repeated.
    """
    for e in edges:
        if not (math.isfinite(e) and 0.0 < e < 1.0):
            raise InputError(
                f"--outlets: edge {e:g} is out of range; an edge is a fraction of the full "
                "displacement (0: straight on, 1: a shift of ε λy at every row), strictly "
                "between 0 and 1, e.g. --outlets 0.5 or --outlets 0.3,0.7"
            )
    if not edges:
        raise InputError("--outlets: give at least one edge between 0 and 1, e.g. 0.5")
    if len(set(edges)) != len(edges):
        raise InputError(f"--outlets: an edge is repeated in {edges}")
    return sorted(edges)


def outlet_table(runs: pd.DataFrame, settings_meta: list[dict], rows: int,
                 edges: list[float]) -> pd.DataFrame:  # fmt: skip
    """Purity and recovery per outlet of a device of ``rows`` rows, for each length.

    Every fiber enters at one point; it leaves at the lateral position
    rows × (its shift per row); a trapped fiber leaves nowhere. Outlets are
    the intervals between ``edges`` (:func:`check_edges`), given as fractions of
    the displacement mode's exit rows × ε λy (0: straight on, 1: fully displaced).
    Recovery of a length in an outlet: the share of that length's fibers that
    leave there; with the length's ``trapped`` share they add up to 1. Purity: the
    share of that outlet's fibers that have that length (equal numbers of each
    length fed); NaN when no fiber leaves through the outlet.

    Returns
    -------
    DataFrame
        ``setting``, ``outlet``, ``from``, ``to`` (edges, fractions of the full
        displacement), ``length`` [µm], ``recovery``, ``purity``, ``trapped``.
    """
    edges = check_edges(list(edges))
    bounds = [-math.inf, *edges, math.inf]
    out = []
    for s, g in runs.groupby("setting"):
        arr = settings_meta[int(s)]["array"]
        full = rows * arr["shift"] * arr["period_y"]
        exit_frac = rows * g["shift_per_row"] / full
        ok = g["mode"] != "trapped"
        counts = {}
        for L, gl in g.groupby("length"):
            e = exit_frac[gl.index][ok[gl.index]]
            counts[L] = [int(((e >= bounds[k]) & (e < bounds[k + 1])).sum())
                         for k in range(len(bounds) - 1)]  # fmt: skip
            counts[L].append(len(gl))
        trapped = {L: float((~ok[gl.index]).mean()) for L, gl in g.groupby("length")}
        for k in range(len(bounds) - 1):
            tot = sum(c[k] / c[-1] for c in counts.values())
            for L, c in counts.items():
                rec = c[k] / c[-1]
                pur = rec / tot if tot > 0 else math.nan
                out.append(
                    {"setting": int(s), "outlet": k, "from": bounds[k], "to": bounds[k + 1],
                     "length": L, "recovery": rec, "purity": pur, "trapped": trapped[L]}
                )  # fmt: skip
    return pd.DataFrame(out)
