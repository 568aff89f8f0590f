"""The array measured table: fibers measured through a pillar array, validated.

Schema (one row per measured fiber; Parquet ``.parquet`` or CSV ``.csv``)
------------------------------------------------------------------------
==========  ========  ==========================================================
column      required  meaning [unit]
==========  ========  ==========================================================
fiber_id    no        unique integer label (default: the row number)
theta0      yes       start angle from +x, counter-clockwise [deg], in [-90, 90]
y0          yes       start lateral position as a fraction of period_y, in [0, 1]
length      yes       fiber length [µm], in (0, 10000]
fraction    yes       displacement fraction f [-] (1 displaced every row, 0 zigzag),
                      in [-1, 2]; NaN exactly for a trapped fiber
trapped     yes       whether the fiber stopped on a pillar (bool, 0/1, true/false)
mode        no        zigzag, displacement, wrap-and-jump, trapped or mixed
                      (case-insensitive); 'trapped' exactly for a trapped fiber
rows_first  no        rows crossed before the first displacement or jump [-], an
                      integer >= 0; NaN when there was none (validated, not compared)
outlet      no        outlet reached [-], an integer (validated, not compared)
bend        no        1 - smallest end-to-end distance / contour length [-], in
                      [0, 1]; NaN for a fiber not imaged for it
==========  ========  ==========================================================

These are the starts as array sweeps use them (``fibersweep run`` on a config
with ``flow.array``) and the columns of an array sweep's runs table of the same
name (``fraction``, ``mode``). The compared columns are the registry's array
observables (:mod:`.array_observables`); ``rows_first`` and ``outlet`` are checked
and kept but not yet compared.

Validation never drops a row or a column: every problem raises
:class:`~fibersweep.errors.InputError` that names the column, the rule and the
offending rows (data rows counted from 1). A column the schema does not know is
an error with a did-you-mean unless ``ignore_extra``.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pandas as pd

from fibersweep.analysis.modes import MODES
from fibersweep.discrepancy.observables import OBSERVABLES, scored
from fibersweep.discrepancy.schema import MeasuredData, read_table, rows_text, unknown_columns
from fibersweep.errors import InputError

__all__ = [
    "ARRAY_COLUMNS",
    "ARRAY_START_COLUMNS",
    "array_measured_data",
    "load_array_measured",
    "validate_array_measured",
]

log = logging.getLogger(__name__)

#: The starts of an array fiber: theta0 [deg], y0 [fraction of period_y], length [µm].
ARRAY_START_COLUMNS = ("theta0", "y0", "length")
_REQUIRED = (*ARRAY_START_COLUMNS, "fraction", "trapped")
_OPTIONAL = ("mode", "rows_first", "outlet", "bend")
#: Every column an array measured table may have, in order.
ARRAY_COLUMNS = ("fiber_id", *_REQUIRED, *_OPTIONAL)

_START_RANGES = {
    "theta0": ((-90.0, 90.0), False, "theta0 must be in degrees"),
    "y0": ((0.0, 1.0), False, "y0 must be a fraction of period_y (divide µm by period_y)"),
    "length": ((0.0, 1.0e4), True, "length must be in µm in a pillar array"),
}
_BOOL = {"true": True, "false": False, "1": True, "0": False, "yes": True, "no": False,
         "1.0": True, "0.0": False}  # fmt: skip


def _floats(df: pd.DataFrame, col: str, problems: list[str]) -> np.ndarray | None:
    num = pd.to_numeric(df[col], errors="coerce")
    bad = (num.isna() & df[col].notna()).to_numpy()
    if bad.any():
        problems.append(f"{col}: not a number in {rows_text(bad)}")
        return None
    v = num.to_numpy(dtype=np.float64)
    inf = np.isinf(v)
    if inf.any():
        problems.append(f"{col}: infinite value in {rows_text(inf)}")
    return v


def _range(col: str, v: np.ndarray, lo: float, hi: float, lower_open: bool, hint: str,
           problems: list[str]) -> None:  # fmt: skip
    below = (v <= lo) if lower_open else (v < lo)
    out = np.isfinite(v) & (below | (v > hi))
    if out.any():
        problems.append(
            f"{col}: out of range {'(' if lower_open else '['}{lo:g}, {hi:g}] in "
            f"{rows_text(out)} (e.g. {v[out][0]:.4g}); {hint}"
        )


def _bools(series: pd.Series, problems: list[str]) -> np.ndarray | None:
    if series.dtype == bool:
        return series.to_numpy()
    keys = series.astype(str).str.strip().str.lower()
    bad = ~keys.isin(list(_BOOL))
    if bad.any():
        problems.append(f"trapped: not a boolean (true/false/0/1) in {rows_text(bad.to_numpy())}")
        return None
    return keys.map(_BOOL).to_numpy(dtype=bool)


def _integers(col: str, v: np.ndarray, lo: float | None, problems: list[str]) -> None:
    fin = np.isfinite(v)
    frac = fin & (v != np.round(v))
    if frac.any():
        problems.append(f"{col}: not a whole number in {rows_text(frac)} (e.g. {v[frac][0]:g})")
    if lo is not None and (fin & (v < lo)).any():
        problems.append(f"{col}: below {lo:g} in {rows_text(fin & (v < lo))}")


def _unknown(columns: list[str]) -> list[str]:
    return unknown_columns(columns, list(ARRAY_COLUMNS))


def validate_array_measured(
    df: pd.DataFrame, source: str = "measured", ignore_extra: bool = False
) -> pd.DataFrame:
    """Check an array measured table against the schema and canonicalise it.

    Parameters
    ----------
    df : pandas.DataFrame
        Raw table, one row per fiber (see the module docstring).
    source : str
        Name used in messages (e.g. the file).
    ignore_extra : bool
        Ignore (and log) columns the schema does not know instead of raising.

    Returns
    -------
    pandas.DataFrame
        Index 0..n-1; ``fiber_id`` (int64), theta0 [deg], y0 [fraction of
        period_y], length [µm], fraction [-] (float64, NaN for trapped), trapped
        (bool), then the optional columns present: mode (canonical label),
        rows_first and outlet (float64: NaN allowed), bend [-].

    Raises
    ------
    InputError
        Listing every problem found, each naming the column, the rule and the rows.
    """
    missing = [c for c in _REQUIRED if c not in df.columns]
    if missing:
        hints = [h for h in _unknown([c for c in df.columns if c not in ARRAY_COLUMNS])
                 if "did you mean" in h]  # fmt: skip
        channel = [c for c in df.columns if c in OBSERVABLES and OBSERVABLES[c].geometry != "array"]
        if channel:
            hints.append(
                f"{', '.join(map(str, channel))}: the single-pillar channel's observables; a "
                "pillar array config compares fibers measured through the array"
            )
        raise InputError(
            f"{source}: missing required column(s) {', '.join(missing)} of an array measured "
            f"table; the columns present are {', '.join(map(str, df.columns)) or '(none)'}"
            + "".join(f"\n  {h}" for h in hints)
        )
    if len(df) == 0:
        raise InputError(f"{source}: the table has no rows")
    problems: list[str] = []
    extra = [c for c in df.columns if c not in ARRAY_COLUMNS]
    if extra and ignore_extra:
        log.warning("%s: ignoring extra columns %s", source, extra)
    elif extra:
        problems.extend(_unknown(extra))
    df = df.reset_index(drop=True)
    vals: dict[str, np.ndarray] = {}
    for col in (*ARRAY_START_COLUMNS, "fraction", *(c for c in _OPTIONAL[1:] if c in df)):
        v = _floats(df, col, problems)
        if v is not None:
            vals[col] = v
    trapped = _bools(df["trapped"], problems)
    for col, ((lo, hi), lower_open, hint) in _START_RANGES.items():
        if col in vals:
            nan = np.isnan(vals[col])
            if nan.any():
                problems.append(f"{col}: missing/NaN value in {rows_text(nan)} (a start is needed)")
            _range(col, vals[col], lo, hi, lower_open, hint, problems)
    for col in ("fraction", "bend"):
        if col in vals:
            o = OBSERVABLES[col]
            _range(col, vals[col], *o.bounds, o.lower_open, o.unit_hint, problems)
    if "rows_first" in vals:
        _integers("rows_first", vals["rows_first"], 0.0, problems)
    if "outlet" in vals:
        _integers("outlet", vals["outlet"], None, problems)
        nan = np.isnan(vals["outlet"]) & ~(trapped if trapped is not None else False)
        if nan.any():
            problems.append(f"outlet: missing/NaN value in {rows_text(nan)} (NaN only if trapped)")
    if trapped is not None and "fraction" in vals:
        f = vals["fraction"]
        if (bad := np.isnan(f) & ~trapped).any():
            problems.append(
                f"fraction: missing/NaN value in {rows_text(bad)} (NaN is allowed only for a "
                "trapped fiber; leave the fiber out if it was not measured)"
            )
        if (bad := np.isfinite(f) & trapped).any():
            problems.append(f"fraction: given for a trapped fiber in {rows_text(bad)} (NaN there)")
    modes = None
    if "mode" in df.columns:
        lookup = {m.lower(): m for m in MODES}
        modes = df["mode"].astype(str).str.strip().str.lower().map(lookup)
        bad = modes.isna().to_numpy()
        if bad.any():
            problems.append(
                f"mode: unknown value in {rows_text(bad)} (e.g. {df['mode'][bad].iloc[0]!r}); "
                f"valid: {', '.join(MODES)}"
            )
        elif trapped is not None:
            odd = (modes.to_numpy() == "trapped") != trapped
            if odd.any():
                problems.append(
                    f"mode: 'trapped' must go with trapped = true and only with it, not so in "
                    f"{rows_text(odd)}"
                )
    if "fiber_id" in df.columns:
        num = pd.to_numeric(df["fiber_id"], errors="coerce")
        bad = (num.isna() | (num != np.round(num))).to_numpy()
        if bad.any():
            problems.append(f"fiber_id: not an integer in {rows_text(bad)}")
        dup = df["fiber_id"].astype(str).duplicated(keep=False).to_numpy()
        if dup.any():
            problems.append(f"fiber_id: duplicated in {rows_text(dup)}")
        ids = None if bad.any() else num.to_numpy().astype(np.int64)
    else:
        ids = np.arange(len(df), dtype=np.int64)
    if problems:
        head = f"{source}: {len(problems)} problem{'s' if len(problems) > 1 else ''}"
        raise InputError(head + "\n" + "\n".join(f"  - {p}" for p in problems))
    out = pd.DataFrame({"fiber_id": ids})
    for col in (*ARRAY_START_COLUMNS, "fraction"):
        out[col] = vals[col]
    out["trapped"] = trapped
    if modes is not None:
        out["mode"] = modes.to_numpy(dtype=object)
    for col in _OPTIONAL[1:]:
        if col in vals:
            out[col] = vals[col]
    return out


def load_array_measured(path: str | Path, ignore_extra: bool = False) -> pd.DataFrame:
    """Read (``.parquet`` or ``.csv``) and validate an array measured table.

    See :func:`validate_array_measured` for the returned frame and the errors.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: no such measured table")
    return validate_array_measured(read_table(p), source=str(p), ignore_extra=ignore_extra)


def array_measured_data(table: pd.DataFrame, source: str = "measured") -> MeasuredData:
    """A validated array table as the workflow's :class:`~.schema.MeasuredData`.

    ``observed`` lists the array observables present (registry order); ``fiber_id``
    becomes a string label as in the channel's table.
    """
    out = table.copy()
    out["fiber_id"] = out["fiber_id"].astype(str)
    observed = tuple(n for n in scored(geometry="array") if n in out.columns)
    if "bend" in observed and not np.isfinite(out["bend"].to_numpy(dtype=float)).any():
        observed = tuple(n for n in observed if n != "bend")  # a column of NaN compares nothing
    return MeasuredData(table=out, observed=observed, source=source)
