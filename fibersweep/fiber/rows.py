"""Fibers through many rows of a pillar array: the array case of the channel's integrators.

An array run is the channel's fiber model and integrator
(:mod:`fibersweep.fiber.models.registry`: mobility, effects' stages, step rule, stop
rule; for the rigid model its implicit stopped steps) in the
:class:`~fibersweep.fiber.frame.Lattice` frame. This module only
assembles the run's :class:`~fibersweep.fiber.kernel.bundles.Kernel`, as
:func:`fibersweep.fiber.kernel.bundles.build_kernel` does for the channel:

- the field: the unit cell padded with its periodic images
  (:meth:`fibersweep.flow.cell.CellField.extended`);
- the pillar: the cell's own (row 0, column 0), rough or smooth, any shape;
  the frame sums the contact of every image within reach;
- the scalars (:func:`~fibersweep.fiber.kernel.bundles.make_params`): no side walls;
  the run passes when its rear end crosses ``x_end`` (after the configured
  rows), and is trapped, fails or times out by the channel's rule;
- the effects: the settings' kernel effects (friction, pillar hydrodynamics,
  Brownian motion, off-midplane, ...). Effects that change the channel's
  field, start or report (inlet speed, pillar scale, start noise) have no
  meaning here yet and are refused by :func:`check_array_effects`.

The fiber lives in unwrapped lab coordinates (x along the flow, y across,
[µm]). The record is the channel's (:data:`fibersweep.fiber.kernel.record.COLS`);
its ``contact`` column holds the number of pillars in contact (two when a
fiber bridges a gap).
"""

from __future__ import annotations

import math

import numpy as np

from fibersweep.config.fiber import FiberSettings
from fibersweep.errors import InputError
from fibersweep.fiber import frame as F
from fibersweep.fiber.contact.pillar import Pillar, contact_force_scale, make_pillar
from fibersweep.fiber.effects import DynamicsContext, EffectSet, build_effects
from fibersweep.fiber.effects.base import Effect
from fibersweep.fiber.kernel.bundles import FlowArrays, Kernel, assemble, make_params
from fibersweep.fiber.models.registry import get_integrator
from fibersweep.fiber.models.spacing import bead_force_scale

__all__ = ["PAD", "array_kernel", "array_pillar", "check_array_effects", "run_array_fiber"]

#: Nodes of periodic images around the cell field (the IB kernel reaches 2).
PAD = 3


def check_array_effects(settings: FiberSettings) -> EffectSet:
    """The settings' active effects; InputError naming one an array run cannot apply.

    An effect acts in an array when all it does is in the kernels (its record's
    stages); one that transforms the channel's flow field, start or report
    (``transform_field``, ``transform_start``, ``transform_result``) is refused.
    """
    effects = build_effects(settings.effects)
    effects.check_model(settings.model)
    for e in effects.effects:
        hooks = [
            h
            for h in ("transform_field", "transform_start", "transform_result")
            if getattr(type(e), h) is not getattr(Effect, h)
        ]
        if hooks:
            raise InputError(
                f"effects.{e.name}: changes the single-pillar channel's "
                f"{' and '.join(h.split('_')[1] for h in hooks)}; not available in pillar "
                "arrays (effects acting in the kernels are: those without these hooks)"
            )
    return effects


def array_pillar(array, settings: FiberSettings, mu: float, u_center: float) -> Pillar:
    """The cell's pillar with the channel's contact law (F_ref = 6πμa|u_center| unless set;
    per bead, times b/2a for a chain finer than touching beads, :mod:`.spacing`)."""
    a = settings.bead_radius
    f_ref = contact_force_scale(settings.contact, mu, a, u_center)
    f_ref *= bead_force_scale(settings.bead_spacing)
    return make_pillar(array.cell_geometry, settings.contact, a, f_ref)


def array_kernel(
    field,
    settings: FiberSettings,
    n_beads: int,
    *,
    mu: float,
    u_center: float,
    x_end: float,
    mode: int = 0,
    t_stop: float = math.nan,
    effects: EffectSet | None = None,
    pillar: Pillar | None = None,
) -> Kernel:
    """The kernel of one fiber in a pillar array.

    Parameters
    ----------
    field : fibersweep.flow.cell.CellField
        The unit-cell field [µm/s] and its array.
    settings : FiberSettings
        Model, contact, step, trap rule and effects, as in the channel.
    n_beads : int
        Beads (1: a sphere).
    mu : float
        Viscosity [pN s/µm²].
    u_center : float
        Midplane speed of the field's flux [µm/s] (contact force scale, trap speed).
    x_end : float
        The run passes when its rear end crosses this x [µm].
    mode, t_stop : int, float
        0: stop after ``x_end``; 1: stop at ``t_stop`` [s]
        (:func:`~fibersweep.fiber.kernel.bundles.make_params`).
    effects, pillar : EffectSet, Pillar, optional
        :func:`check_array_effects` and :func:`array_pillar` of these settings, when the
        caller has them already (the array case checked the start with them).
    """
    array = field.array
    if effects is None:
        effects = check_array_effects(settings)
    if pillar is None:
        pillar = array_pillar(array, settings, mu, u_center)
    arrays = pillar.arrays()
    frame = F.lattice(array, PAD, float(field.dx), n_beads)
    ux, uy = field.extended(PAD)
    flow = FlowArrays(ux, uy, float(field.dx))
    ctx = DynamicsContext(
        bead_radius=settings.bead_radius,
        dx=float(field.dx),
        depth=float(array.depth),
        viscosity=mu,
        n_beads=n_beads,
        pillar=arrays,
        frame=frame,
        flow=flow,
        curvature=settings.contact.curvature == "local",
        corner_radius=float(settings.contact.corner_radius),
    )
    params = make_params(
        settings,
        mu=mu,
        u_center=u_center,
        x_stop=float(x_end),
        y_lo=-math.inf,
        y_hi=math.inf,
        random=effects.random,
        mode=mode,
        t_stop=t_stop,
    )
    sampled = effects.sample_flow(flow, float(settings.bead_radius))
    return assemble(settings, n_beads, sampled, arrays, params, effects.kernel(ctx), frame)


def run_array_fiber(
    k: Kernel, model: str, x0: float, y0: float, th0: float, integrator: str | None = None
) -> tuple[np.ndarray, int]:
    """Integrate one fiber from centre (x0, y0) [µm], angle th0 [rad] with ``model``.

    ``integrator``: one of the model's (None: its default); ``k`` must be built for it.
    Returns the record (rows, :data:`fibersweep.fiber.kernel.record.NCOLS`) and the stop code.
    """
    rec, _, code = get_integrator(model, integrator).integrate(k, x0, y0, th0, None)
    return rec, int(code)
