"""The inverse question of a sorter design: which array setting gives a critical length.

A sweep over an array setting (``flow.array.shift``, a period, the pillar size or
shape) gives a critical length per value (:func:`fibersweep.sorting.report.critical_table`).
:func:`critical_curve` lays them out against the setting with their uncertainty;
:func:`answer` reads the curve backwards: for a target critical length, the value
of the setting that gives it, by linear interpolation between the two simulated
values whose critical lengths bracket the target, with

* its interval at :data:`~fibersweep.sorting.interval.INTERVAL_LEVEL`: the runs'
  scatter, the interpolation between simulated lengths and the interpolation
  between simulated values (:mod:`fibersweep.sorting.interval`, where the choice is
  argued; its coverage is measured in ``tests/unit/test_design_coverage.py``), and
  apart, the statistical error alone (the critical lengths' standard errors,
  propagated), which leaves the interpolation out;
* the lengths that decide it on few moving runs (fewer than
  :data:`~fibersweep.sorting.interval.FEW_MOVING`), named
  (:func:`fibersweep.sorting.report.thin_crossings`);
* whether the simulated lengths decide it whatever the interpolation: each
  critical length lies between two simulated lengths, so when neither bracket
  holds the target the answer lies between the two values;
* the values the lattice allows (a row shift ε λy and the periods must be whole
  numbers of cells), and the runs to add to be sure: the answered value itself,
  and where a critical length's bracket is wider than one bead, the lengths that
  bisect it (:func:`fibersweep.sorting.report.refine_lengths`).

A categorical setting (the pillar shape) is not interpolated: the answer is the
simulated value whose critical length is nearest the target. Pure functions of
the tables; nothing is simulated here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from fibersweep.sorting.interval import INTERVAL_LEVEL

__all__ = [
    "ARRAY_KEYS",
    "DesignAnswer",
    "GroupAnswer",
    "answer",
    "answers",
    "critical_curve",
    "curve_draws",
    "design_key",
    "lattice_neighbours",
    "lattice_pick",
    "report_key",
    "swept_keys",
    "target_length",
]

#: Array settings a designer sweeps; any other swept numeric setting is taken too.
ARRAY_KEYS = (
    "flow.array.shift",
    "flow.array.period_x",
    "flow.array.period_y",
    "flow.array.pillar_size",
    "flow.array.pillar_shape",
    "flow.array.pillar_rotation",
)


def swept_keys(settings: list[dict]) -> list[str]:
    """Swept keys whose value differs between the setting combinations (sweep order)."""
    keys: list[str] = []
    for s in settings:
        for k in s.get("values") or {}:
            if k not in keys:
                keys.append(k)
    return [k for k in keys if len({repr((s.get("values") or {}).get(k)) for s in settings}) > 1]


def design_key(settings: list[dict], key: str | None = None) -> str | None:
    """The swept setting the critical length is read against, or None when none varies.

    ``key`` names it (it must vary); otherwise the first swept array setting, else the
    first swept setting.

    Raises
    ------
    InputError
        ``key`` is not a swept setting of these results (the valid ones listed).
    """
    from fibersweep.errors import InputError

    keys = swept_keys(settings)
    if key is not None:
        if key not in keys:
            raise InputError(
                f"--setting {key!r}: not a swept setting of these results; valid: "
                + (", ".join(keys) or "none (one setting combination)")
            )
        return key
    array = [k for k in keys if k in ARRAY_KEYS]
    return (array or keys or [None])[0]


def report_key(settings: list[dict], key: str | None, target: float | None) -> str | None:
    """:func:`design_key`, and an error when a target is asked of results that sweep no setting.

    Raises
    ------
    InputError
        ``key`` is not a swept setting, or ``target`` is given and no setting is swept.
    """
    from fibersweep.errors import InputError

    found = design_key(settings, key)
    if found is None and target is not None:
        raise InputError(
            "--target-length/--separate: these results sweep no array setting, so there is "
            "nothing to choose; sweep one, e.g. 'sweep.flow.array.shift=[0.05, 0.1, 0.15, 0.2]' "
            "(docs/arrays.md, 'Design: a target critical length')"
        )
    return found


def target_length(target: float | None, separate: str | Sequence[float] | None) -> float | None:
    """The critical length asked for [µm]: ``target``, or halfway between the two lengths
    of ``separate`` (``"L1,L2"`` or a pair of numbers [µm]); at most one of them given.

    Raises
    ------
    InputError
        Both given, a target that is not a length > 0, or ``separate`` not two different
        lengths > 0 (named as the options ``--target-length`` and ``--separate``).
    """
    from fibersweep.errors import InputError

    if target is not None and separate is not None:
        raise InputError("--target-length and --separate: give one of them")
    if separate is not None:
        try:
            parts = separate.split(",") if isinstance(separate, str) else list(separate)
            pair = [float(v) for v in parts]
        except (TypeError, ValueError):
            pair = []
        if (
            len(pair) != 2
            or not all(math.isfinite(v) and v > 0 for v in pair)
            or pair[0] == pair[1]
        ):
            shown = separate if isinstance(separate, str) else ",".join(map(str, separate))
            raise InputError(f"--separate {shown!r}: expected two different lengths L1,L2 [µm]")
        return 0.5 * (pair[0] + pair[1])
    if target is not None and not (math.isfinite(target) and target > 0):
        raise InputError(f"--target-length {target}: expected a length > 0 [µm]")
    return target


def critical_curve(
    crit: pd.DataFrame, table: pd.DataFrame, settings: list[dict], key: str
) -> pd.DataFrame:
    """The critical length of each setting combination against ``key``.

    The first length where f rises through 1/2 (the lower edge of a high-pass or
    band-pass sorter); where f never rises through 1/2, the first where it falls
    through it (a low-pass sorter, or a band's upper edge alone in the swept lengths).

    Parameters
    ----------
    crit : DataFrame
        :func:`fibersweep.sorting.report.critical_table`.
    table : DataFrame
        :func:`fibersweep.sorting.report.migration_table` (for the combinations
        without a crossing: is f above or below 1/2 at every length?).
    settings : list of dict
        The settings of :func:`fibersweep.results.load_array_results`.
    key : str
        The swept setting (:func:`design_key`).

    Returns
    -------
    DataFrame
        One row per combination: ``setting``, ``value`` (of ``key``), ``group`` (the
        other swept values, '' when only ``key`` varies), ``critical``, ``se``, ``lo``,
        ``hi`` [µm], ``rising`` (f rises through 1/2 there; None without a crossing),
        ``ci_lo``, ``ci_hi`` [µm] (the interval of :func:`critical_table`).
        Without a crossing ``critical`` is NaN, and ``lo`` is the longest length when
        f < 1/2 at every length, ``hi`` the shortest when f > 1/2 at every length.
    """
    others = [k for k in swept_keys(settings) if k != key]
    rows = []
    for i, s in enumerate(settings):
        vals = s.get("values") or {}
        mine = crit[crit["setting"] == i]
        c = mine[mine["rising"].eq(True).fillna(False).to_numpy(bool)]
        c = c if len(c) else mine  # no rising crossing: the first falling one
        row = {
            "setting": i,
            "value": vals.get(key),
            "group": ", ".join(f"{k.rsplit('.', 1)[-1]} = {vals.get(k)}" for k in others),
            "rising": None,
        }
        if len(c):
            r = c.iloc[0]
            row.update(critical=r["critical"], se=r["se"], lo=r["lo"], hi=r["hi"],
                       rising=bool(r["rising"]), ci_lo=r.get("ci_lo", math.nan),
                       ci_hi=r.get("ci_hi", math.nan))  # fmt: skip
        else:
            g = table[table["setting"] == i].sort_values("length")
            f = g["fraction_mean"].to_numpy(float)
            below = bool(np.nanmax(f) < 0.5) if np.isfinite(f).any() else False
            row.update(
                critical=math.nan,
                se=math.nan,
                lo=float(g["length"].max()) if below else math.nan,
                hi=math.nan if below else float(g["length"].min()),
                ci_lo=math.nan,
                ci_hi=math.nan,
            )
        rows.append(row)
    columns = ["setting", "value", "group", "critical", "se", "lo", "hi", "rising", "ci_lo",
               "ci_hi"]  # fmt: skip
    return pd.DataFrame(rows, columns=columns)


def lattice_neighbours(key: str, value: float, flow: dict) -> tuple[float, float]:
    """The nearest values of ``key`` at or below and at or above ``value`` that the
    lattice allows (ε λy and the periods whole numbers of cells of ``flow['dx']``).

    A setting the sub-grid wall resolves at any value (pillar size, rotation) is
    returned as it is.
    """
    from fibersweep.config.array import ArraySettings
    from fibersweep.geometry.array import ArrayError

    name = key.rsplit(".", 1)[-1]
    dx = float(flow["dx"])
    arr = dict(flow["array"])
    if name == "shift":
        step = dx / float(arr["period_y"])
    elif name in ("period_x", "period_y"):
        step = dx
    else:
        return value, value

    def valid(v: float) -> bool:
        try:
            ArraySettings.model_validate({**arr, name: v}).to_array().check_lattice(dx)
        except (ArrayError, ValueError):
            return False
        return True

    base = value / step
    lo = next(
        (
            round(k * step, 12)
            for k in range(math.floor(base + 1e-9), -1, -1)
            if valid(round(k * step, 12))
        ),
        math.nan,
    )
    hi = next(
        (
            round(k * step, 12)
            for k in range(math.ceil(base - 1e-9), math.ceil(base) + 200)
            if valid(round(k * step, 12))
        ),
        math.nan,
    )
    return lo, hi


@dataclass(frozen=True)
class DesignAnswer:
    """Which value of a swept setting gives a target critical length.

    Attributes
    ----------
    key : str
        The setting.
    target : float
        Target critical length [µm].
    value : float or str or None
        The answer (interpolated; for a categorical setting the nearest simulated one);
        None when the target is outside the simulated critical lengths.
    se : float
        Statistical error of ``value`` alone: the critical lengths' standard errors
        propagated through the two linear interpolations (NaN when not interpolated).
        It leaves out the interpolation between simulated lengths and values; ``ci``
        holds it.
    span : tuple of float
        The two simulated values the answer lies between whatever the interpolation:
        the brackets of their critical lengths lie on either side of the target (NaN
        when a bracket holds the target: the simulated lengths do not decide yet).
    between : tuple
        The two simulated values it was interpolated between (or the nearest ones).
    lattice : tuple of float
        Nearest values the lattice allows, at or below and at or above ``value``.
    text : str
        The answer in one sentence, with its interval and its level.
    add : list of str
        What to run to be sure.
    ci : tuple of float
        The interval of ``value`` at ``level``: the runs' scatter, the interpolation
        between simulated lengths and between simulated values
        (:func:`fibersweep.sorting.interval.inverse_draws`); an end ±inf lies beyond
        the simulated values. NaN when not interpolated.
    level : float
        The probability ``ci`` holds (:data:`~fibersweep.sorting.interval.INTERVAL_LEVEL`).
    caveats : tuple of str
        Lengths that decide the answer's critical lengths on few moving runs, each
        with its setting and count (:func:`fibersweep.sorting.report.thin_crossings`).
    """

    key: str
    target: float
    value: float | str | None
    se: float = math.nan
    span: tuple[float, float] = (math.nan, math.nan)
    between: tuple = ()
    lattice: tuple[float, float] = (math.nan, math.nan)
    text: str = ""
    add: list[str] = field(default_factory=list)
    ci: tuple[float, float] = (math.nan, math.nan)
    level: float = INTERVAL_LEVEL
    caveats: tuple[str, ...] = ()


def _interp(v0: float, v1: float, c0: float, c1: float, target: float) -> float:
    return v0 + (target - c0) / (c1 - c0) * (v1 - v0)


def curve_draws(curve: pd.DataFrame, table: pd.DataFrame | None = None) -> dict[int, np.ndarray]:
    """Draws of each setting's critical length [µm] (the curve's crossing), by setting.

    With the migration table: from the posterior of
    :func:`fibersweep.sorting.interval.critical_draws`;
    without it (a curve read back from ``critical.csv``): uniform over the bracket
    plus the statistical error (:func:`~fibersweep.sorting.interval.bracket_draws`).
    Combinations without a crossing have none.
    """
    from fibersweep.sorting.interval import bracket_draws, critical_draws

    runs = table is not None and {"moving", "fraction_std"} <= set(table.columns)
    out: dict[int, np.ndarray] = {}
    for r in curve.itertuples():
        if not math.isfinite(r.critical):
            continue
        rising = True if getattr(r, "rising", None) is None else bool(r.rising)
        if runs:
            out[int(r.setting)] = critical_draws(table, int(r.setting), r.lo, r.hi, rising)
        else:
            out[int(r.setting)] = bracket_draws(r.lo, r.hi, r.se, (int(r.setting),))
    return out


def _num(v: float) -> str:
    return f"{v:.4g}"


def _value_interval(name: str, ci: tuple[float, float], values: np.ndarray, level: float) -> str:
    """'95 % interval: shift = 0.1187 to 0.1352' (an infinite end: beyond the simulated)."""
    from fibersweep.sorting.interval import level_text

    lo, hi = ci
    left = f"below {values.min():g}, the smallest simulated" if lo == -math.inf else _num(lo)
    right = f"beyond {values.max():g}, the largest simulated" if hi == math.inf else _num(hi)
    return f"{level_text(level)} interval: {name} = {left} to {right}"


def _crit(lc: float, lo: float, hi: float, level: float) -> str:
    from fibersweep.sorting.report import critical_text

    return critical_text(lc, lo, hi, level)


def answer(
    curve: pd.DataFrame,
    key: str,
    target: float,
    flow: dict,
    bead: float,
    draws: dict[int, np.ndarray] | None = None,
    caveats: dict[int, list[str]] | None = None,
) -> DesignAnswer:
    """The value of ``key`` whose critical length is ``target`` [µm] (module docstring).

    Parameters
    ----------
    curve : DataFrame
        :func:`critical_curve` of one group (the other swept values fixed).
    key : str
    target : float
        Target critical length [µm].
    flow : dict
        The flow settings of the sweep (``dx``, ``array``): the lattice's allowed values.
    bead : float
        Length of one bead, 2a [µm]: brackets this narrow are located (a fiber has
        round(L / 2a) beads, so lengths closer than that are the same fiber).
    draws : dict, optional
        Setting -> draws of its critical length [µm] (:func:`curve_draws`; default:
        from the curve alone, the bracket and the statistical error).
    caveats : dict, optional
        Setting -> its lengths that decide a crossing on few moving runs
        (:func:`fibersweep.sorting.report.thin_crossings`); those of the settings the
        answer rests on are kept in :attr:`DesignAnswer.caveats`.
    """
    from fibersweep.sorting.interval import interval, inverse_draws

    name = key.rsplit(".", 1)[-1]
    caveats = caveats or {}
    c = curve.dropna(subset=["critical"])
    if "ci_lo" not in c:
        c = c.assign(ci_lo=math.nan, ci_hi=math.nan)
    if not pd.api.types.is_numeric_dtype(curve["value"]):
        if c.empty:
            return DesignAnswer(
                key,
                target,
                None,
                text="no value of the setting has a critical length in the swept lengths",
            )
        best = c.iloc[int(np.argmin(np.abs(c["critical"].to_numpy() - target)))]
        return DesignAnswer(
            key,
            target,
            best["value"],
            between=(best["value"],),
            text=f"{name} = {best['value']} gives the critical length nearest {target:g} µm: "
            f"{_crit(best['critical'], best['ci_lo'], best['ci_hi'], INTERVAL_LEVEL)} (not "
            f"interpolated: {name} is not a number)",
            caveats=tuple(caveats.get(int(best["setting"]), ())),
        )
    c = c.sort_values("value")
    v = c["value"].to_numpy(float)
    lc = c["critical"].to_numpy(float)
    se = np.nan_to_num(c["se"].to_numpy(float))
    lo, hi = c["lo"].to_numpy(float), c["hi"].to_numpy(float)
    ci_lo, ci_hi = c["ci_lo"].to_numpy(float), c["ci_hi"].to_numpy(float)
    sids = c["setting"].to_numpy(int)
    add: list[str] = []
    # a curve without the column (made by hand, or read from an older critical.csv): rising
    rising = (
        ~c["rising"].eq(False).fillna(False).to_numpy(bool)
        if "rising" in c
        else np.ones(len(c), bool)
    )
    mixed = False
    for k in range(len(v) - 1):
        if (lc[k] - target) * (lc[k + 1] - target) > 0 or lc[k] == lc[k + 1]:
            continue
        if rising[k] != rising[k + 1]:
            mixed = True
            continue  # a lower edge and an upper edge are not one curve
        w = (target - lc[k]) / (lc[k + 1] - lc[k])
        val = v[k] + w * (v[k + 1] - v[k])
        sig = (
            abs(v[k + 1] - v[k])
            / abs(lc[k + 1] - lc[k])
            * math.hypot((1 - w) * se[k], w * se[k + 1])
        )
        # the interval: every setting's critical length drawn, the whole interpolation
        # done again per draw (lengths, then values, with the curvature of a third value)
        if draws is None:
            draws = curve_draws(c)
        C = np.stack([draws[int(s)] for s in sids], axis=1)
        ci = interval(inverse_draws(v, C, target, rising))
        ci_text = (
            _value_interval(name, ci, v, INTERVAL_LEVEL)
            + (
                ", which holds the runs' scatter and the interpolation between simulated "
                f"lengths and between simulated values of {name}"
                if len(v) >= 3
                else ", which holds the runs' scatter and the interpolation between simulated "
                f"lengths, not the curvature between the two simulated values of {name} "
                "(simulate a third to estimate it)"
            )
            + f" (the statistical error alone: ± {sig:.2g})"
        )
        # model-free: the crossing lies in each bracket [lo, hi] whatever the interpolation;
        # when neither bracket holds the target, the answer lies between the two values
        decided = not (lo[k] <= target <= hi[k] or lo[k + 1] <= target <= hi[k + 1])
        span = (min(v[k], v[k + 1]), max(v[k], v[k + 1])) if decided else (math.nan, math.nan)
        grid = lattice_neighbours(key, val, flow)
        for j in (k, k + 1):
            if hi[j] - lo[j] > bead * (1 + 1e-9):
                add.append(
                    f"{name} = {v[j]:g}: its critical length is bracketed by {lo[j]:g} and "
                    f"{hi[j]:g} µm; add the length {0.5 * (lo[j] + hi[j]):g} µm to narrow it"
                )
        near = grid[0] if abs(grid[0] - val) <= abs(grid[1] - val) else grid[1]
        done = np.flatnonzero(np.isclose(v, near, rtol=0, atol=1e-9))
        rests = [int(sids[k]), int(sids[k + 1])]
        head = (
            f"{name} = {val:.4g} gives a critical length of {target:g} µm (interpolated "
            f"between {name} = {v[k]:g}: {lc[k]:.1f} µm and {name} = {v[k + 1]:g}: "
            f"{lc[k + 1]:.1f} µm); {ci_text}"
        )
        if done.size:  # the check has run: what it says
            j = int(done[0])
            rests.append(int(sids[j]))
            holds = lo[j] <= target <= hi[j]
            one_bead = hi[j] - lo[j] <= bead * (1 + 1e-9)
            checked = (
                f"; {name} = {near:g}, the value the lattice allows nearest, is simulated: "
                f"its critical length {_crit(lc[j], ci_lo[j], ci_hi[j], INTERVAL_LEVEL)}, "
                f"between the simulated {lo[j]:g} and {hi[j]:g} µm"
                + (
                    f", which hold {target:g} µm"
                    + (
                        " (to one bead: as close as lengths go)"
                        if one_bead
                        else "; narrow the bracket to be sure (below)"
                    )
                    if holds
                    else f", which do not hold {target:g} µm"
                )
            )  # fmt: skip
            return DesignAnswer(key, target, float(val), float(sig), span, (v[k], v[k + 1]),
                                grid, head + checked, add, ci, INTERVAL_LEVEL,
                                _caveats(caveats, rests))  # fmt: skip
        if grid[0] != grid[1] and math.isfinite(near):
            add.insert(
                0,
                f"{name} = {near:g} (the value the lattice allows nearest {val:.4g}; "
                f"the other side: {grid[1] if near == grid[0] else grid[0]:g}), with "
                f"lengths around {target:g} µm: the check",
            )
        else:
            add.insert(0, f"{name} = {val:.4g} with lengths around {target:g} µm: the check")
        text = head
        if decided:
            text += (
                f"; whatever the interpolation, between {span[0]:g} and {span[1]:g} (the "
                f"brackets of their critical lengths lie on either side of {target:g} µm)"
            )
        else:
            text += (
                f"; not yet decided: a critical length's bracket of simulated lengths holds "
                f"{target:g} µm, narrow it first (below)"
            )
        return DesignAnswer(key, target, float(val), float(sig), span, (v[k], v[k + 1]), grid,
                            text, add, ci, INTERVAL_LEVEL, _caveats(caveats, rests))  # fmt: skip
    if c.empty:
        text = f"no value of {name} has a critical length in the swept lengths: widen sweep.length"
        return DesignAnswer(key, target, None, text=text)
    if mixed:
        text = (
            f"the critical lengths on either side of {target:g} µm are a lower edge (f rises "
            f"through 1/2) and an upper edge (f falls): not one curve, nothing to interpolate"
        )
        add = [f"values of {name} between those two, to find where the edge of one kind "
               f"reaches {target:g} µm"]  # fmt: skip
        return DesignAnswer(key, target, None, text=text, add=add)
    k_near = int(np.argmin(np.abs(lc - target)))
    rng = f"{lc.min():.1f} to {lc.max():.1f} µm over {name} = {v.min():g} to {v.max():g}"
    side = "above" if target > lc.max() else "below" if target < lc.min() else "inside"
    text = (
        f"{target:g} µm is {side} the critical lengths simulated ({rng}); nothing to "
        f"interpolate: the nearest is "
        f"{_crit(lc[k_near], ci_lo[k_near], ci_hi[k_near], INTERVAL_LEVEL)} at {name} = "
        f"{v[k_near]:g}"
    )
    if side != "inside":
        grow = (lc[-1] - lc[0]) * (1 if side == "above" else -1) > 0
        edge = v.max() if grow else v.min()
        add.append(
            f"values of {name} {'beyond' if grow else 'below'} {edge:g}, where the "
            "critical length moves towards the target"
        )
    return DesignAnswer(key, target, None, between=(v[k_near],), text=text, add=add,
                        caveats=_caveats(caveats, [int(sids[k_near])]))  # fmt: skip


def _caveats(caveats: dict[int, list[str]], settings: list[int]) -> tuple[str, ...]:
    """The caveats of ``settings``, each once, in order."""
    out: list[str] = []
    for s in settings:
        for line in caveats.get(s, ()):
            if line not in out:
                out.append(line)
    return tuple(out)


def lattice_pick(ans: DesignAnswer) -> float:
    """The value the lattice allows nearest the answer (the answer itself when it allows any)."""
    lo, hi = ans.lattice
    cands = [v for v in (lo, hi) if math.isfinite(v)]
    return min(cands, key=lambda v: abs(v - ans.value)) if cands else ans.value


@dataclass(frozen=True)
class GroupAnswer:
    """The answer for one group of a design curve (the other swept values fixed).

    Attributes
    ----------
    group : str
        The other swept values ('' when only the design key varies).
    answer : DesignAnswer
    check : float or None
        The value to add to the swept values to check the answer: the one the lattice
        allows nearest it, when it is not simulated yet (None otherwise).
    """

    group: str
    answer: DesignAnswer
    check: float | None = None


def answers(
    curve: pd.DataFrame,
    settings: list[dict],
    key: str,
    target: float,
    bead: float,
    table: pd.DataFrame | None = None,
    caveats: dict[int, list[str]] | None = None,
) -> list[GroupAnswer]:
    """:func:`answer` for each group of ``curve``, with the value to run to check it.

    Parameters
    ----------
    curve : DataFrame
        :func:`critical_curve`.
    settings : list of dict
        The settings of :func:`fibersweep.results.load_array_results` (each group's
        flow settings give the lattice).
    key : str
    target : float
        Target critical length [µm].
    bead : float
        Length of one bead, 2a [µm].
    table : DataFrame, optional
        :func:`fibersweep.sorting.report.migration_table`: the runs behind the curve,
        for the interval (:func:`curve_draws`; without it, from the brackets alone).
    caveats : dict, optional
        Setting -> lengths that decide its crossings on few moving runs
        (:func:`fibersweep.sorting.report.thin_crossings`).
    """
    out = []
    simulated = curve["value"].to_numpy(float) if _numeric(curve) else None
    draws = curve_draws(curve, table) if _numeric(curve) else None
    for grp, g in curve.groupby("group", sort=False):
        ans = answer(g, key, target, settings[int(g["setting"].iloc[0])]["flow"], bead,
                     draws=draws, caveats=caveats)  # fmt: skip
        check = None
        if isinstance(ans.value, float) and simulated is not None:
            pick = lattice_pick(ans)
            if not np.isclose(simulated, pick).any():
                check = float(pick)
        out.append(GroupAnswer(str(grp), ans, check))
    return out


def _numeric(curve: pd.DataFrame) -> bool:
    return pd.api.types.is_numeric_dtype(curve["value"])
