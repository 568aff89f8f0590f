"""Validation of one run's input (the kernel bundles are built from it in :mod:`.bundles`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from fibersweep.config.fiber import FiberSettings
from fibersweep.errors import InputError
from fibersweep.fiber.contact.pillar import Pillar, contact_force_scale, make_pillar
from fibersweep.fiber.effects import DynamicsContext, EffectSet, build_effects
from fibersweep.fiber.models.spacing import bead_force_scale, n_beads, offsets
from fibersweep.fiber.result import FiberStart
from fibersweep.flow.field import FlowField
from fibersweep.units import Geometry

__all__ = ["MIN_BEADS", "Setup", "StartPlacement", "check_start", "prepare"]

MIN_BEADS = 2


@dataclass(frozen=True)
class Setup:
    """Everything a kernel needs for one run, validated.

    Attributes
    ----------
    field : FlowField
        The (effect-transformed) field.
    settings : FiberSettings
    start : FiberStart
    n : int
        Beads.
    x0, y0_abs, th0 : float
        Start centre [µm] and directed angle of the axis towards bead n-1 [rad]
        (bead n-1 is the head: the one that leads).
    pillar : Pillar
    kernel_effects : tuple
        Kernel records of the active effects that act in the integrators
        (:meth:`EffectSet.kernel`, sorted by effect name).
    u_center : float
        Signed centreline speed of the field [µm/s].
    effects : EffectSet
        The run's active effects (their ``result`` hook converts the report).
    """

    field: FlowField
    settings: FiberSettings
    start: FiberStart
    n: int
    x0: float
    y0_abs: float
    th0: float
    pillar: Pillar
    kernel_effects: tuple
    u_center: float
    effects: EffectSet


def _finite(name: str, value: float) -> None:
    if not math.isfinite(value):
        raise InputError(f"{name}: must be finite, got {value!r}")


class _FieldArrays(NamedTuple):
    """The channel's field as an effect's kernel may read it: ``ux, uy`` (nx, ny) [µm/s],
    node spacing ``dx`` [µm] (:attr:`DynamicsContext.flow`)."""

    ux: np.ndarray
    uy: np.ndarray
    dx: float


@dataclass(frozen=True)
class StartPlacement:
    """Where a checked start puts the fiber.

    Attributes
    ----------
    n : int
        Beads.
    x0, y0_abs : float
        Centre of mass [µm].
    th0 : float
        Directed angle of the axis towards bead n-1, the head [rad].
    """

    n: int
    x0: float
    y0_abs: float
    th0: float


def check_start(
    geo: Geometry,
    dx: float,
    settings: FiberSettings,
    start: FiberStart,
    pillar: Pillar | None = None,
) -> StartPlacement:
    """Check that a start is a fiber the grid resolves, in the channel, clear of the pillar.

    Needs only the geometry and grid spacing, so a config can be checked before
    any flow field exists.

    Parameters
    ----------
    geo : Geometry
    dx : float
        Grid spacing of the flow field [µm].
    settings : FiberSettings
    start : FiberStart
    pillar : Pillar, optional
        The run's pillar; built from ``settings.contact`` when omitted (only its
        outline and cutoff are used here).

    Raises
    ------
    InputError
        Naming the parameter (theta0, y0, length or x0) that is bad.
    """
    for name in ("theta0", "y0", "length"):
        _finite(name, float(getattr(start, name)))
    a = settings.bead_radius
    length_um = start.length * geo.pillar_base_length
    n = n_beads(length_um, a, settings.bead_spacing)
    if start.length <= 0 or n < MIN_BEADS:
        raise InputError(
            f"length: L/l_obs = {start.length} is {length_um:.3g} µm, {n} bead(s) of "
            f"radius {a} µm; at least {MIN_BEADS} beads are needed"
        )
    if length_um < 2.0 * dx:
        raise InputError(
            f"length: L = {length_um:.3g} µm is shorter than two grid spacings "
            f"(dx = {dx} µm): the flow field cannot resolve it"
        )
    x0 = geo.length / 4.0 if settings.x0 is None else float(settings.x0)
    _finite("x0", x0)
    y0_abs = geo.y_from_base(start.y0)
    th0 = math.radians(start.theta0)
    if math.cos(th0) < 0.0:  # keep bead n-1 as the leading bead (the head)
        th0 += math.pi
    s = offsets(n, a, settings.bead_spacing)
    bx = x0 + s * math.cos(th0)
    by = y0_abs + s * math.sin(th0)
    if by.min() - a <= 0.0 or by.max() + a >= geo.width:
        raise InputError(
            f"y0: y0/h = {start.y0} with theta0 = {start.theta0}° puts beads outside the "
            f"channel (bead y from {by.min():.1f} to {by.max():.1f} µm, width {geo.width} µm)"
        )
    if bx.min() - a <= 0.0 or bx.max() + a >= geo.length:
        raise InputError(f"x0: the fiber at x0 = {x0} µm does not fit in the channel length")
    if pillar is None:
        pillar = make_pillar(geo, settings.contact, a, 1.0)  # force scale unused here
    for xb, yb in zip(bx, by, strict=True):
        d = pillar.distance(xb, yb)
        if d < pillar.r_cut:
            raise InputError(
                f"y0: the start (theta0 = {start.theta0}°, y0/h = {start.y0}, x0 = {x0} µm) "
                f"overlaps the pillar (bead at {d:.2f} µm from its outline)"
            )
    return StartPlacement(n, x0, y0_abs, th0)


def prepare(
    field: FlowField, settings: FiberSettings, start: FiberStart, rng: np.random.Generator
) -> Setup:
    """Apply effects and check the start; InputError naming the parameter when it is bad."""
    effects = build_effects(settings.effects)
    effects.check_model(settings.model)
    field = effects.field(field)
    start = effects.start(start, rng)
    geo = field.geometry
    a = settings.bead_radius
    u_center = float(field.fluid.u_center)
    _finite("u_center", u_center)
    if u_center == 0.0:
        raise InputError("u_center: the field has zero speed")
    f_ref = contact_force_scale(settings.contact, field.fluid.viscosity, a, u_center)
    pillar = make_pillar(geo, settings.contact, a, f_ref * bead_force_scale(settings.bead_spacing))
    place = check_start(geo, float(field.dx), settings, start, pillar)
    ctx = DynamicsContext(
        bead_radius=a,
        dx=float(field.dx),
        depth=geo.depth,
        viscosity=field.fluid.viscosity,
        n_beads=place.n,
        pillar=pillar.arrays(),
        flow=_FieldArrays(field.ux, field.uy, float(field.dx)),
        curvature=settings.contact.curvature == "local",
        corner_radius=float(settings.contact.corner_radius),
    )
    kernel_effects = effects.kernel(ctx)
    return Setup(
        field,
        settings,
        start,
        place.n,
        place.x0,
        place.y0_abs,
        place.th0,
        pillar,
        kernel_effects,
        u_center,
        effects,
    )
