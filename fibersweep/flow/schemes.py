"""The flow solver's collision and pillar-wall schemes, each a registry entry.

Like the steppers (:mod:`fibersweep.flow.steppers`), a scheme is chosen by its
name in the settings (``FlowSettings.collision``, ``FlowSettings.pillar_boundary``)
and looked up here; the solver never compares scheme names. A lookup of an
unknown name fails listing the valid ones.

* :data:`COLLISIONS`: the relaxation rates (ω+, ω−) of the collision operator
  from the relaxation time τ and the TRT magic parameter Λ.
* :data:`WALL_SCHEMES`: how the pillar wall enters the lattice: half-way
  bounce-back on the staircase of solid cells, or interpolated bounce-back at
  the exact sub-grid wall (its link interpolation, :mod:`fibersweep.flow.ibb`);
  a sub-grid wall also closes the pillar's outline nodes and stores ghost
  values inside the wall for the fiber's interpolation.

A new scheme is its entry here (with its kernel or link interpolation where
that is new) and its name in the ``Literal`` of :class:`FlowSettings` (a
contract test checks that the two agree).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

__all__ = [
    "COLLISIONS",
    "WALL_SCHEMES",
    "CollisionScheme",
    "WallScheme",
    "get_collision",
    "get_wall_scheme",
]


@dataclass(frozen=True)
class CollisionScheme:
    """A collision operator of the D3Q19 kernels (two relaxation rates).

    Attributes
    ----------
    name : str
    description : str
    rates : callable (tau, magic) -> (omega_plus, omega_minus)
        Relaxation rates of the even and odd moments from τ (> 1/2) and Λ.
    """

    name: str
    description: str
    rates: Callable[[float, float], tuple[float, float]]


def _bgk(tau: float, magic: float) -> tuple[float, float]:
    omega = 1.0 / tau
    return omega, omega


def _trt(tau: float, magic: float) -> tuple[float, float]:
    # Λ = (1/ω+ − 1/2)(1/ω− − 1/2)
    return 1.0 / tau, 1.0 / (magic / (tau - 0.5) + 0.5)


COLLISIONS: dict[str, CollisionScheme] = {
    s.name: s
    for s in (
        CollisionScheme(
            "trt",
            "two relaxation times, ω− set by the magic parameter Λ (walls where Λ puts them)",
            _trt,
        ),
        CollisionScheme("bgk", "one relaxation time (ω+ = ω− = 1/τ)", _bgk),
    )
}


@dataclass(frozen=True)
class WallScheme:
    """How the pillar wall enters the lattice.

    Attributes
    ----------
    name : str
    description : str
    links : str or None
        Interpolation of the cut links (:func:`fibersweep.flow.ibb.family_coefficients`
        scheme, 'trt' or 'bfl'); None: half-way bounce-back on the solid cells.
    """

    name: str
    description: str
    links: str | None

    @property
    def sub_grid(self) -> bool:
        """Whether the wall sits at its exact sub-grid position (interpolated links):
        the pillar's outline nodes are closed and ghost values are stored in the wall."""
        return self.links is not None


WALL_SCHEMES: dict[str, WallScheme] = {
    s.name: s
    for s in (
        WallScheme(
            "interpolated",
            "interpolated bounce-back at the exact wall, the TRT-exact member of the linear "
            "family (second order)",
            "trt",
        ),
        WallScheme("bfl", "plain linear Bouzidi-Firdaouss-Lallemand interpolation", "bfl"),
        WallScheme(
            "staircase", "half-way bounce-back on the staircase of solid cells (first order)", None
        ),
    )
}


def _get(registry: dict, name: str, what: str):  # noqa: ANN202 - either scheme type
    try:
        return registry[name]
    except KeyError:
        raise ValueError(f"unknown {what} {name!r}; valid: {list(registry)}") from None


def get_collision(name: str) -> CollisionScheme:
    """The collision scheme called ``name``; unknown names fail listing the valid ones."""
    return _get(COLLISIONS, name, "collision")


def get_wall_scheme(name: str) -> WallScheme:
    """The pillar-wall scheme called ``name``; unknown names fail listing the valid ones."""
    return _get(WALL_SCHEMES, name, "pillar boundary")
