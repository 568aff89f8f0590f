"""Measured-like fibers through a pillar array with hidden effects (``synth`` on an array).

As :mod:`.synth` does past one pillar: true starts uniform in the box of the
config's sweep axes (θ0 [deg], y0 [fraction of period_y], L [µm]), redrawn where
the fiber would touch a pillar at its start (an array sweep cannot start it
there either); reported starts with the start noise of :func:`.copies.array_noise`;
every fiber run through ``fiber.array_rows`` rows at its *true* start with the
hidden effects on; its observables (:mod:`.array_observables`) with their
measurement noise. The table follows :mod:`.array_schema`; the truth (effects,
noise, seed, true starts, failures) is returned apart.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.array_schema import validate_array_measured
from fibersweep.discrepancy.array_starts import AXES as _AXES
from fibersweep.discrepancy.array_starts import redraw_clear
from fibersweep.discrepancy.copies import NoiseModel, array_noise
from fibersweep.discrepancy.observables import OBSERVABLES, noise_draws, of_geometry
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.errors import InputError

__all__ = ["array_effects_check", "synthesize_array"]

log = logging.getLogger(__name__)


def array_effects_check(fiber: FiberSettings, effects: Mapping[str, float], what: str) -> None:
    """InputError naming an effect a pillar-array run cannot apply (before any run).

    ``what`` names the source in the message (e.g. '--effect', 'candidate').
    """
    from fibersweep.fiber.rows import check_array_effects

    on = {k: float(v) for k, v in effects.items() if float(v) != 0.0}
    try:
        check_array_effects(fiber.model_copy(update={"effects": {**fiber.effects, **on}}))
    except InputError as exc:
        raise InputError(f"{what}: {exc}") from None


def synthesize_array(
    field: Any,
    fiber: FiberSettings,
    box: Mapping[str, tuple[float, float]],
    n: int,
    effects: Mapping[str, float] | None = None,
    noise: NoiseModel | None = None,
    seed: int = 0,
    workers: int = 2,
    progress: bool = True,
    executor: str = "local",
    scheduler: str | None = None,
) -> tuple[pd.DataFrame, dict[str, Any]]:
    """An array measured table and its truth.

    Parameters
    ----------
    field : fibersweep.flow.cell.CellField
        The array's unit-cell field (baseline).
    fiber : FiberSettings
        Fiber settings (``array_rows`` rows); ``effects`` are added to its own.
    box : mapping 'theta0' | 'y0' | 'length' -> (lo, hi)
        Range of the true starts [deg, fraction of period_y, µm].
    n : int
        Fibers.
    effects : mapping name -> value
        Hidden effects (those a pillar-array run applies).
    noise : NoiseModel, optional
        Default :func:`~fibersweep.discrepancy.copies.array_noise` of ``fiber``.
    seed : int

    Returns
    -------
    table : DataFrame
        Follows :mod:`fibersweep.discrepancy.array_schema` (validated); ``bend``
        only for a flexible model.
    truth : dict
        JSON-ready: effects, noise, seed, box, true starts, failed runs.
    """
    if n < 1:
        raise InputError(f"--n: must be >= 1, got {n}")
    noise = noise or array_noise(fiber)
    effects = {k: float(v) for k, v in (effects or {}).items()}
    array_effects_check(fiber, effects, "--effect")
    rng = np.random.default_rng([seed, 4242])
    lo = np.array([box[k][0] for k in _AXES], dtype=np.float64)
    hi = np.array([box[k][1] for k in _AXES], dtype=np.float64)
    true = redraw_clear(field, fiber, lo + (hi - lo) * rng.random((n, 3)), box, rng, "synth")
    reported = noise.jitter_starts(true, rng)
    seeds = rng.integers(0, 2**31 - 1, size=n)
    z = noise_draws([seed, 4242], n)
    effects = {**fiber.effects, **effects}
    with Simulator(field, fiber, workers=workers, progress=progress, executor=executor,
                   scheduler=scheduler, planned=n) as sim:  # fmt: skip
        raw = sim.run(true, effects, seeds, desc="synth")
    obs = noise.observe(raw, z)
    keep = (obs["status"] == "ok").to_numpy()
    table = pd.DataFrame({"fiber_id": np.arange(n, dtype=np.int64)})
    for k, name in enumerate(_AXES):
        table[name] = reported[:, k]
    for name in of_geometry("array"):  # as the registry writes them; no bend for a rigid model
        if name != "bend" or fiber.model != "rigid":
            table[name] = OBSERVABLES[name].to_table(obs[name])
    failures = [
        {"fiber_id": int(i), "true_start": true[i].tolist(), "reason": str(raw["reason"][i])}
        for i in np.flatnonzero(~keep)
    ]
    if failures:
        log.warning("synth: %d of %d runs failed and are left out (listed in the truth)",
                    len(failures), n)  # fmt: skip
    table = validate_array_measured(table[keep].reset_index(drop=True), source="synth")
    truth = {
        "geometry": "array",
        "effects": effects,
        "noise": noise.as_dict(),
        "seed": seed,
        "n_requested": n,
        "n_written": int(keep.sum()),
        "box": {k: list(v) for k, v in box.items()},
        "true_starts": {
            "fiber_id": np.flatnonzero(keep).tolist(),
            **{name: true[keep, k].tolist() for k, name in enumerate(_AXES)},
        },
        "failed": failures,
    }
    return table, truth
