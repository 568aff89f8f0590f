"""What the discrepancy workflow may name as the cause of a gap: its candidates.

A candidate is one parameter of the model that the workflow can switch on,
fit and name, with the interval it is fitted in, the probe values its
signature is read at, and a realistic magnitude (the report's power table,
the tests). Every stage (signature, halves, pooled refit, held-out test,
pairs, power, what to measure next, report) works on a candidate's *value*
``u``, a float whose 0 is the config's model (the baseline): copies are
simulated with ``{name: u}`` (:meth:`fibersweep.discrepancy.simulate.Simulator.run`).

Two kinds share this one object:

- a library effect (:data:`LIBRARY`, ``scale='effect'``): an effect of the
  effect registry (:mod:`fibersweep.fiber.effects`), switched on at ``u``;
- a declared setting (``--candidate KEY=...``, :mod:`.declared`): any setting
  of the config; ``u`` maps to the setting's value by the candidate's scale
  (:meth:`Candidate.setting`), and the simulator applies it as a config
  override (:meth:`Candidate.overrides`). ``linear``: ``base + u``; ``log``:
  ``base * 10**u``, for a range that spans decades; ``rigid``: a stiffness
  with the rigid model as its limit, ``E = base / (10**u - 1)`` (``u = 0``
  is rigid, ``base`` is the stiffest fiber of the range at ``u = log10 2``,
  the range's softest at ``hi``); ``choice``: one alternative value, ``u``
  is 0 (the config's) or 1 (the alternative), compared, never scanned.

An unknown library name fails loudly, listing the valid ones.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from fibersweep.errors import InputError

__all__ = ["Candidate", "LIBRARY", "SCALES", "get_candidates", "show_values"]

#: How a candidate's value maps to its setting (see the module docstring).
SCALES = ("effect", "linear", "log", "rigid", "choice")


@dataclass(frozen=True)
class Candidate:
    """A fittable parameter: a library effect or a declared setting, and its search range.

    Attributes
    ----------
    name : str
        Registry name.
    lo, hi : float
        Fit interval of the value (0 = baseline lies inside).
    probes : tuple of float
        Values whose simulated signature is compared with the gap.
    realistic : float
        A realistic magnitude (what the source or a plausible calibration error suggests).
    note : str
        What the value means.
    random : bool
        The effect draws random numbers per run (it spreads outcomes rather
        than moving them): its copies carry Monte Carlo noise of their own, so
        the workflow gives its fits and held-out scores more copies
        (``DiscrepancySettings.random_fit_copies``, ``random_copies``).
    scale : str
        One of :data:`SCALES`: how a value maps to the setting (module docstring).
    key : str
        Dotted setting a declared candidate varies ('' for a library effect).
    base : float
        ``linear``, ``log``: the config's value of ``key``; ``rigid``: the
        stiffness at ``u = log10 2`` (the range's stiffest).
    choice : Any
        ``choice``: the alternative value of ``key``.
    switch : tuple of (str, Any)
        Settings that come with any nonzero value (a model switch:
        ``fiber.model = bead-spring``, ``fiber.integrator = ros2`` for a stiffness).
    unit : str
        Unit of ``key``'s value, for reports.
    """

    name: str
    lo: float
    hi: float
    probes: tuple[float, ...]
    realistic: float
    note: str
    random: bool = False
    scale: str = "effect"
    key: str = ""
    base: float = 0.0
    choice: Any = None
    switch: tuple[tuple[str, Any], ...] = ()
    unit: str = ""

    def __post_init__(self) -> None:
        if self.scale not in SCALES:
            raise ValueError(f"candidate {self.name}: scale {self.scale!r} not in {SCALES}")
        if not self.lo <= 0.0 <= self.hi:
            raise ValueError(f"candidate {self.name}: range [{self.lo}, {self.hi}] must hold 0")

    @property
    def signed(self) -> bool:
        return self.lo < 0.0 < self.hi

    @property
    def is_effect(self) -> bool:
        """A library effect (else a declared setting)."""
        return self.scale == "effect"

    @property
    def categorical(self) -> bool:
        """An alternative value: its value is 0 or 1, compared, never scanned."""
        return self.scale == "choice"

    @property
    def keys(self) -> frozenset[str]:
        """The settings a nonzero value changes (empty for a library effect)."""
        return frozenset([self.key, *(k for k, _ in self.switch)]) if self.key else frozenset()

    def conflicts(self, other: Candidate) -> bool:
        """Both change one setting: they cannot be switched on together (a pair)."""
        return bool(self.keys & other.keys)

    def setting(self, u: float) -> Any:
        """The value of :attr:`key` at the candidate value ``u`` (a library effect: ``u``).

        ``rigid`` at ``u = 0``: ``math.inf`` (the rigid model).
        """
        u = float(u)
        if self.scale == "linear":
            return self.base + u
        if self.scale == "log":
            return self.base * 10.0**u
        if self.scale == "rigid":
            return math.inf if u <= 0.0 else self.base / (10.0**u - 1.0)
        if self.scale == "choice":
            return self.choice if u != 0.0 else None
        return u

    def overrides(self, u: float) -> dict[str, Any]:
        """Dotted setting -> value for candidate value ``u`` (``{}`` at 0 and for an effect)."""
        if self.is_effect or float(u) == 0.0:
            return {}
        return {**dict(self.switch), self.key: self.setting(u)}

    def show_value(self, u: float) -> str:
        """``u`` in the candidate's own unit, for reports (``'∞ (rigid)'``, ``'smooth'``)."""
        if self.scale == "choice":
            return str(self.choice) if float(u) != 0.0 else "the config's value"
        v = self.setting(u)
        if self.scale == "rigid" and math.isinf(v):
            return "∞ (rigid)"
        return f"{v:.3g}" + (f" {self.unit}" if self.unit else "")

    def show(self, u: float) -> str:
        """``name = value`` in the candidate's own unit (a choice: its name when on)."""
        if self.scale == "choice":
            return self.name if float(u) != 0.0 else f"{self.key} (config)"
        if self.is_effect:
            return f"{self.name} = {float(u):.3g}"
        return f"{self.key} = {self.show_value(u)}"

    def interval(self, lo: float, hi: float) -> tuple[Any, Any]:
        """An interval of values ``[lo, hi]`` in the setting's unit, low end first.

        The ``rigid`` scale runs backwards (a larger value is a softer fiber), so
        its ends swap; its value 0 is ``inf``. A choice: ``(choice, choice)``.
        """
        a, b = self.setting(lo), self.setting(hi)
        if self.scale == "choice":
            return (self.choice, self.choice)
        return (b, a) if self.scale == "rigid" else (a, b)


def show_values(values: dict[str, float], candidates: dict[str, Candidate] | None = None) -> str:
    """``a = 0.3 + fiber.young_modulus = 3e+05 Pa``: each value in its candidate's unit.

    Names without a candidate in ``candidates`` (library effects when it is None)
    print as ``name = value``.
    """
    cands = {**LIBRARY, **(candidates or {})}
    return " + ".join(
        cands[n].show(v) if n in cands else f"{n} = {float(v):.3g}" for n, v in values.items()
    )


LIBRARY: dict[str, Candidate] = {
    c.name: c
    for c in (
        Candidate("friction", 0.0, 1.0, (0.5,), 0.5, "Coulomb coefficient on the pillar"),
        # realistic 1: the first-reflection (Faxén) drag itself
        Candidate("pillar_hydro", 0.0, 3.0, (1.0,), 1.0, "multiplier on the Faxén pillar drag"),
        Candidate("off_midplane", 0.0, 0.35, (0.25,), 0.15, "offset from the midplane / depth"),
        # 1e3 x kT: rotational diffusion of ~25° over a ~1 s pass, already extreme
        Candidate("brownian", 0.0, 3.0e3, (1.0e3,), 1.0, "multiplier on kT at 295 K", True),
        Candidate("inlet_speed", -0.3, 0.3, (-0.15, 0.15), 0.05, "relative speed error"),
        Candidate("start_noise", 0.0, 5.0, (3.0,), 3.0, "start noise / reference noise", True),
        Candidate("pillar_scale", -0.2, 0.2, (-0.1, 0.1), 0.1, "relative pillar size error"),
    )
}


def get_candidates(names: list[str] | tuple[str, ...] | None = None) -> list[Candidate]:
    """Candidates by name (all when None); InputError listing the valid names otherwise."""
    if names is None:
        return list(LIBRARY.values())
    out = []
    for n in names:
        if n not in LIBRARY:
            raise InputError(
                f"effects: {n!r} is not a fittable effect; valid: {', '.join(LIBRARY)}"
            )
        out.append(LIBRARY[n])
    return out
