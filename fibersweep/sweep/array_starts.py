"""Checks of a pillar-array config (``flow.array`` set) that need the fiber and the sweep.

The flow section checks the array and its lattice on its own
(:mod:`fibersweep.config.array`); here: the fiber model and effects an
array run takes, the gap against the fiber's diameter, and the start points
(y0 a fraction of ``period_y`` in [0, 1], lengths of at least one bead, grid
starts clear of the pillars: one that is not names the free ranges of y0 at its
angle and length). Each problem is a ``FieldError`` at its field.
"""

from __future__ import annotations

from typing import Any

from fibersweep.config.errors import FieldError
from fibersweep.errors import InputError
from fibersweep.geometry.array import ArrayError

__all__ = ["check_array_config"]


def check_array_config(cfg: Any) -> None:
    """Every fiber of the sweep can run in the array (see the module docstring).

    Raises
    ------
    FieldError
        At ``fiber.model``, ``fiber.effects``, ``flow.array.period_y`` (gap),
        ``sweep.length`` or ``sweep.y0``.
    """
    import numpy as np

    from fibersweep.config.axes import axis_values
    from fibersweep.fiber.array_run import n_beads_of, start_clear
    from fibersweep.fiber.rows import array_pillar, check_array_effects

    fiber = cfg.fiber
    try:
        check_array_effects(fiber)
    except InputError as exc:
        raise FieldError("fiber.effects", str(exc)) from None
    array = cfg.flow.array.to_array()
    try:
        array.check_fiber(fiber.bead_radius)
    except ArrayError as exc:
        raise FieldError(("flow", "array", exc.field), str(exc)) from None
    lengths = axis_values(cfg.sweep.length)
    short = lengths[lengths < 2.0 * fiber.bead_radius - 1e-9]
    if short.size:
        raise FieldError(
            "sweep.length",
            f"L = {short[0]:g} µm is shorter than one bead (2a = {2 * fiber.bead_radius:g} µm); "
            "in a pillar array lengths are in µm",
        )
    if fiber.model != "rigid":
        from fibersweep.fiber.setup import MIN_BEADS

        few = [
            float(L)
            for L in lengths
            if n_beads_of(float(L), fiber.bead_radius, fiber.bead_spacing) < MIN_BEADS
        ]
        if few:
            n_few = n_beads_of(few[0], fiber.bead_radius, fiber.bead_spacing)
            raise FieldError(
                "sweep.length",
                f"L = {few[0]:g} µm is {n_few} bead(s); the "
                f"{fiber.model} model needs at least {MIN_BEADS} (a sphere runs with the rigid "
                "model)",
            )
    y = axis_values(cfg.sweep.y0)
    if np.any((y < 0) | (y > 1)):
        raise FieldError(
            "sweep.y0",
            f"y0 = {y[(y < 0) | (y > 1)][0]:g}: in a pillar array y0 is the lateral start as "
            "a fraction of period_y, in [0, 1]",
        )
    if getattr(cfg.sweep, "random", None) is not None:
        return  # random starts that touch a pillar are drawn again
    pillar = array_pillar(array, fiber, cfg.flow.fluid.viscosity, cfg.flow.fluid.u_center)
    t = axis_values(cfg.sweep.theta0)
    for L in lengths:
        n = n_beads_of(float(L), fiber.bead_radius, fiber.bead_spacing)
        for yi in y:
            for ti in t:
                if not start_clear(
                    array, pillar, n, fiber.bead_radius, float(yi), float(ti), fiber.bead_spacing
                ):
                    from fibersweep.sweep.draws import free_text

                    raise FieldError(
                        "sweep.y0",
                        f"the fiber of L = {L:g} µm at y0 = {yi:g} (fraction of period_y), "
                        f"theta0 = {ti:g} deg touches a pillar at the start; "
                        f"{free_text(cfg, float(ti), float(L))}",
                    )
