"""The measured-fiber table: its schema, its validation and an atomic writer.

Schema (one row per measured fiber; Parquet ``.parquet`` or CSV ``.csv``)
------------------------------------------------------------------------
==========  ========  ==========================================================
column      required  meaning [unit]
==========  ========  ==========================================================
fiber_id    no        any unique label (default: the row number)
theta0      yes       start angle from +x, counter-clockwise [degrees]
y0          yes       start centre-of-mass lateral position from the base / h_obs
length      yes       fiber length / l_obs
angle_unit  no        'deg' (default) or 'rad' for every angle column, same in every row
==========  ========  ==========================================================

plus one column per observable of the registry
(:data:`fibersweep.discrepancy.observables.OBSERVABLES`, listed at the end of
this docstring with its unit, range and NaN rule). An observable derived from
other columns (``dwell`` = t_pass - t_contact) is computed here.

An optional observed column that is absent is simply not tested. An optional
column that is present must be complete: NaN is allowed only where the quantity
does not exist (``Observable.defined``: e.g. delta and t_pass for Trapping,
theta_c, y_c and t_contact without contact); a value given where it does not
exist is an error for the strict ones. Leave a column out entirely if it was
not measured.

Reading a table from disk, with its optional trajectories (their schema and
checks), is :func:`fibersweep.discrepancy.measured.load_measured`.

Validation never drops a row or a column: every problem raises
:class:`InputError` that names the column, the rule and the offending rows
(first few, 0-based). A column the schema does not know (a misspelled
``Delta`` or ``thetac``) is an error with a did-you-mean, unless the caller
asks to ignore extra columns (``discrepancy --ignore-extra-columns``).
Without an ``angle_unit`` column, every angle column is checked for radians:
theta0 when every |theta0| is below 0.2 with a non-zero spread (the source study's
±10° is ±0.17 rad); an angle observable (theta_c) when at least three values
are given and every one is at most π in size (contact angles in degrees spread
over tens of degrees); the trajectories' theta when their first samples match theta0
converted to radians far better than theta0 itself (:mod:`.measured`).
``angle_unit = 'deg'``
states degrees and turns the guess off.
"""

from __future__ import annotations

import difflib
import logging
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from fibersweep.atomic import atomic_path
from fibersweep.discrepancy.observables import OBSERVABLES, Observable, table_columns
from fibersweep.errors import InputError

__all__ = [
    "START_COLUMNS",
    "OBSERVED_COLUMNS",
    "MeasuredData",
    "read_table",
    "rows_text",
    "validate_measured",
    "write_table",
]

log = logging.getLogger(__name__)

START_COLUMNS = ("theta0", "y0", "length")
#: Observed columns of the schema (the registry's observables that are table columns).
OBSERVED_COLUMNS = table_columns()

# Plausible start ranges (inclusive; values outside point to a unit error) and unit hints.
# The observed columns' ranges and hints are in the observable registry.
_START_RANGES = {
    "theta0": ((-90.0, 90.0), "theta0 must be in degrees"),
    # the full channel spans about -5 .. 5.7 h_obs from the base
    "y0": ((-6.0, 7.0), "y0 must be in units of h_obs (divide µm by the pillar height)"),
    "length": (
        (0.05, 5.0),
        "length must be in units of l_obs (divide µm by the pillar base length)",
    ),
}
# Where a quantity does not exist, per condition of Observable.defined
_WITHOUT = {"not_trapped": "for Trapping", "contact": "without contact"}
_GIVEN = {"not_trapped": "for a Trapping fiber", "contact": "for a fiber without contact"}
_BOOL_LOOKUP = {"true": True, "false": False, "1": True, "0": False, "yes": True, "no": False}
_MAX_ROWS_SHOWN = 8


@dataclass(frozen=True)
class MeasuredData:
    """Validated measured fibers.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per fiber, columns ``fiber_id`` + START_COLUMNS + the observed
        columns present (+ the track observables with trajectories); angles in
        degrees, ``contact`` bool, ``class`` canonical.
    observed : tuple of str
        The observables present (always 'class'; 'dwell' when t_pass and
        t_contact are both given; the track observables with trajectories).
    trajectories : pandas.DataFrame or None
        Validated trajectory table, if given (channel frame, see the module docstring).
    source : str
        Where the data came from (for messages and the report).
    """

    table: pd.DataFrame
    observed: tuple[str, ...]
    trajectories: pd.DataFrame | None = None
    source: str = "measured"

    def __len__(self) -> int:
        return len(self.table)

    @property
    def starts(self) -> np.ndarray:
        """Measured starts, shape (n, 3): theta0 [deg], y0 [/h], length [/l_obs]."""
        return self.table[list(START_COLUMNS)].to_numpy(dtype=np.float64)


def rows_text(mask: np.ndarray | pd.Series) -> str:
    """'row 3' or 'rows 1, 4 and 2 more': data rows counted from 1, as a reader counts them.

    Row 1 is the first row of data (the line after a CSV's header).
    """
    idx = np.flatnonzero(np.asarray(mask)) + 1
    shown = ", ".join(str(i) for i in idx[:_MAX_ROWS_SHOWN])
    more = f" and {len(idx) - _MAX_ROWS_SHOWN} more" if len(idx) > _MAX_ROWS_SHOWN else ""
    return f"row{'s' if len(idx) > 1 else ''} {shown}{more}"


def read_table(path: Path) -> pd.DataFrame:
    """A ``.parquet`` or ``.csv`` table; InputError when unreadable or of another format."""
    suffix = path.suffix.lower()
    try:
        if suffix == ".parquet":
            return pd.read_parquet(path)
        if suffix == ".csv":
            return pd.read_csv(path)
    except (OSError, ValueError) as exc:
        raise InputError(f"{path}: cannot read table: {exc}") from None
    raise InputError(f"{path}: unknown table format '{suffix}'; use .parquet or .csv")


def _to_float(df: pd.DataFrame, col: str, problems: list[str]) -> np.ndarray | None:
    num = pd.to_numeric(df[col], errors="coerce")
    bad = num.isna() & df[col].notna()
    if bad.any():
        problems.append(f"{col}: not a number in {rows_text(bad)}")
        return None
    return num.to_numpy(dtype=np.float64)


def _to_bool(series: pd.Series, name: str, problems: list[str]) -> np.ndarray | None:
    if series.dtype == bool:
        return series.to_numpy()
    out = np.zeros(len(series), dtype=bool)
    bad = np.zeros(len(series), dtype=bool)
    for k, v in enumerate(series.tolist()):
        key = str(v).strip().lower()
        if isinstance(v, float) and math.isfinite(v) and v in (0.0, 1.0):
            out[k] = bool(v)
        elif key in _BOOL_LOOKUP:
            out[k] = _BOOL_LOOKUP[key]
        else:
            bad[k] = True
    if bad.any():
        problems.append(f"{name}: not a boolean (true/false/0/1) in {rows_text(bad)}")
        return None
    return out


def _looks_like_radians(col: str, v: np.ndarray) -> str | None:
    """Why the angle column ``col`` (values as given) looks like radians, or None."""
    finite = v[np.isfinite(v)]
    if len(finite) < 3 or not np.std(finite) > 0.0:
        return None
    biggest = float(np.max(np.abs(finite)))
    if col == "theta0" and biggest < 0.2:
        return f"every |theta0| is below 0.2 with a non-zero spread (max {biggest:.3g})"
    if col != "theta0" and biggest <= math.pi + 1e-9:
        return (
            f"all {len(finite)} {OBSERVABLES[col].angle}s lie within ±π "
            f"(max |{col}| {biggest:.3g}), while {OBSERVABLES[col].angle}s in degrees "
            "spread over tens of degrees"
        )
    return None


def _angles_to_degrees(df: pd.DataFrame, vals: dict[str, np.ndarray], problems: list[str]) -> None:
    """Convert radians if ``angle_unit`` says so; otherwise catch radians by their range."""
    angle_cols = ["theta0", *(n for n, o in OBSERVABLES.items() if o.angle and n in vals)]
    if "angle_unit" in df.columns:
        units = df["angle_unit"].astype(str).str.strip().str.lower()
        bad = ~units.isin(["deg", "rad"])
        if bad.any():
            problems.append(f"angle_unit: must be 'deg' or 'rad' in {rows_text(bad)}")
            return
        if units.nunique() > 1:
            problems.append("angle_unit: must be the same in every row (mixed 'deg' and 'rad')")
            return
        if units.iloc[0] == "rad":
            for c in angle_cols:
                vals[c] = np.degrees(vals[c])
            log.info("converted %s from radians (angle_unit column)", "/".join(angle_cols))
        return
    for c in angle_cols:
        why = _looks_like_radians(c, vals[c])
        if why:
            problems.append(
                f"{c}: {why}; these look like radians, but degrees are expected. Convert to "
                "degrees, or add a column angle_unit = 'rad' (or 'deg' if they are degrees)"
            )


def unknown_columns(columns: list[str], known: list[str] | None = None) -> list[str]:
    """One problem line per column the schema does not know, with a did-you-mean.

    ``known``: the schema's columns (default: the channel's measured table).
    """
    if known is None:
        known = ["fiber_id", "angle_unit", *START_COLUMNS, *table_columns()]
    lowered = {k.lower(): k for k in known}
    problems = []
    for c in columns:
        name = str(c)
        guess = lowered.get(name.strip().lower().replace("-", "_").replace(" ", "_"))
        if guess is None:
            close = difflib.get_close_matches(name.lower(), list(lowered), n=1, cutoff=0.6)
            guess = lowered[close[0]] if close else None
        hint = f"did you mean '{guess}'? " if guess else ""
        problems.append(f"{name}: unknown column; {hint}(known: {', '.join(known)})")
    if problems:
        problems.append(
            "leave out columns the tool does not use, or pass --ignore-extra-columns to ignore them"
        )
    return problems


def validate_measured(
    df: pd.DataFrame, source: str = "measured", ignore_extra: bool = False
) -> MeasuredData:
    """Check a measured-fiber table against the schema and canonicalise it.

    Parameters
    ----------
    df : pandas.DataFrame
        Raw table (see the module docstring for the schema).
    source : str
        Name used in messages.
    ignore_extra : bool
        Ignore columns the schema does not know (logged) instead of raising.

    Returns
    -------
    MeasuredData

    Raises
    ------
    InputError
        Listing every problem found, each naming the column and the rows.
    """
    problems: list[str] = []
    columns = table_columns()
    required = [*START_COLUMNS, *(c for c in columns if OBSERVABLES[c].required)]
    missing = [c for c in required if c not in df.columns]
    if missing:
        raise InputError(
            f"{source}: missing required column(s) {', '.join(missing)}; "
            f"the columns present are {', '.join(map(str, df.columns)) or '(none)'}"
        )
    known = {"fiber_id", "angle_unit", *START_COLUMNS, *columns}
    extra = [c for c in df.columns if c not in known]
    if extra and ignore_extra:
        log.warning("%s: ignoring extra columns %s", source, extra)
    elif extra:
        problems.extend(unknown_columns(extra))
    if len(df) == 0:
        raise InputError(f"{source}: the table has no rows")
    df = df.reset_index(drop=True)
    present = [OBSERVABLES[c] for c in columns if c in df.columns]

    vals: dict[str, np.ndarray] = {}
    for col in (*START_COLUMNS, *(o.name for o in present if o.kind == "continuous")):
        v = _to_float(df, col, problems)
        if v is not None:
            vals[col] = v
    if "theta0" in vals:
        _angles_to_degrees(df, vals, problems)
    labels = {o.name: _to_labels(df[o.name], o, problems) for o in present if o.kind == "class"}
    flags = {o.name: _to_bool(df[o.name], o.name, problems) for o in present if o.kind == "binary"}
    trapped = (labels["class"] == "Trapping").to_numpy()
    contact = flags.get("contact")

    for col, v in vals.items():
        _check_values(col, v, trapped, contact, problems)
    _check_consistency(labels["class"], contact, vals, trapped, problems)

    if "fiber_id" in df.columns:
        ids = df["fiber_id"].astype(str)
        dup = ids.duplicated(keep=False).to_numpy()
        if dup.any():
            problems.append(f"fiber_id: duplicated in {rows_text(dup)}")
    else:
        ids = pd.Series([str(i) for i in range(len(df))])

    if problems:
        head = f"{source}: {len(problems)} problem{'s' if len(problems) > 1 else ''}"
        raise InputError(head + "\n" + "\n".join(f"  - {p}" for p in problems))

    out = pd.DataFrame({"fiber_id": ids.to_numpy()})
    for col in START_COLUMNS:
        out[col] = vals[col]
    canonical = {**labels, **flags, **vals}
    observed = []
    for name, o in OBSERVABLES.items():  # registry order
        if name in canonical:
            out[name] = canonical[name]
        elif o.derive is not None and all(c in vals for c in o.derived_from):
            out[name] = o.derive(vals)  # e.g. dwell = t_pass - t_contact
        else:
            continue
        if o.scored:
            observed.append(name)
    return MeasuredData(table=out, observed=tuple(observed), source=source)


def _to_labels(series: pd.Series, o: Observable, problems: list[str]) -> pd.Series:
    """Canonical category names (case-insensitive match); NaN where unknown (reported)."""
    lookup = {c.lower(): c for c in o.categories}
    labels = series.astype(str).str.strip().str.lower().map(lookup)
    bad = labels.isna().to_numpy()
    if bad.any():
        problems.append(
            f"{o.name}: unknown value in {rows_text(bad)} "
            f"(e.g. {series[bad].iloc[0]!r}); valid: {', '.join(o.categories)}"
        )
    return labels


def _check_values(
    col: str,
    v: np.ndarray,
    trapped: np.ndarray,
    contact: np.ndarray | None,
    problems: list[str],
) -> None:
    """Finite, NaN only where the quantity does not exist, within the plausible range."""
    inf = np.isinf(v)
    if inf.any():
        problems.append(f"{col}: infinite value in {rows_text(inf)}")
    nan = np.isnan(v)
    if col in _START_RANGES:
        (lo, hi), hint = _START_RANGES[col]
        allowed, why, lower_open = np.zeros_like(nan), "a value is required", False
    else:
        o = OBSERVABLES[col]
        (lo, hi), hint, lower_open = o.bounds or (-np.inf, np.inf), o.unit_hint, o.lower_open
        defined = o.defined_mask(trapped, contact)
        # without a contact column NaN means 'no contact'
        allowed = ~defined if defined is not None else np.ones_like(nan)
        why = "a value is required"
        if o.defined:
            why = "NaN is allowed only " + " or ".join(_WITHOUT[c] for c in o.defined)
    bad_nan = nan & ~allowed
    if bad_nan.any():
        problems.append(
            f"{col}: missing/NaN value in {rows_text(bad_nan)} ({why}; "
            "leave the column out if it was not measured)"
        )
    below = (v <= lo) if lower_open else (v < lo)
    out = np.isfinite(v) & (below | (v > hi))
    if out.any():
        problems.append(
            f"{col}: out of range [{lo:g}, {hi:g}] in {rows_text(out)} "
            f"(e.g. {v[out][0]:.4g}); {hint}"
        )


def _check_consistency(
    classes: pd.Series,
    contact: np.ndarray | None,
    vals: dict[str, np.ndarray],
    trapped: np.ndarray,
    problems: list[str],
) -> None:
    """Rules between columns: contact of the contact classes, values given where undefined."""
    if contact is not None:
        must = (classes.isin(["Trapping", "Pole-vaulting"])).to_numpy() & ~contact
        if must.any():
            problems.append(
                f"contact: false for a Trapping or Pole-vaulting fiber in {rows_text(must)} "
                "(both classes require contact)"
            )
    for col, v in vals.items():
        o = OBSERVABLES.get(col)
        if o is None or not o.strict or not o.defined:
            continue
        defined = o.defined_mask(trapped, contact)
        if defined is not None:
            given = np.isfinite(v) & ~defined
            if given.any():
                where = " or ".join(_GIVEN[c] for c in o.defined)
                problems.append(f"{col}: given {where} in {rows_text(given)}")
    if "t_contact" in vals and "t_pass" in vals:
        late = np.isfinite(vals["t_contact"]) & np.isfinite(vals["t_pass"])
        late &= vals["t_contact"] > vals["t_pass"]
        if late.any():
            problems.append(f"t_contact: later than t_pass in {rows_text(late)}")


def write_table(df: pd.DataFrame, path: str | Path) -> Path:
    """Write a table atomically (temporary file + ``os.replace``); format from the suffix."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in (".parquet", ".csv"):
        raise InputError(f"{p}: unknown table format '{suffix}'; use .parquet or .csv")
    with atomic_path(p) as tmp:
        if suffix == ".parquet":
            df.to_parquet(tmp, index=False)
        else:
            df.to_csv(tmp, index=False)
    return p


def observed_columns_doc() -> str:
    """The registry's observed columns as a reStructuredText table (unit, range, NaN rule)."""
    without = {"not_trapped": "for Trapping", "contact": "without contact"}
    rows = []
    for name, o in OBSERVABLES.items():
        if o.geometry != "channel":  # the array's table: fibersweep.discrepancy.array_schema
            continue
        if o.derived_from or o.track:
            src = "from the trajectories" if o.track else "derived"
            rows.append((name, "-", f"{o.description} [{o.unit}], {src}"))
            continue
        if o.kind == "class":
            what = f"{o.description}: {', '.join(o.categories)} (case-insensitive)"
        elif o.kind == "binary":
            what = f"{o.description} (bool, 0/1, true/false)"
        else:
            lo, hi = o.bounds or (-math.inf, math.inf)
            what = f"{o.description} [{o.unit}] in {'(' if o.lower_open else '['}{lo:g}, {hi:g}]"
        if o.defined:
            what += "; NaN " + " or ".join(without[c] for c in o.defined)
        rows.append((name, "yes" if o.required else "no", what))
    rule = "==========  ========  " + "=" * 58
    lines = ["", "Observed columns (from the registry)", "-" * 36, rule]
    lines += ["column      required  meaning [unit]", rule]
    lines += [f"{n:<10}  {r:<8}  {w}" for n, r, w in rows]
    return "\n".join([*lines, rule, ""])


__doc__ = (__doc__ or "") + observed_columns_doc()
