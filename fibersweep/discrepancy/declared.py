"""Candidates from any setting: ``--candidate`` specs parsed, checked and applied.

A declared candidate is a :class:`~.candidates.Candidate` like a library
effect; this module makes one from its text and applies its value to the
model's settings. One spec, parts joined by commas:

- ``KEY=LO..HI``: a number setting fitted in a range; on a log scale when the
  range spans a decade or more (``HI >= 10 LO > 0``), else linearly. The
  config's value must lie in the range: it is the baseline every value is
  compared with.
- ``KEY=VALUE``: an alternative to the config's value (categorical), compared
  with it, never scanned. Repeat ``--candidate`` for more alternatives.
- ``KEY=VALUE,...,KEY2=LO..HI`` or ``KEY=VALUE,KEY2=VALUE2``: settings that
  come with the candidate (a model switch) and the one that is fitted or
  compared.
- A stiffness (:data:`STIFFNESS_KEYS`) of a config whose fiber is rigid is a
  model switch to :data:`FLEXIBLE_MODEL` unless the spec names
  ``fiber.model``; the rigid model is its limit (scale ``rigid``).

Keys are the dotted keys of ``fibersweep run CONFIG KEY=VALUE`` and of sweep
axes (checked by :func:`fibersweep.config.sweep_axes.setting_annotation`), and
a value is applied as such an override
(:func:`fibersweep.config.loading.apply_overrides`), so the schema checks it
with the same messages. A library effect is refused (``--effect`` names
those), as is a range of a ``flow`` setting: each flow value is its own flow
field, solved and cached (about a minute at dx = 4 µm on one core, more on a
finer grid), so a flow setting is compared at the alternatives given.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from typing import Any

import yaml
from pydantic import ValidationError

from fibersweep.config.errors import ConfigError
from fibersweep.config.fiber import FiberSettings
from fibersweep.config.flow import FlowSettings
from fibersweep.config.loading import apply_overrides
from fibersweep.config.schema import setting_annotation, setting_column
from fibersweep.discrepancy.candidates import LIBRARY, Candidate
from fibersweep.errors import InputError

__all__ = [
    "FLEXIBLE_INTEGRATOR",
    "FLEXIBLE_MODEL",
    "STIFFNESS_KEYS",
    "apply_values",
    "parse_candidate",
    "parse_candidates",
]

#: The flexible model a stiffness candidate of a rigid config switches to, and its
#: integrator (ROS2: the adaptive one for sweeps, docs/flexible.md).
FLEXIBLE_MODEL = "bead-spring"
FLEXIBLE_INTEGRATOR = "ros2"

#: Settings that only a flexible model reads: on a rigid config, the rigid model is
#: their limit (infinitely stiff).
STIFFNESS_KEYS = ("fiber.young_modulus",)

#: HI / LO from which a range is fitted on a log scale.
DECADE = 10.0


def _value_of(data: Mapping[str, Any], key: str) -> Any:
    node: Any = data
    for part in key.split("."):
        node = node.get(part) if isinstance(node, dict) else None
    return node


def apply_values(
    candidates: Mapping[str, Candidate],
    values: Mapping[str, float],
    fiber: FiberSettings,
    flow: FlowSettings,
    where: str = "candidate",
) -> tuple[FiberSettings, FlowSettings]:
    """The fiber and flow settings with each declared candidate at its value.

    Parameters
    ----------
    candidates : mapping name -> Candidate
        The declared candidates (names in ``values`` without one are ignored:
        library effects).
    values : mapping name -> float
        Candidate values (0: the config's).

    Raises
    ------
    InputError
        A value the schema refuses, naming ``where`` and the override.
    """
    over: dict[str, Any] = {}
    for name, u in values.items():
        cand = candidates.get(name)
        if cand is None or cand.is_effect:
            continue
        over.update(cand.overrides(u))
    if not over:
        return fiber, flow
    data = {"fiber": fiber.model_dump(mode="json"), "flow": flow.model_dump(mode="json")}
    items = [f"{k}={json.dumps(v)}" for k, v in over.items()]
    try:
        data = apply_overrides(data, {}, items)
        new_fiber = FiberSettings.model_validate(data["fiber"])
        new_flow = FlowSettings.model_validate(data["flow"])
    except ConfigError as exc:
        raise InputError(f"{where}: {'; '.join(exc.problems)}") from None
    except ValidationError as exc:
        section = "fiber" if "fiber" in exc.title.lower() else "flow"
        msg = "; ".join(
            f"{section}.{'.'.join(str(p) for p in e['loc'])}: "
            + e["msg"].removeprefix("Value error, ")
            for e in exc.errors()
        )
        raise InputError(f"{where}: {', '.join(items)}: {msg}") from None
    return new_fiber, new_flow


def _parse_value(raw: str, label: str) -> Any:
    try:
        return yaml.safe_load(raw) if raw.strip() else None
    except yaml.YAMLError as exc:
        raise InputError(f"{label}: the value is not valid YAML ({exc})") from None


def _parse_range(raw: str, label: str) -> tuple[float, float] | None:
    if ".." not in raw:
        return None
    a, _, b = raw.partition("..")
    try:
        lo, hi = float(a), float(b)
    except ValueError:
        raise InputError(f"{label}: a range is LO..HI with two numbers, got {raw!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise InputError(f"{label}: the range needs finite LO < HI, got {raw!r}")
    return lo, hi


def _check_key(key: str, label: str) -> None:
    parts = key.split(".")
    name = parts[-1] if parts[:2] == ["fiber", "effects"] else key
    if (parts[:2] == ["fiber", "effects"]) or key in LIBRARY:
        raise InputError(
            f"{label}: {name} is a library effect of the discrepancy workflow; "
            f"consider it with --effect {name} (fitted in its library range)"
        )
    try:
        setting_annotation(key)
    except ValueError as exc:
        raise InputError(f"{label}: {exc}") from None


def parse_candidate(
    text: str, fiber: FiberSettings, flow: FlowSettings, where: str = "--candidate"
) -> Candidate:
    """One declared candidate from its spec (module docstring), checked against the config.

    Parameters
    ----------
    text : str
        E.g. ``fiber.young_modulus=1e4..3e7``, ``fiber.contact.pillar=smooth``.
    fiber, flow : FiberSettings, FlowSettings
        The config's (the baseline).
    where : str
        The option or config field named in errors.

    Raises
    ------
    InputError
        Malformed spec, unknown key, a library effect, a range without the
        config's value, a value the schema refuses (each naming ``where``).
    """
    label = f"{where} {text}"
    parts = [p.strip() for p in str(text).split(",") if p.strip()]
    if not parts:
        raise InputError(f"{label}: expected KEY=LO..HI or KEY=VALUE")
    fixed: list[tuple[str, Any]] = []
    ranged: tuple[str, float, float] | None = None
    for part in parts:
        key, sep, raw = part.partition("=")
        key = key.strip()
        if not sep or not key:
            raise InputError(f"{label}: expected KEY=LO..HI or KEY=VALUE, got {part!r}")
        _check_key(key, label)
        rng = _parse_range(raw.strip(), label)
        if rng is None:
            fixed.append((key, _parse_value(raw, label)))
        elif ranged is not None:
            raise InputError(f"{label}: one range per candidate ({ranged[0]} and {key})")
        else:
            ranged = (key, *rng)
    keys = [k for k, _ in fixed] + ([ranged[0]] if ranged else [])
    if len(set(keys)) != len(keys):
        raise InputError(f"{label}: a setting is named twice")
    base = {"fiber": fiber.model_dump(mode="json"), "flow": flow.model_dump(mode="json")}
    if ranged is None:
        *switch, (key, value) = fixed
        if _value_of(base, key) == value and not switch:
            raise InputError(f"{label}: {value!r} is the config's own {key}; give an alternative")
        cand = Candidate(
            name=",".join(f"{k}={v}" for k, v in fixed), lo=0.0, hi=1.0, probes=(1.0,),
            realistic=1.0, note=f"{key} = {value} instead of the config's "
            f"{_value_of(base, key)}", scale="choice", key=key, choice=value,
            switch=tuple(switch),
        )  # fmt: skip
        apply_values({cand.name: cand}, {cand.name: 1.0}, fiber, flow, label)
        return cand
    key, lo, hi = ranged
    ann, _ = setting_annotation(key)
    if ann is not float:
        raise InputError(
            f"{label}: {key} is not a number setting; give each alternative as KEY=VALUE"
        )
    if key.split(".")[0] == "flow":
        raise InputError(
            f"{label}: {key} is a flow setting: each value is its own flow field, solved "
            f"and cached, so a range is not fitted; give alternatives, one --candidate "
            f"{key}=VALUE each"
        )
    unit = setting_column(key)[1]
    switch = tuple(fixed)
    model = dict(switch).get("fiber.model", fiber.model)
    if key in STIFFNESS_KEYS and fiber.model == "rigid":
        if lo <= 0.0:
            raise InputError(
                f"{label}: {key} needs a positive range (a rigid fiber is its limit, at "
                f"infinite stiffness), got {lo:g}..{hi:g}"
            )
        if model == "rigid":
            switch = (
                ("fiber.model", FLEXIBLE_MODEL),
                ("fiber.integrator", FLEXIBLE_INTEGRATOR),
                *switch,
            )
            model = FLEXIBLE_MODEL
        # the rigid model is the limit: u = 0 rigid, E(u) = hi / (10**u - 1)
        top = math.log10(1.0 + hi / lo)
        cand = Candidate(
            name=key, lo=0.0, hi=top, probes=(0.5 * top,), realistic=0.5 * top,
            note=f"{key} [{unit}] of a {model} fiber, {lo:g}..{hi:g}; rigid at 0",
            scale="rigid", key=key, base=hi, switch=switch, unit=unit,
        )  # fmt: skip
    else:
        if switch:
            raise InputError(
                f"{label}: a fitted range comes with fixed settings only as a model switch "
                f"of a stiffness on a rigid config ({', '.join(STIFFNESS_KEYS)})"
            )
        v0 = _value_of(base, key)
        if not (isinstance(v0, int | float) and lo <= v0 <= hi):
            raise InputError(
                f"{label}: the range must hold the config's {key} = {v0} (the baseline "
                f"every value is compared with)"
            )
        log = lo > 0 and hi / lo >= DECADE and v0 > 0
        a, b = (math.log10(lo / v0), math.log10(hi / v0)) if log else (lo - v0, hi - v0)
        width = b - a
        probes = tuple(0.5 * e for e in (a, b) if abs(e) >= 0.1 * width)
        cand = Candidate(
            name=key, lo=a, hi=b, probes=probes, realistic=abs(probes[0]),
            note=f"{key} [{unit}], {lo:g}..{hi:g}" + (" (log scale)" if log else ""),
            scale="log" if log else "linear", key=key, base=float(v0), unit=unit,
        )  # fmt: skip
    for u in (cand.lo, cand.hi, *cand.probes):
        apply_values({cand.name: cand}, {cand.name: u}, fiber, flow, label)
    return cand


def parse_candidates(
    texts: Sequence[str],
    fiber: FiberSettings,
    flow: FlowSettings,
    where: str | Sequence[str] = "--candidate",
) -> list[Candidate]:
    """Declared candidates in order; a name given twice is refused.

    ``where``: the option or config field named in errors, one per text (or one
    for all).
    """
    labels = [where] * len(texts) if isinstance(where, str) else list(where)
    out: dict[str, Candidate] = {}
    for text, label in zip(texts, labels, strict=True):
        cand = parse_candidate(text, fiber, flow, label)
        if cand.name in out:
            raise InputError(f"{label} {text}: candidate {cand.name} is declared twice")
        out[cand.name] = cand
    return list(out.values())
