"""Settings in words with units, for every axis, legend and title of the figures.

A setting is named in the figures as a reader of the paper would name it, never
by its config key: ``fiber.young_modulus`` is "Young's modulus E [kPa]" on an
axis and "E = 10 kPa" in a legend, ``flow.array.shift`` "row shift ε" and
"ε = 0.1". The registry :data:`SETTINGS` holds the words, symbol and display unit
of the settings that are swept in practice; any other key falls back on its
field description and unit in the config schema
(:func:`fibersweep.config.setting_column`), and failing that on its last part
in words (``pillar_rotation`` -> "pillar rotation").
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

__all__ = [
    "SETTINGS",
    "Setting",
    "axis_label",
    "describe",
    "display_values",
    "is_decades",
    "setting_of",
    "short_name",
    "value_text",
    "values_text",
]


@dataclass(frozen=True)
class Setting:
    """How a setting is written in a figure.

    Attributes
    ----------
    words : str
        What it is ("Young's modulus").
    symbol : str
        Its symbol, mathtext allowed ("E", r"$\\lambda_x$"); '' if it has none.
    unit : str
        The unit of the figures ('' for a number without unit).
    scale : float
        Figure value = stored value × scale (Pa -> kPa: 1e-3).
    log : bool
        Spans decades by nature (a stiffness): a log axis whenever it is positive.
    si : str
        Base unit of an SI prefix per value in legends ("Pa": 10 kPa, 1 MPa); ''
        to write values in ``unit``.
    """

    words: str
    symbol: str = ""
    unit: str = ""
    scale: float = 1.0
    log: bool = False
    si: str = ""


#: Settings of the sweeps in the docs and configs, by dotted key (start axes bare).
SETTINGS: dict[str, Setting] = {
    "fiber.young_modulus": Setting("Young's modulus", "E", "kPa", 1e-3, log=True, si="Pa"),
    "fiber.bead_radius": Setting("bead radius", "a", "µm"),
    "fiber.bead_spacing": Setting("bead spacing", "b/2a"),
    "fiber.array_rows": Setting("rows crossed"),
    "fiber.model": Setting("fiber model"),
    "fiber.integrator": Setting("integrator"),
    "fiber.self_exclusion": Setting("self-exclusion"),
    "fiber.effects.friction": Setting("friction coefficient"),
    "fiber.effects.near_wall": Setting("near-wall hydrodynamics"),
    "fiber.contact.pillar": Setting("pillar surface"),
    "fiber.step.t_max": Setting("time limit", "", "s"),
    "flow.dx": Setting("lattice spacing", "dx", "µm"),
    "flow.fluid.u_center": Setting("centreline speed", r"$U$", "µm/s"),
    "flow.fluid.viscosity": Setting("viscosity", "μ", "Pa s", log=True),
    "flow.array.shift": Setting("row shift", "ε"),
    "flow.array.period_x": Setting("period along the flow", r"$\lambda_x$", "µm"),
    "flow.array.period_y": Setting("period across the flow", r"$\lambda_y$", "µm"),
    "flow.array.pillar_size": Setting("pillar size", r"$h_{obs}$", "µm"),
    "flow.array.pillar_shape": Setting("pillar shape"),
    "flow.array.pillar_rotation": Setting("pillar rotation", "", "deg"),
    "flow.array.depth": Setting("channel depth", "H", "µm"),
    "flow.array.mean_flow": Setting("mean flow"),
    "flow.geometry.pillar_height": Setting("pillar size", r"$h_{obs}$", "µm"),
    "flow.geometry.pillar_shape": Setting("pillar shape"),
    "flow.geometry.pillar_rotation": Setting("pillar rotation", "", "deg"),
    "flow.geometry.width": Setting("channel width", "W", "µm"),
    "flow.geometry.depth": Setting("channel depth", "H", "µm"),
    "theta0": Setting("start angle", r"$\theta_0$", "deg"),
    "model": Setting("fiber model"),
    "n_beads": Setting("beads"),
}

#: The start axes: in a channel in units of the pillar, in an array in µm and periods.
_CHANNEL = {
    "length": Setting("fiber length", r"$L/l_{obs}$"),
    "y0": Setting("start position", r"$y_0/h_{obs}$"),
}
_ARRAY = {
    "length": Setting("fiber length", "L", "µm"),
    "y0": Setting("start position", r"$y_0/\lambda_y$"),
}

_PREFIXES = ((1e9, "G"), (1e6, "M"), (1e3, "k"), (1.0, ""), (1e-3, "m"))


def _from_schema(key: str) -> Setting:
    """A setting the registry does not know: words and unit from its field description."""
    from fibersweep.config import setting_column

    _, unit, doc = setting_column(key)
    desc = doc.split(":", 1)[1].strip() if ":" in doc else ""
    words = re.split(r"\s*[\[(;:,]", desc, maxsplit=1)[0].strip()
    last = key.rsplit(".", 1)[-1].replace("_", " ")
    if not 3 <= len(words) <= 32 or "." in words:
        words = last
    return Setting(words, "", unit)


def setting_of(key: str, array: bool = False) -> Setting:
    """The :class:`Setting` of ``key`` (a dotted key, or a column of the runs table).

    ``array``: the runs are a pillar array's (L in µm, y0 a fraction of λy).
    """
    fixed = (_ARRAY if array else _CHANNEL).get(key)
    if fixed is not None:
        return fixed
    if key in SETTINGS:
        return SETTINGS[key]
    if "." in key:
        return _from_schema(key)
    return Setting(key.replace("_", " "))


def axis_label(key: str, array: bool = False) -> str:
    """Axis label: words, symbol and unit, e.g. "Young's modulus E [kPa]", "row shift ε"."""
    s = setting_of(key, array)
    text = " ".join(p for p in (s.words, s.symbol) if p)
    return f"{text} [{s.unit}]" if s.unit else text


def short_name(key: str, array: bool = False) -> str:
    """The symbol of ``key``, or its words when it has none ("E", "pillar surface")."""
    s = setting_of(key, array)
    return s.symbol or s.words


def _number(v: float) -> str:
    return f"{v:.4g}"


def value_text(key: str, value: object, array: bool = False) -> str:
    """One setting's value as a legend or title writes it: "E = 10 kPa", "ε = 0.1",
    "L = 80 µm", "pillar surface = rough"."""
    s = setting_of(key, array)
    name = s.symbol or s.words
    if isinstance(value, bool) or not isinstance(value, int | float | np.number):
        return f"{name} = {value}"
    v = float(value)
    if s.si and math.isfinite(v) and v != 0.0:
        for factor, prefix in _PREFIXES:
            if abs(v) >= factor:
                return f"{name} = {_number(v / factor)} {prefix}{s.si}"
    v = v * s.scale
    return f"{name} = {_number(v)}" + (f" {s.unit}" if s.unit else "")


def values_text(values: Mapping[str, object], array: bool = False) -> str:
    """Several settings' values, e.g. "E = 10 kPa, ε = 0.1" ('' for none)."""
    return ", ".join(value_text(k, v, array) for k, v in values.items())


def describe(settings: Iterable[Mapping], array: bool = True) -> dict[int, str]:
    """Label of each setting combination (the ``values`` of each entry of
    :func:`fibersweep.results.load_array_results`'s settings), by index."""
    return {i: values_text(s.get("values") or {}, array) for i, s in enumerate(settings)}


def display_values(key: str, values, array: bool = False) -> np.ndarray:
    """Stored numbers of ``key`` in the unit of its axis (E in Pa -> kPa)."""
    return np.asarray(values, dtype=float) * setting_of(key, array).scale


def is_decades(key: str, values) -> bool:
    """Whether ``key`` is drawn on a log axis: positive values over a decade or more
    (a stiffness, a viscosity), never the start axes (designed on a linear scale)."""
    if key in ("length", "theta0", "y0"):
        return False
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size < 2 or v.min() <= 0:
        return False
    return bool(v.max() >= 10.0 * v.min() or (setting_of(key).log and v.max() > v.min()))
