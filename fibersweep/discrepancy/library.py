"""The effects the discrepancy workflow may name, with their search ranges.

Each candidate is an effect of the registry (:mod:`fibersweep.fiber.effects`)
with the interval its parameter is fitted in, the probe values used to read
its signature, and a realistic magnitude (used by the tests and the study).
An unknown name fails loudly, listing the valid ones.
"""

from __future__ import annotations

from dataclasses import dataclass

from fibersweep.errors import InputError

__all__ = ["Candidate", "LIBRARY", "get_candidates"]


@dataclass(frozen=True)
class Candidate:
    """A fittable effect.

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
    """

    name: str
    lo: float
    hi: float
    probes: tuple[float, ...]
    realistic: float
    note: str
    random: bool = False

    @property
    def signed(self) -> bool:
        return self.lo < 0.0 < self.hi


LIBRARY: dict[str, Candidate] = {
    c.name: c
    for c in (
        Candidate("friction", 0.0, 1.0, (0.5,), 0.5, "Coulomb coefficient on the pillar"),
        # k = 1: the first-reflection (Faxén) drag itself; contact dwell +14-36 %. At 0.5
        # (the source's "about 10 % slower") 60 fibers show only a t_pass shift, which a
        # 2.5 % slower inlet explains as well (docs/discrepancy.md, the study)
        Candidate("pillar_hydro", 0.0, 3.0, (1.0,), 1.0, "multiplier on the Faxén pillar drag"),
        # k = 1: the sphere-wall theory's drag and flow push of the pillar on each bead
        Candidate("near_wall", 0.0, 2.0, (1.0,), 1.0, "multiplier on the sphere-wall theory"),
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
