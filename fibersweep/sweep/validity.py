"""Where a config leaves what the validation reports checked: the rules, each with its page.

Every number fibersweep prints is as good as the model behind it, and the
validation reports say where the model is not converged or not checked. A config
can still ask for such a point (a soft fiber of touching beads, rows fewer than a
zigzag period): it runs, and these rules say so once per command, naming the
setting to change and the page that shows why. ``run``, ``sort-report`` and
``simulate`` return them as ``warnings`` (:mod:`fibersweep.api`), log them, and
the command line prints them.

:data:`RULES` is the registry: each :class:`Rule` reads the :class:`Facts` of one
setting combination (model, stiffness, bead spacing, rows...) and returns what it
found or None. :func:`warnings_for` applies every rule to the combinations of a
command and writes one line per rule, naming the combinations it concerns. The
thresholds are module constants, each with the measurement it comes from.

What the reports list and what is warned on (``docs/validation/``):

* touching beads below about 30 kPa: not converged in bead spacing (bandpass.md,
  sections 4 and 'What a designer can trust'; flexible.md 'In a pillar array') —
  :data:`RULES` ``touching-soft``;
* touching beads between 31.6 kPa and 1 MPa in an array: compared with finer
  chains only at 1 MPa (and b = a with b = a/2 at 0.1 MPa) — ``touching-unchecked``;
* trapped shares at b = a (or coarser): not converged, b = a/2 needed (bandpass.md,
  section 7) — ``trapped-spacing``;
* a soft chain without self-exclusion passes through itself (flexible.md,
  'Array: the band-pass filter') — ``self-exclusion``;
* fewer than two zigzag periods of rows: f cannot tell zigzag from displacement
  (arrays.md, 'Design: a target critical length') — ``rows-periods``;
* a device (``sort-report --rows``) shorter than one zigzag period — ``device-rows``.

Listed but not warned on: the coarse grid dx = 4 µm (the channel's separatrix
error is estimated and printed by ``flow``, docs/fidelity.md); the staircase
pillar (it converges, slowly: flow.md); the one-bead sphere against Davis's law
(a model limit, arrays.md); band edges on a smooth pillar and stiffnesses above
100 kPa in the band-pass map (bandpass.md 'Not established': a map's scope, not a
config's). Pure: reads settings, imports only the config schema.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

__all__ = [
    "Facts",
    "MIN_PERIODS",
    "RULES",
    "Rule",
    "combination_facts",
    "SOFT_TOUCHING_E",
    "STIFF_E",
    "facts",
    "facts_from_dict",
    "warnings_for",
]

#: Highest E [Pa] at which the touching chain was shown not converged in bead spacing
#: (31.6 kPa, docs/validation/bandpass.md section 4; "below about 30 kPa" in flexible.md).
SOFT_TOUCHING_E = 31.6e3

#: Stiffness [Pa] from which a touching chain moves as the finer ones (shift per row
#: within 0.1 µm at 1 MPa, docs/validation/flexible.md 'Bead spacing'), and from which
#: distant beads never meet (smallest distance 7.5 µm at 1 MPa, 'Array: ...').
STIFF_E = 1.0e6

#: b / 2a of b = a: the spacing whose f and band edges agree with b = a/2.
SPACING_A = 0.5

#: b / 2a of b = a/2: the spacing trapped shares need.
SPACING_HALF_A = 0.25

#: Zigzag periods (1/ε rows each) a run must cross for its f to mean something
#: (docs/arrays.md; :data:`fibersweep.sorting.report.MIN_PERIODS`).
MIN_PERIODS = 2.0

_TOL = 1e-9


@dataclass(frozen=True)
class Facts:
    """What the rules read of one setting combination.

    Attributes
    ----------
    label : str
        The combination ('' without swept settings), to name it.
    model : str
        ``fiber.model``.
    young_modulus : float
        E [Pa].
    bead_spacing : float
        b / 2a (1: touching beads).
    self_exclusion : bool
    array : bool
        A pillar array (``flow.array`` set).
    shift : float
        Row shift ε (NaN past one pillar).
    array_rows : int
        Rows a run crosses.
    device_rows : int or None
        Rows of the device the report's outlets are for (``sort-report --rows``).
    trapped : int or None
        Runs trapped at this combination (None: not known, e.g. before the runs).
    runs : int or None
        Runs at this combination.
    """

    label: str
    model: str
    young_modulus: float
    bead_spacing: float
    self_exclusion: bool
    array: bool
    shift: float = math.nan
    array_rows: int = 20
    device_rows: int | None = None
    trapped: int | None = None
    runs: int | None = None

    @property
    def flexible(self) -> bool:
        return self.model != "rigid"


@dataclass(frozen=True)
class Rule:
    """One check of the validated range.

    Attributes
    ----------
    name : str
    source : str
        The page (and section) that shows why.
    setting : str
        The setting that takes a combination back into the validated range.
    applies : callable
        Facts -> whether the combination is outside.
    says : callable
        The combinations it applies to -> the warning (naming them when not all are).
    """

    name: str
    source: str
    setting: str
    applies: Callable[[Facts], bool]
    says: Callable[[list[Facts]], str]


def _kpa(e: float) -> str:
    return f"{e / 1e3:.3g} kPa" if e < 1e6 else f"{e / 1e6:.3g} MPa"


def _moduli(hits: list[Facts]) -> str:
    es = sorted({f.young_modulus for f in hits})
    return "E = " + ", ".join(_kpa(e) for e in es)


def _where(hits: list[Facts]) -> str:
    named = [f.label for f in hits if f.label]
    return f" ({'; '.join(named)})" if named else ""


def _spacing(b: float) -> str:
    """'touching beads (b = 2a)', 'b = a', 'b = 0.5a' (``fiber.bead_spacing`` is b / 2a)."""
    if abs(b - 1.0) <= _TOL:
        return "touching beads (b = 2a)"
    return "b = a" if abs(b - 0.5) <= _TOL else f"b = {2 * b:g}a"


def _spacings(hits: list[Facts]) -> str:
    return ", ".join(_spacing(b) for b in sorted({f.bead_spacing for f in hits}))


def _touching_soft(f: Facts) -> bool:
    return (
        f.flexible
        and f.bead_spacing > SPACING_A + _TOL
        and f.young_modulus <= SOFT_TOUCHING_E * (1 + _TOL)
    )


def _touching_unchecked(f: Facts) -> bool:
    return (
        f.flexible
        and f.array
        and f.bead_spacing > SPACING_A + _TOL
        and SOFT_TOUCHING_E * (1 + _TOL) < f.young_modulus < STIFF_E
    )


def _trapped_spacing(f: Facts) -> bool:
    return (
        f.flexible
        and f.array
        and f.bead_spacing > SPACING_HALF_A + _TOL
        and f.young_modulus < STIFF_E
        and (f.trapped is None or f.trapped > 0)
    )


def _self_exclusion(f: Facts) -> bool:
    return f.flexible and not f.self_exclusion and f.young_modulus < STIFF_E


def _rows_periods(f: Facts) -> bool:
    return f.array and f.shift > 0 and f.array_rows * f.shift < MIN_PERIODS - _TOL


def _device_rows(f: Facts) -> bool:
    return (
        f.array and f.shift > 0 and f.device_rows is not None
        and f.device_rows * f.shift < 1 - _TOL
    )  # fmt: skip


def _trapped_count(hits: list[Facts]) -> str:
    if any(f.trapped is None or f.runs is None for f in hits):
        return ""
    return f", {sum(f.trapped for f in hits)} of {sum(f.runs for f in hits)} runs trapped"


def _worst(hits: list[Facts], rows: Callable[[Facts], int]) -> Facts:
    return min(hits, key=lambda f: rows(f) * f.shift)


def _rows_text(hits: list[Facts]) -> str:
    f = _worst(hits, lambda f: f.array_rows)
    return (
        f"{f.array_rows} rows are {f.array_rows * f.shift:.1f} zigzag periods at ε = "
        f"{f.shift:g} (1/ε = {1 / f.shift:.0f} rows){_where(hits)}, too few for f to tell "
        f"zigzag from displacement; run at least {math.ceil(MIN_PERIODS / f.shift - _TOL)} "
        "rows (fiber.array_rows)"
    )


def _device_text(hits: list[Facts]) -> str:
    f = _worst(hits, lambda f: f.device_rows or 0)
    return (
        f"a device of {f.device_rows} rows is less than one zigzag period at ε = {f.shift:g} "
        f"(1/ε = {1 / f.shift:.0f} rows){_where(hits)}: a fiber cannot complete one period "
        "of the array, so a zigzagging fiber has not jumped back once and its outlet cannot "
        f"be told from a displaced one's; use --rows {math.ceil(1 / f.shift - _TOL)} or more"
    )


RULES: dict[str, Rule] = {
    r.name: r
    for r in (
        Rule(
            "touching-soft",
            "docs/validation/bandpass.md, 'What a designer can trust' (section 4); "
            "docs/flexible.md, 'In a pillar array'",
            "fiber.bead_spacing",
            _touching_soft,
            lambda hits: (
                f"bead-spring fibers of {_moduli(hits)} with {_spacings(hits)}{_where(hits)}: "
                f"touching beads are not converged at or below {_kpa(SOFT_TOUCHING_E)} (a "
                "bending length of two to three beads; the band and the trapping they show "
                "are artefacts of 2a segments): set fiber.bead_spacing to 0.5 (b = a)"
            ),
        ),
        Rule(
            "touching-unchecked",
            "docs/validation/bandpass.md, 'What a designer can trust'",
            "fiber.bead_spacing",
            _touching_unchecked,
            lambda hits: (
                f"bead-spring fibers of {_moduli(hits)} with {_spacings(hits)} in an array"
                f"{_where(hits)}: the touching chain is checked against finer ones only at "
                f"{_kpa(STIFF_E)}; compare with fiber.bead_spacing=0.5 (b = a) before "
                "trusting it"
            ),
        ),
        Rule(
            "trapped-spacing",
            "docs/validation/bandpass.md, section 7 ('The trapped share does not converge "
            "between a and a/2')",
            "fiber.bead_spacing",
            _trapped_spacing,
            lambda hits: (
                f"trapped shares of bead-spring fibers with {_spacings(hits)}{_where(hits)}"
                f"{_trapped_count(hits)}: trapped shares need b = a/2 (at b = a, 0.3 to 0.6 "
                "of the fibers below the lower edge are trapped where b = a/2 traps none of "
                "the same starts); set fiber.bead_spacing to 0.25 before trusting them (f "
                "and the edges are converged at 0.5)"
            ),
        ),
        Rule(
            "self-exclusion",
            "docs/validation/flexible.md, 'Array: the band-pass filter' (with and without "
            "self-exclusion)",
            "fiber.self_exclusion",
            _self_exclusion,
            lambda hits: (
                f"bead-spring fibers of {_moduli(hits)} without self-exclusion{_where(hits)}: "
                "a soft chain passes through itself (at 10 kPa two segments crossed in 40 of "
                "84 runs; at 0.1 MPa distant beads come within 2a): set "
                "fiber.self_exclusion to true"
            ),
        ),
        Rule(
            "rows-periods",
            "docs/arrays.md, 'Design: a target critical length' (rows matter too)",
            "fiber.array_rows",
            _rows_periods,
            _rows_text,
        ),
        Rule(
            "device-rows",
            "docs/arrays.md, 'Design: a target critical length' (rows matter too)",
            "sort-report --rows",
            _device_rows,
            _device_text,
        ),
    )
}


def facts(
    fiber: Any,
    array: Any = None,
    label: str = "",
    device_rows: int | None = None,
    trapped: int | None = None,
    runs: int | None = None,
) -> Facts:
    """The :class:`Facts` of a combination from its settings.

    Parameters
    ----------
    fiber : FiberSettings
        ``config.fiber`` (of the combination).
    array : ArraySettings, dict or None
        ``config.flow.array`` (None past one pillar).
    label : str
        The combination's name.
    device_rows, trapped, runs : int, optional
        See :class:`Facts`.
    """
    shift = math.nan
    if array is not None:
        shift = float(array["shift"] if isinstance(array, Mapping) else array.shift)
    return Facts(
        label=label,
        model=str(fiber.model),
        young_modulus=float(fiber.young_modulus),
        bead_spacing=float(fiber.bead_spacing),
        self_exclusion=bool(fiber.self_exclusion),
        array=array is not None,
        shift=shift,
        array_rows=int(fiber.array_rows),
        device_rows=device_rows,
        trapped=trapped,
        runs=runs,
    )


def facts_from_dict(
    fiber: Mapping[str, Any],
    array: Mapping[str, Any] | None,
    values: Mapping[str, Any] | None = None,
    label: str = "",
    **kw: Any,
) -> Facts:
    """:func:`facts` from a stored config's ``fiber`` section (a manifest's: settings at
    their defaults are left out of it) with the combination's swept ``values``
    (``fiber.young_modulus`` ...) applied."""
    from fibersweep.config.fiber import FiberSettings

    data = dict(fiber)
    for key, value in (values or {}).items():
        parts = key.split(".")
        if parts[0] == "fiber" and len(parts) == 2:
            data[parts[1]] = value
    settings = FiberSettings.model_validate(data)
    return facts(settings, array, label, **kw)


def combination_facts(settings: Sequence[Any], runs: Any = None) -> list[Facts]:
    """The :class:`Facts` of each setting combination of a sweep, with its trapped runs.

    Parameters
    ----------
    settings : sequence
        The sweep's settings (:func:`fibersweep.sweep.plan.sweep_settings`: each with
        ``id`` and ``combination``, whose ``config`` and ``label`` are read).
    runs : DataFrame, optional
        The runs table (``settings``, ``mode``): trapped runs per combination; without
        it, or before the runs, the trapped counts are not known.
    """
    out = []
    for st in settings:
        cfg = st.combination.config
        trapped = count = None
        if runs is not None and len(runs) and "settings" in runs and "mode" in runs:
            mine = runs[runs["settings"] == st.id]
            if len(mine):
                trapped, count = int((mine["mode"] == "trapped").sum()), len(mine)
        out.append(facts(cfg.fiber, cfg.flow.array, st.combination.label, trapped=trapped,
                         runs=count))  # fmt: skip
    return out


def warnings_for(
    combos: Iterable[Facts], rules: Mapping[str, Rule] | None = None
) -> tuple[str, ...]:
    """One warning per rule that some combination breaks, naming those combinations, the
    setting to change and the source page (the API logs them and returns them).

    Parameters
    ----------
    combos : iterable of Facts
    rules : mapping, optional
        The registry [default: :data:`RULES`].
    """
    rules = RULES if rules is None else rules
    items: Sequence[Facts] = list(combos)
    out = []
    for rule in rules.values():
        hit = [f for f in items if rule.applies(f)]
        if not hit:
            continue
        if len(hit) == len(items) and len(items) > 1:  # all of them: no need to name them
            hit = [Facts(**{**f.__dict__, "label": ""}) for f in hit]
        out.append(f"{rule.says(hit)} [{rule.source}]")
    return tuple(out)
