"""Measured fibers of a fabricated array beside the model's f(L): pure functions of tables.

A sorter designer who has built the array measures fibers through it (one row per
fiber: its ``length`` [µm], its displacement fraction ``fraction`` and whether it
was ``trapped``; the array measured table of
:mod:`fibersweep.discrepancy.array_schema`) and asks whether the device sorts where
the model said. This module puts the two side by side, in the model's terms:

* **Length bins.** The fibers are binned by length: by default one bin per simulated
  length of the sweep, its edges halfway to the neighbouring lengths and half a
  spacing beyond the first (not below 0) and the last (:func:`length_edges`); or at
  edges the designer gives. Fibers outside the bins are counted and left out.
* **The measured f per bin** is the mean f of its fibers that were not trapped (as
  the model's f leaves its trapped runs out), at the mean length of those fibers.
  **Its error bar is a Wilson score interval** (:func:`wilson`) on that mean, taken
  as a share of the bin's moving fibers, at
  :data:`~fibersweep.sorting.interval.INTERVAL_LEVEL`. Why Wilson and not a
  bootstrap over the fibers: a measured f is nearly a yes/no per fiber (1 follows
  the tilt, 0 zigzags), and on a plateau the few fibers of a bin often all agree;
  a bootstrap of n equal values has zero width, while Wilson keeps the uncertainty
  of a share of n fibers (5 of 5 displaced: 0.57 to 1). For an f between 0 and 1
  that is not a yes/no (a mixed fiber) the share's variance p (1 − p) is the
  largest any value in [0, 1] with mean p can have, so the interval errs wide there.
  A mean f a little below 0 (zigzags read slightly negative) is kept inside its
  interval. The trapped share per bin gets the same interval (a yes/no by nature).
* **The measured critical length** (mean f = :data:`~fibersweep.sorting.report.LEVEL`)
  and its interval are the model's own: the bins enter
  :func:`fibersweep.sorting.report.critical_table` as a migration table of one
  setting (each bin a "length" with its moving fibers, mean and spread of f), so the
  interval holds the fibers' scatter and the interpolation between bins
  (:mod:`fibersweep.sorting.interval`). The error of each fiber's measured length
  is not in it: it moves fibers across bin edges, which widens the transition.
* **The model beside it**: per setting and bin, the model's runs whose simulated
  length lies in the bin, pooled (f over their moving runs, their trapped share).
* **Trapped share, measured against model**: over all binned fibers, and the
  model's at the same lengths (each bin's model share weighted by its measured
  fibers, so that a length mix unlike the sweep's does not show as a difference).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from dataclasses import field as attr
from statistics import NormalDist

import numpy as np
import pandas as pd

from fibersweep.errors import InputError
from fibersweep.sorting.interval import INTERVAL_LEVEL
from fibersweep.sorting.report import LEVEL, critical_table

__all__ = [
    "BIN_COLUMNS",
    "MEASURED_COLUMNS",
    "UNIT_LIMIT",
    "Measured",
    "check_measured",
    "compare",
    "length_edges",
    "measured_bins",
    "model_bins",
    "parse_length_edges",
    "trapped_summary",
    "wilson",
]

#: The columns of an array measured table this comparison reads.
MEASURED_COLUMNS = ("length", "fraction", "trapped")

#: Every length below this [µm] while the model's are not: they look like L / l_obs.
UNIT_LIMIT = 2.0

#: Columns of :func:`measured_bins`.
BIN_COLUMNS = [
    "bin", "from", "to", "length", "fibers", "moving", "trapped", "trapped_lo",
    "trapped_hi", "fraction_mean", "fraction_std", "fraction_se", "fraction_lo",
    "fraction_hi",
]  # fmt: skip


def wilson(p: np.ndarray | float, n: np.ndarray | float,
           level: float = INTERVAL_LEVEL) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Wilson score interval of a share ``p`` of ``n`` trials (module docstring).

    Parameters
    ----------
    p : array_like
        Observed share(s), clipped into [0, 1] (a mean f a little below 0 is a zigzag).
    n : array_like
        Trials (fibers); NaN bounds where ``n`` is 0.
    level : float
        Probability the interval holds.

    Returns
    -------
    lo, hi : ndarray
        The interval's ends, within [0, 1].
    """
    p = np.clip(np.asarray(p, float), 0.0, 1.0)
    n = np.asarray(n, float)
    z = NormalDist().inv_cdf(0.5 + 0.5 * level)
    with np.errstate(divide="ignore", invalid="ignore"):
        den = 1.0 + z * z / n
        mid = (p + z * z / (2.0 * n)) / den
        half = z / den * np.sqrt(p * (1.0 - p) / n + z * z / (4.0 * n * n))
        lo = np.where(n > 0, np.clip(mid - half, 0.0, 1.0), np.nan)
        hi = np.where(n > 0, np.clip(mid + half, 0.0, 1.0), np.nan)
    return lo, hi


def parse_length_edges(edges: str | Sequence[float]) -> np.ndarray:
    """Length bin edges [µm] from ``--edges`` text (``"4,10,14,30"``) or numbers.

    Raises
    ------
    InputError
        Naming ``--edges``: not numbers, fewer than two, or not strictly increasing.
    """
    try:
        parts = edges.split(",") if isinstance(edges, str) else list(edges)
        out = np.array([float(e) for e in parts if str(e).strip()], float)
    except ValueError:
        raise InputError(f"--edges: not a list of numbers: {edges!r}") from None
    if out.size < 2 or not np.all(np.isfinite(out)) or np.any(np.diff(out) <= 0):
        raise InputError(
            f"--edges: {edges!r}: give two or more length bin edges in µm, strictly "
            "increasing, e.g. --edges 2,10,14,18,30"
        )
    return out


def length_edges(lengths: Sequence[float]) -> np.ndarray:
    """One bin per simulated length [µm]: edges halfway between neighbours, and half a
    spacing beyond the first (not below 0) and the last (a single length: half a length
    each side).

    Returns
    -------
    ndarray
        (n_lengths + 1,) increasing edges [µm]; the outer two are the model's range.
    """
    L = np.unique(np.asarray(lengths, float))
    if L.size == 1:
        return np.array([0.5 * L[0], 1.5 * L[0]])
    mid = 0.5 * (L[1:] + L[:-1])
    first = max(L[0] - 0.5 * (L[1] - L[0]), 0.0)  # no length below 0
    return np.concatenate([[first], mid, [L[-1] + 0.5 * (L[-1] - L[-2])]])


def check_measured(measured: pd.DataFrame, model_lengths: Sequence[float]) -> pd.DataFrame:
    """The three columns of ``measured`` this comparison reads, checked against the model.

    Parameters
    ----------
    measured : DataFrame
        One row per measured fiber with ``length`` [µm], ``fraction`` [-] (NaN for a
        trapped fiber) and ``trapped`` (bool or 0/1).
    model_lengths : sequence of float
        The sweep's simulated lengths [µm].

    Returns
    -------
    DataFrame
        ``length`` (float), ``fraction`` (float), ``trapped`` (bool), the input's order.

    Raises
    ------
    InputError
        Naming the column: missing; not numbers; a fiber that is not trapped without
        an f; lengths that all look like L / l_obs fractions while the model's are in
        µm; no fiber inside the model's length range.
    """
    missing = [c for c in MEASURED_COLUMNS if c not in measured.columns]
    if missing:
        raise InputError(
            f"measured table: column {', '.join(missing)} missing; an array measured "
            f"table has one row per fiber with {', '.join(MEASURED_COLUMNS)} (length in "
            f"µm, fraction the displacement fraction f, trapped true/false); it has "
            f"{', '.join(map(str, measured.columns))}"
        )
    out = pd.DataFrame(index=measured.index)
    for c in ("length", "fraction"):
        num = pd.to_numeric(measured[c], errors="coerce")
        bad = num.isna() & measured[c].notna()
        if bad.any():
            raise InputError(f"measured table: {c}: not a number in rows {_rows(bad)}")
        out[c] = num.astype(float)
    trapped = measured["trapped"]
    if trapped.dtype != bool:
        key = trapped.astype(str).str.strip().str.lower()
        known = {"true": True, "false": False, "1": True, "0": False, "1.0": True, "0.0": False}
        bad = ~key.isin(list(known))
        if bad.any():
            raise InputError(
                f"measured table: trapped: not true/false (or 1/0) in rows {_rows(bad)}"
            )
        trapped = key.map(known)
    out["trapped"] = trapped.astype(bool)
    if out["length"].isna().any():
        raise InputError(f"measured table: length: missing in rows {_rows(out['length'].isna())}")
    no_f = ~out["trapped"] & out["fraction"].isna()
    if no_f.any():
        raise InputError(
            f"measured table: fraction: missing for a fiber that was not trapped, rows "
            f"{_rows(no_f)} (NaN is for trapped fibers only)"
        )
    model = np.asarray(model_lengths, float)
    if out["length"].max() < UNIT_LIMIT <= model.min():
        raise InputError(
            f"measured table: length: every length is below {UNIT_LIMIT:g} "
            f"({out['length'].min():.3g} to {out['length'].max():.3g}), while the model's "
            f"are {model.min():g} to {model.max():g} µm; they look like fractions L / l_obs "
            "(the single-pillar measured tables); give length in µm"
        )
    lo, hi = length_edges(model)[[0, -1]]
    inside = out["length"].between(lo, hi, inclusive="left")
    if not inside.any():
        raise InputError(
            f"measured table: length: no fiber inside the model's length range ({lo:g} to "
            f"{hi:g} µm: the simulated {model.min():g} to {model.max():g} µm and half a "
            f"spacing beyond); the measured lengths are {out['length'].min():g} to "
            f"{out['length'].max():g} µm. Sweep the measured lengths (sweep.length) and run "
            "the report again"
        )
    return out


def _rows(mask: pd.Series) -> str:
    """'3, 7, 12' (the first ten) of a mask's positions: data rows counted from 1 (row 1
    is the line after a CSV's header), as a reader counts them."""
    idx = np.flatnonzero(np.asarray(mask, bool)) + 1
    text = ", ".join(str(i) for i in idx[:10])
    return text + (f" and {idx.size - 10} more" if idx.size > 10 else "")


def measured_bins(measured: pd.DataFrame, edges: np.ndarray) -> pd.DataFrame:
    """Per length bin: the measured f with its Wilson interval and the trapped share.

    Parameters
    ----------
    measured : DataFrame
        :func:`check_measured`.
    edges : ndarray
        Increasing bin edges [µm]; a bin holds ``from <= length < to``.

    Returns
    -------
    DataFrame
        :data:`BIN_COLUMNS`, one row per bin with at least one fiber: ``length`` the
        mean length of its moving fibers [µm] (of all its fibers where all were
        trapped), ``fibers``, ``moving`` (not trapped), ``trapped`` share and its
        interval, ``fraction_mean``, ``fraction_std`` (NaN for one fiber),
        ``fraction_se`` and the interval ``fraction_lo``, ``fraction_hi`` (NaN where
        every fiber was trapped).
    """
    k = np.searchsorted(edges, measured["length"].to_numpy(float), side="right") - 1
    rows = []
    for b in range(len(edges) - 1):
        g = measured[k == b]
        if g.empty:
            continue
        moving = g[~g["trapped"]]
        n = len(moving)
        f = moving["fraction"].to_numpy(float)
        std = float(np.std(f, ddof=1)) if n > 1 else math.nan
        rows.append(
            {
                "bin": b, "from": float(edges[b]), "to": float(edges[b + 1]),
                "length": float((moving if n else g)["length"].mean()),
                "fibers": len(g), "moving": n, "trapped": float(g["trapped"].mean()),
                "fraction_mean": float(f.mean()) if n else math.nan,
                "fraction_std": std,
                "fraction_se": std / math.sqrt(n) if n > 1 else math.nan,
            }
        )  # fmt: skip
    out = pd.DataFrame(rows, columns=[c for c in BIN_COLUMNS if not c.endswith(("_lo", "_hi"))])
    out["trapped_lo"], out["trapped_hi"] = wilson(out["trapped"], out["fibers"])
    lo, hi = wilson(out["fraction_mean"], out["moving"])
    # a mean f a little outside [0, 1] (a zigzag reads slightly below 0) stays inside
    # its interval: the share's interval is widened to reach it
    out["fraction_lo"] = np.fmin(lo, out["fraction_mean"])
    out["fraction_hi"] = np.fmax(hi, out["fraction_mean"])
    out.loc[out["moving"] == 0, ["fraction_lo", "fraction_hi"]] = math.nan
    return out[BIN_COLUMNS]


def model_bins(table: pd.DataFrame, bins: pd.DataFrame) -> pd.DataFrame:
    """The model's runs per setting in each measured bin, pooled.

    Parameters
    ----------
    table : DataFrame
        :func:`fibersweep.sorting.report.migration_table` (per setting and simulated
        length: ``runs``, ``moving``, ``trapped``, ``fraction_mean``).
    bins : DataFrame
        :func:`measured_bins`.

    Returns
    -------
    DataFrame
        ``setting``, ``bin``, ``runs``, ``moving``, ``fraction_mean`` (over the moving
        runs of the simulated lengths in the bin; NaN where none) and ``trapped``
        (their share; NaN where the bin holds no simulated length).
    """
    rows = []
    spans = list(zip(bins["bin"], bins["from"], bins["to"], strict=True))
    for s, g in table.groupby("setting"):
        for b, lo, hi in spans:
            m = g[(g["length"] >= lo) & (g["length"] < hi)]
            runs, moving = int(m["runs"].sum()), int(m["moving"].sum())
            fsum = float((m["fraction_mean"].fillna(0.0) * m["moving"]).sum())
            rows.append(
                {
                    "setting": int(s), "bin": int(b), "runs": runs, "moving": moving,
                    "fraction_mean": fsum / moving if moving else math.nan,
                    "trapped": float((m["trapped"] * m["runs"]).sum() / runs) if runs else math.nan,
                }
            )  # fmt: skip
    return pd.DataFrame(rows, columns=["setting", "bin", "runs", "moving", "fraction_mean",
                                       "trapped"])  # fmt: skip


@dataclass(frozen=True)
class TrappedShare:
    """The trapped share over the binned fibers, measured and modelled.

    Attributes
    ----------
    trapped, fibers : int
        Measured fibers trapped, and binned.
    share, lo, hi : float
        Their share and its Wilson interval.
    model : dict
        Setting -> the model's share at the measured lengths (each bin's model share
        weighted by the bin's measured fibers; bins without simulated runs left out).
    """

    trapped: int
    fibers: int
    share: float
    lo: float
    hi: float
    model: dict[int, float]


def trapped_summary(bins: pd.DataFrame, model: pd.DataFrame) -> TrappedShare:
    """Trapped share over all binned fibers and the model's at the same lengths."""
    n = int(bins["fibers"].sum())
    k = int(round(float((bins["trapped"] * bins["fibers"]).sum())))
    lo, hi = wilson(k / n, n)
    per = {}
    w = bins.set_index("bin")["fibers"]
    for s, g in model.groupby("setting"):
        g = g[np.isfinite(g["trapped"].to_numpy(float))]
        ww = w.loc[g["bin"]].to_numpy(float)
        per[int(s)] = (
            float((g["trapped"].to_numpy(float) * ww).sum() / ww.sum()) if ww.sum() else math.nan
        )
    return TrappedShare(k, n, k / n, float(lo), float(hi), per)


@dataclass(frozen=True)
class Measured:
    """A measured table beside the model's curve (:func:`compare`).

    Attributes
    ----------
    bins : DataFrame
        :func:`measured_bins`.
    critical : DataFrame
        The measured critical lengths: :func:`fibersweep.sorting.report.critical_table`
        of the bins (``setting`` 0), with their interval.
    model : DataFrame
        :func:`model_bins`.
    trapped : TrappedShare
    fibers : int
        Fibers in the table.
    outside : int
        Fibers outside the bins (left out).
    edges : ndarray
        The bin edges [µm].
    given_edges : bool
        The edges were given (``--edges``), not the sweep's lengths.
    level : float
        The mean f that defines a critical length.
    """

    bins: pd.DataFrame = attr(repr=False)
    critical: pd.DataFrame = attr(repr=False)
    model: pd.DataFrame = attr(repr=False)
    trapped: TrappedShare
    fibers: int
    outside: int
    edges: np.ndarray = attr(repr=False)
    given_edges: bool = False
    level: float = LEVEL

    @property
    def binned(self) -> int:
        """Fibers inside the bins."""
        return self.fibers - self.outside

    def table(self) -> pd.DataFrame:
        """Bins and the model's pooled runs, one row per bin (``measured.csv``):
        the bin columns, then ``model_fraction_<s>``, ``model_trapped_<s>``,
        ``model_runs_<s>`` per setting s."""
        out = self.bins.copy()
        for s, g in self.model.groupby("setting"):
            g = g.set_index("bin").loc[out["bin"]]
            for c in ("fraction_mean", "trapped", "runs"):
                name = "fraction" if c == "fraction_mean" else c
                out[f"model_{name}_{int(s)}"] = g[c].to_numpy()
        return out


def compare(
    measured: pd.DataFrame,
    table: pd.DataFrame,
    edges: str | Sequence[float] | None = None,
    level: float = LEVEL,
) -> Measured:
    """A measured table beside the model's migration table (module docstring).

    Parameters
    ----------
    measured : DataFrame
        One row per measured fiber (``length`` [µm], ``fraction``, ``trapped``).
    table : DataFrame
        The model's :func:`fibersweep.sorting.report.migration_table`.
    edges : str or sequence of float, optional
        Length bin edges [µm] [default: one bin per simulated length,
        :func:`length_edges`].
    level : float
        The mean f that defines a critical length.

    Returns
    -------
    Measured

    Raises
    ------
    InputError
        :func:`check_measured`'s, :func:`parse_length_edges`'s, and no fiber inside
        the given edges.
    """
    lengths = sorted(table["length"].unique())
    m = check_measured(measured, lengths)
    given = edges is not None
    e = parse_length_edges(edges) if given else length_edges(lengths)
    inside = m["length"].between(e[0], e[-1], inclusive="left")
    if not inside.any():
        raise InputError(
            f"--edges: no measured fiber between {e[0]:g} and {e[-1]:g} µm (the measured "
            f"lengths are {m['length'].min():g} to {m['length'].max():g} µm)"
        )
    bins = measured_bins(m[inside], e)
    crit = critical_table(bins.assign(setting=0), level)
    model = model_bins(table, bins)
    return Measured(
        bins=bins, critical=crit, model=model, trapped=trapped_summary(bins, model),
        fibers=len(m), outside=int((~inside).sum()), edges=e, given_edges=given, level=level,
    )  # fmt: skip
