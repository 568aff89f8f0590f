"""The discrepancy workflow on a pillar array: which candidates apply, the settings it runs with.

The workflow itself (:mod:`.workflow`) is the channel's: it compares whatever
observables the measured data holds, through a :class:`~.simulate.Simulator`
that runs array fibers when its field is a unit cell. What differs in an
array is gathered here:

- the observables: the registry's array ones (:mod:`.array_observables`), read
  from an array measured table (:mod:`.array_schema`);
- the measurement noise: :func:`~.copies.array_noise` (starts in the array's units);
- the library effects: those a pillar-array run applies (acting in the kernels:
  friction, pillar hydrodynamics, off-midplane, Brownian motion); the others
  (inlet speed, start noise, pillar scale change the single pillar's field,
  start or report) are refused by name when asked for, and left out by default;
- declared candidates: any fiber setting, and the array's fabrication settings
  as alternatives (``flow.array.shift=0.125``, ``flow.array.pillar_size=44``):
  each value's unit-cell field is solved once and cached (:meth:`.Simulator.variant`),
  and a shift must stay a whole number of lattice cells (the flow schema says
  so, naming the field). A channel geometry setting (``flow.geometry.*``) is refused.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.candidates import LIBRARY, Candidate
from fibersweep.discrepancy.declared import apply_values
from fibersweep.errors import InputError

__all__ = ["array_effect_names", "array_library", "check_array_candidates", "field_plan"]


def array_library() -> tuple[str, ...]:
    """Library effects a pillar-array run applies (``rows.check_array_effects``)."""
    from fibersweep.fiber.rows import check_array_effects

    ok = []
    for name, c in LIBRARY.items():
        try:
            check_array_effects(FiberSettings(effects={name: c.probes[0]}))
        except InputError:
            continue
        ok.append(name)
    return tuple(ok)


def array_effect_names(names: Sequence[str] | None, fiber: FiberSettings) -> tuple[str, ...]:
    """The library effects considered on an array: ``names`` checked, or all that apply.

    Raises
    ------
    InputError
        A name the array cannot apply (naming why and the valid ones).
    """
    valid = array_library()
    if not names:
        return valid
    bad = [n for n in names if n in LIBRARY and n not in valid]
    if bad:
        raise InputError(
            f"--effect {', '.join(bad)}: changes the single-pillar channel's field, start or "
            f"report; not available in pillar arrays. Effects that apply there: {', '.join(valid)}"
        )
    return tuple(names)


def check_array_candidates(declared: Sequence[Candidate]) -> None:
    """InputError for a declared candidate that means nothing in an array (``flow.geometry``)."""
    for c in declared:
        keys = [c.key, *(k for k, _ in c.switch)] if c.key else [k for k, _ in c.switch]
        bad = [k for k in keys if k.startswith("flow.geometry")]
        if bad:
            raise InputError(
                f"--candidate {c.name}: {bad[0]} is the single-pillar channel's; in a pillar "
                "array the geometry is flow.array (e.g. flow.array.shift, flow.array.pillar_size)"
            )


def field_plan(
    declared: Sequence[Candidate], fiber: FiberSettings, flow: Any, cache_dir: Any,
    base_meta: dict | None,
) -> list[str]:  # fmt: skip
    """Lines of the plan on the unit-cell fields the declared flow candidates need.

    Each distinct flow setting is solved once and cached; a field already in the
    cache costs nothing. The cost of one to solve is scaled from the baseline
    field's own solve (``base_meta['seconds']``): cells ∝ period_x period_y depth / dx³,
    steps ∝ the longest side / dx (the same grid for a shift or a pillar size: the
    same time).
    """
    from fibersweep.flow.cache import cache_key
    from fibersweep.flow.cell_cache import cell_path

    lines = []
    base = flow.array
    t0 = float((base_meta or {}).get("seconds", math.nan))
    for c in declared:
        if not any(k.startswith("flow.") for k in (c.key, *(k for k, _ in c.switch)) if k):
            continue
        _, new = apply_values({c.name: c}, {c.name: 1.0}, fiber, flow, c.name)
        a = new.array
        if cache_dir is not None and cell_path(cache_dir, cache_key(new)).is_file():
            lines.append(f"  {c.name}: its unit-cell field is in the cache (no solve)")
            continue
        scale = (
            (flow.dx / new.dx) ** 4
            * (a.period_x * a.period_y * a.depth)
            / (base.period_x * base.period_y * base.depth)
            * max(a.period_x, a.period_y)
            / max(base.period_x, base.period_y)
        )
        cost = f"about {t0 * scale:.2g} s" if math.isfinite(t0) else "one LBM solve"
        lines.append(f"  {c.name}: its unit-cell field is solved once, then cached ({cost}, "
                     "scaled from the baseline field's solve)")  # fmt: skip
    return lines
