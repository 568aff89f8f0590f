"""The start points of a sweep: the grid of the start axes, or seeded random draws.

With ``sweep.random: {count: N, seed: S}`` every length gets N starts drawn
uniform in the ``theta0`` and ``y0`` ranges ``[lo, hi]``; a start that touches
the pillar (a channel: the run's own start check,
:func:`fibersweep.fiber.setup.check_start`; an array: any pillar within the
contact cutoff, :func:`fibersweep.fiber.array_run.start_clear`) is drawn again.
The generator of a length is seeded by ``(S, the bits of L)``: the same config
gives the same starts, a length added later leaves the others' draws as they
were (so a resumed sweep keeps its run ids), and every setting combination
draws from the same stream (common random numbers; only redraws differ).

:func:`free_starts` gives, with the same check, the ranges of y0 where a start at a
given angle and length is clear, and :func:`check_start_of` refuses one start that
is not, naming those ranges, before any flow field or kernel is made (``simulate``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from fibersweep.config.axes import axis_values
from fibersweep.errors import InputError
from fibersweep.fiber.result import FiberStart

__all__ = [
    "MAX_TRIES_PER_START",
    "check_start_of",
    "free_starts",
    "free_text",
    "start_points",
]

#: Draws per accepted start before a length is declared impossible to place.
MAX_TRIES_PER_START = 1000


def _range(axis: Any) -> tuple[float, float]:
    v = axis_values(axis)
    return float(v[0]), float(v[-1])


def _clear_test(cfg: Any) -> Callable[[float, float, float], bool]:
    """(theta0, y0, length) -> whether that start is clear (raises for a bad length)."""
    fiber = cfg.fiber
    if cfg.flow.array is not None:
        from fibersweep.fiber.array_run import n_beads_of, start_clear
        from fibersweep.fiber.rows import array_pillar

        array = cfg.flow.array.to_array()
        pillar = array_pillar(array, fiber, cfg.flow.fluid.viscosity, cfg.flow.fluid.u_center)

        def clear(t: float, y: float, L: float) -> bool:
            n = n_beads_of(L, fiber.bead_radius, fiber.bead_spacing)
            return start_clear(array, pillar, n, fiber.bead_radius, y, t, fiber.bead_spacing)

        return clear
    from fibersweep.fiber.contact.pillar import make_pillar
    from fibersweep.fiber.setup import check_start

    geo = cfg.flow.geometry.to_geometry()
    pillar = make_pillar(geo, fiber.contact, fiber.bead_radius, 1.0)

    def clear_channel(t: float, y: float, L: float) -> bool:
        try:
            check_start(geo, cfg.flow.dx, fiber, FiberStart(t, y, L), pillar)
        except InputError as exc:
            if str(exc).startswith(("length", "x0", "theta0")):
                raise  # no redraw of the position mends these
            return False
        return True

    return clear_channel


def start_points(cfg: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The sweep's start points (theta0 [deg], y0, length), length varying slowest.

    Parameters
    ----------
    cfg : Config
        Without ``sweep.random``: its grid (:meth:`SweepSettings.grid`).

    Raises
    ------
    InputError
        A length whose fiber cannot be placed (``length: ...``), or no clear start
        found in ``MAX_TRIES_PER_START`` draws per start (``y0: ...``).
    """
    r = cfg.sweep.random
    if r is None:
        return cfg.sweep.grid()
    t_lo, t_hi = _range(cfg.sweep.theta0)
    y_lo, y_hi = _range(cfg.sweep.y0)
    clear = _clear_test(cfg)
    ts, ys, Ls = [], [], []
    for L in axis_values(cfg.sweep.length).tolist():
        rng = np.random.default_rng([r.seed, int(np.float64(L).view(np.uint64))])
        got = 0
        for _ in range(MAX_TRIES_PER_START * r.count):
            t = float(rng.uniform(t_lo, t_hi))
            y = float(rng.uniform(y_lo, y_hi))
            if clear(t, y, L):
                ts.append(t)
                ys.append(y)
                Ls.append(L)
                got += 1
                if got == r.count:
                    break
        else:
            raise InputError(
                f"y0: no start of the fiber of length {L:g} clears the pillars in "
                f"{MAX_TRIES_PER_START * r.count} draws over y0 in [{y_lo:g}, {y_hi:g}], "
                f"theta0 in [{t_lo:g}, {t_hi:g}]; widen the ranges or shorten the fiber"
            )
    return np.array(ts), np.array(ys), np.array(Ls, dtype=np.float64)


#: y0 samples of :func:`free_starts` (each edge then bisected to :data:`_EDGE_TOL`).
FREE_SAMPLES = 400
_EDGE_TOL = 1e-6


def _y0_domain(cfg: Any) -> tuple[float, float]:
    """The y0 a start can have: [0, 1] of period_y in an array; across the channel in
    h_obs from the pillar's base line past one pillar."""
    if cfg.flow.array is not None:
        return 0.0, 1.0
    geo = cfg.flow.geometry.to_geometry()
    return float(geo.y_over_h(0.0)), float(geo.y_over_h(geo.width))


def free_starts(
    cfg: Any, theta0: float, length: float, samples: int = FREE_SAMPLES
) -> list[tuple[float, float]]:
    """The intervals of y0 whose start at ``theta0`` [deg] and ``length`` is clear.

    The check is the run's own (:func:`_clear_test`: a pillar array's contact cutoff
    round every pillar image, the channel's walls and pillar). y0 is sampled at
    ``samples`` points across its range, and each edge is bisected to 1e-6.

    Parameters
    ----------
    cfg : Config
    theta0 : float
        Start angle [deg].
    length : float
        Fiber length: L [µm] in an array, L/l_obs past one pillar.

    Returns
    -------
    list of (float, float)
        Free intervals of y0 (a fraction of period_y in an array, y0/h_obs past one
        pillar), increasing; empty when no y0 is free.

    Raises
    ------
    InputError
        A length no position mends (too short to resolve, or a fiber longer than the
        channel).
    """
    clear = _clear_test(cfg)
    lo, hi = _y0_domain(cfg)
    ys = np.linspace(lo, hi, samples + 1)
    ok = np.array([clear(float(theta0), float(y), float(length)) for y in ys])

    def edge(a: float, b: float) -> float:  # clear at a, not at b (or the reverse)
        want = clear(float(theta0), a, float(length))
        while abs(b - a) > _EDGE_TOL:
            m = 0.5 * (a + b)
            if clear(float(theta0), m, float(length)) == want:
                a = m
            else:
                b = m
        return a

    out = []
    k = 0
    while k < len(ys):
        if not ok[k]:
            k += 1
            continue
        j = k
        while j + 1 < len(ys) and ok[j + 1]:
            j += 1
        start = ys[k] if k == 0 else edge(float(ys[k]), float(ys[k - 1]))
        end = ys[j] if j == len(ys) - 1 else edge(float(ys[j]), float(ys[j + 1]))
        out.append((float(start), float(end)))
        k = j + 1
    return out


def free_text(cfg: Any, theta0: float, length: float) -> str:
    """'free starts at θ0 = 0°, L = 40 µm: y0 in [0.0313, 0.4119] ∪ [0.6033, 0.9811]'."""
    array = cfg.flow.array is not None
    what = f"L = {length:g} µm" if array else f"L/l_obs = {length:g}"
    unit = "" if array else " (y0/h_obs)"
    spans = free_starts(cfg, theta0, length)
    if not spans:
        lo, hi = _y0_domain(cfg)
        return (
            f"no start at θ0 = {theta0:g}°, {what} is free for y0 in [{lo:.4g}, {hi:.4g}]: "
            "change θ0 or the length"
        )
    joined = " ∪ ".join(f"[{a:.4f}, {b:.4f}]" for a, b in spans)
    return f"free starts at θ0 = {theta0:g}°, {what}: y0 in {joined}{unit}"


def check_start_of(cfg: Any, theta0: float, y0: float, length: float) -> None:
    """Refuse a start that touches a pillar (or, past one pillar, leaves the channel),
    naming the free y0 at its angle and length; nothing is computed but geometry.

    The run checks the same when it places the fiber, but only after the flow field
    and the kernels are ready; this check comes first. Starts the run would refuse
    for another reason (a y0 outside [0, 1] in an array, a length too short) are left
    to the run, which names them; past one pillar with an effect that moves the start
    (its start is drawn by the run) nothing is checked here.

    Raises
    ------
    InputError
        ``y0: ...`` with the free ranges (:func:`free_text`).
    """
    import math

    fiber = cfg.fiber
    if not all(math.isfinite(v) for v in (theta0, y0, length)):
        return
    if cfg.flow.array is not None:
        from fibersweep.fiber.array_run import n_beads_of
        from fibersweep.fiber.setup import MIN_BEADS

        if not 0.0 <= y0 <= 1.0 or length < 2.0 * fiber.bead_radius - 1e-9:
            return
        n = n_beads_of(length, fiber.bead_radius, fiber.bead_spacing)
        if fiber.model != "rigid" and n < MIN_BEADS:
            return
        if not _clear_test(cfg)(theta0, y0, length):
            raise InputError(
                f"y0: the fiber at y0 = {y0:g} (fraction of period_y), theta0 = {theta0:g} deg "
                f"touches a pillar at the start; {free_text(cfg, theta0, length)}"
            )
        return
    if any(v != 0 for v in fiber.effects.values()):
        return
    from fibersweep.fiber.setup import check_start

    try:
        check_start(cfg.flow.geometry.to_geometry(), cfg.flow.dx, fiber,
                    FiberStart(theta0, y0, length))  # fmt: skip
    except InputError as exc:
        if not str(exc).startswith("y0"):
            raise
        raise InputError(f"{exc}; {free_text(cfg, theta0, length)}") from None
