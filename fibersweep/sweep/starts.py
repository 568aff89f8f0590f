"""Physics checks of a config: start points a fiber the grid resolves, in the channel,
off the pillar, and swept effects in their range, checked before any flow field is
computed (:data:`PHYSICS`, handed to ``load_config``).

The same check a run makes (:func:`fibersweep.fiber.setup.check_start`), applied to
the sweep points that could fail it (:func:`starts_to_check`), so a 200 000-point
sweep is checked in a fraction of a second.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fibersweep.config.errors import FieldError
from fibersweep.config.sweep_axes import PhysicsChecks, SweepSettings
from fibersweep.errors import InputError
from fibersweep.fiber.result import FiberStart

__all__ = ["PHYSICS", "check_effects", "check_starts", "grid_starts", "starts_to_check"]


def check_starts(cfg: Any) -> None:
    """Every sweep point must be a fiber the grid resolves, in the channel, off the pillar.

    Checked when a config is validated, before any flow field is computed, with the
    same check a run makes (:func:`fibersweep.fiber.setup.check_start`); effects that move the
    start (start noise, pillar scale) are applied per run and checked there.

    Raises
    ------
    FieldError
        At the first field (``sweep.<axis>`` or ``fiber.x0``) with a bad point.
    """
    if cfg.sweep.setting_keys:
        return  # each setting combination is checked as a config of its own
    if cfg.flow.array is not None:  # a pillar array: its own units and checks
        from fibersweep.sweep.array_starts import check_array_config

        check_array_config(cfg)
    if cfg.sweep.random is not None:  # drawn starts: placed clear, or the length is bad
        from fibersweep.sweep.draws import start_points

        try:
            start_points(cfg)
        except InputError as exc:
            name, _, msg = str(exc).partition(": ")
            raise FieldError("fiber.x0" if name == "x0" else f"sweep.{name}", msg) from None
        return
    if cfg.flow.array is not None:
        return
    from fibersweep.fiber.contact.pillar import make_pillar  # numba-backed: import lazily
    from fibersweep.fiber.setup import check_start

    geo = cfg.flow.geometry.to_geometry()
    pillar = make_pillar(geo, cfg.fiber.contact, cfg.fiber.bead_radius, 1.0)
    bad: dict[str, str] = {}
    for start in starts_to_check(cfg, geo, pillar.r_cut):
        try:
            check_start(geo, cfg.flow.dx, cfg.fiber, start, pillar)
        except InputError as exc:
            name, _, msg = str(exc).partition(": ")
            # x0 is a fiber setting; the other names are sweep axes.
            path = "fiber.x0" if name == "x0" else f"sweep.{name}"
            bad.setdefault(path, msg)  # first problem per field is enough to act on
    if bad:
        path, msg = next(iter(bad.items()))
        raise FieldError(path, msg)


def starts_to_check(cfg: Any, geo: Any, r_cut: float) -> list[FiberStart]:
    """The sweep points that could fail :func:`check_start`, in sweep order.

    A point is skipped only when it provably passes: its length was checked on
    another point (the length rules depend on L alone), and a disc around its
    centre that holds every bead, with the pillar's cutoff and a grid spacing
    to spare, lies inside the channel and clear of the pillar's bounding box.
    So the first failing point per field is the same as checking every point,
    and a 200 000-point sweep is checked in a fraction of a second.
    """
    t, y, L = cfg.sweep.grid()
    a = cfg.fiber.bead_radius
    x0 = geo.length / 4.0 if cfg.fiber.x0 is None else float(cfg.fiber.x0)
    yc = np.array([geo.y_from_base(v) for v in (0.0, 1.0)])
    y_abs = yc[0] + y * (yc[1] - yc[0])  # y_from_base is affine in y0
    reach = L * geo.pillar_base_length / 2.0 + 2.0 * a + cfg.flow.dx
    x_lo, y_lo, x_hi, y_hi = geo.shape.bounds
    lo, hi = (x_lo, y_lo), (x_hi, y_hi)
    gap_x = np.maximum(np.maximum(lo[0] - x0, x0 - hi[0]), 0.0)
    gap_y = np.maximum(np.maximum(lo[1] - y_abs, y_abs - hi[1]), 0.0)
    clear = (
        (y_abs - reach > 0.0)
        & (y_abs + reach < geo.width)
        & (x0 - reach > 0.0)
        & (x0 + reach < geo.length)
        & (np.hypot(gap_x, gap_y) > reach + r_cut)
    )
    _, first_of_length = np.unique(L, return_index=True)
    clear[first_of_length] = False
    idx = np.flatnonzero(~clear)
    return [FiberStart(theta0=float(t[i]), y0=float(y[i]), length=float(L[i])) for i in idx]


def check_effects(values: dict[str, Any], locs: dict[str, tuple]) -> list[str]:
    """Swept effects exist and take the value (the registry checks names and ranges).

    Returns
    -------
    list of str
        The swept effect keys whose value is the effect's baseline (inactive).
    """
    keys = [k for k in values if k.startswith("fiber.effects.")]
    if not keys:
        return []
    from fibersweep.fiber.effects import build_effects  # numba-backed: import lazily

    off = []
    for key in keys:
        try:
            made = build_effects({key.split(".", 2)[2]: values[key]})
        except InputError as exc:
            msg = str(exc).removeprefix("effects: ")
            raise FieldError(locs[key], f"value {values[key]!r}: {msg}") from None
        if not made.effects:
            off.append(key)
    return off


def grid_starts(sweep: SweepSettings) -> list[FiberStart]:
    """The grid of start axes as starts: their Cartesian product, ordered length, y0, theta0."""
    return [
        FiberStart(theta0=float(t), y0=float(y), length=float(L))
        for t, y, L in zip(*sweep.grid(), strict=True)
    ]


#: The physics checks a config is loaded with for a sweep or a run
#: (``load_config(path, physics=PHYSICS)``, ``cfg.combinations(PHYSICS)``).
PHYSICS = PhysicsChecks(check=check_starts, effects_off=check_effects)
