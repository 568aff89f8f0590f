"""Measured-like data from the model with hidden effects (``fibersweep synth``).

True starts are drawn uniformly in the box spanned by the config's sweep axes
(min..max of θ0, y0/h, L/l_obs); the reported starts carry the measurement
noise of :class:`NoiseModel`; every fiber is simulated at its *true* start
with the effects switched on; the outcomes get measurement noise. The truth
(effects, noise model, seed, true starts, failures) is returned separately so
the discrepancy workflow never sees it. A failed run is not a measurement: it is
left out of the table and listed in the truth.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from fibersweep.discrepancy.noise import N_DRAWS, NoiseModel
from fibersweep.discrepancy.schema import validate_measured
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.errors import InputError
from fibersweep.fiber.result import CLASSES
from fibersweep.fiber.settings import FiberSettings
from fibersweep.flow.field import FlowField

__all__ = ["synthesize", "parse_effects"]

log = logging.getLogger(__name__)


def parse_effects(items: list[str] | None) -> dict[str, float]:
    """``["friction=0.3", ...]`` -> ``{"friction": 0.3}``; InputError naming a bad item."""
    from fibersweep.fiber.effects import build_effects

    out: dict[str, float] = {}
    for item in items or []:
        name, sep, val = item.partition("=")
        if not sep or not name.strip():
            raise InputError(f"--effect: expected NAME=VALUE, got {item!r}")
        try:
            out[name.strip()] = float(val)
        except ValueError:
            raise InputError(f"--effect {name}: value {val!r} is not a number") from None
    build_effects(out)  # unknown names and bad values fail here, listing the valid ones
    return out


def synthesize(
    field: FlowField,
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
    """Make a measured-fiber table and its truth.

    Parameters
    ----------
    field : FlowField
        Baseline flow field.
    fiber : FiberSettings
        Fiber settings; ``effects`` are switched on in addition to its own.
    box : mapping 'theta0' | 'y0' | 'length' -> (lo, hi)
        Range of the true starts [deg, /h, /l_obs].
    n : int
        Fibers.
    effects : mapping name -> value
        Hidden effects.
    noise : NoiseModel
    seed : int

    Returns
    -------
    table : DataFrame
        Follows :mod:`fibersweep.discrepancy.schema` (validated).
    truth : dict
        JSON-ready: effects, noise, seed, box, true starts, failed runs.
    """
    if n < 1:
        raise InputError(f"--n: must be >= 1, got {n}")
    noise = noise or NoiseModel()
    effects = {k: float(v) for k, v in (effects or {}).items()}
    rng = np.random.default_rng([seed, 4242])
    lo = np.array([box[k][0] for k in ("theta0", "y0", "length")], dtype=np.float64)
    hi = np.array([box[k][1] for k in ("theta0", "y0", "length")], dtype=np.float64)
    true = lo + (hi - lo) * rng.random((n, 3))
    reported = noise.jitter_starts(true, rng)
    seeds = rng.integers(0, 2**31 - 1, size=n)
    z = rng.standard_normal((n, N_DRAWS))
    effects = {**fiber.effects, **effects}  # hidden effects on top of the config's own
    with Simulator(
        field, fiber, workers=workers, progress=progress, executor=executor, scheduler=scheduler
    ) as sim:
        raw = sim.run(true, effects, seeds, desc="synth")
    obs = noise.observe(raw, z=z)
    ok = (obs["status"] == "ok").to_numpy()
    table = pd.DataFrame(
        {
            "fiber_id": [f"f{i:04d}" for i in range(n)],
            "theta0": reported[:, 0],
            "y0": reported[:, 1],
            "length": reported[:, 2],
            "class": [CLASSES[int(c)] if np.isfinite(c) else "" for c in obs["class"]],
            "delta": obs["delta"].to_numpy(),
            "contact": obs["contact"].to_numpy() > 0.5,
            "theta_c": obs["theta_c"].to_numpy(),
            "y_c": obs["y_c"].to_numpy(),
            "t_pass": obs["t_pass"].to_numpy(),
            # first contact on the same clock: t_pass - dwell (both as measured)
            "t_contact": np.where(
                np.isfinite(obs["dwell"]), obs["t_pass"] - obs["dwell"], obs["t_contact"]
            ),
        }
    )
    # A passing fiber whose rear never crossed the pillar line within the run has no
    # time to pass: such a run is incomplete, so it is treated like a failure.
    incomplete = ok & (table["class"] != "Trapping").to_numpy() & ~np.isfinite(table["t_pass"])
    keep = ok & ~incomplete
    failures = [
        {
            "fiber_id": table["fiber_id"][i],
            "true_start": true[i].tolist(),
            "reason": raw["reason"][i] or "no time to pass",
        }
        for i in np.flatnonzero(~keep)
    ]
    if failures:
        log.warning(
            "synth: %d of %d runs failed and are left out (listed in the truth)", len(failures), n
        )
    table = table[keep].reset_index(drop=True)
    validate_measured(table, source="synth")  # the writer's own output must follow the schema
    truth = {
        "effects": effects,
        "noise": {k: getattr(noise, k) for k in noise.__dataclass_fields__},
        "seed": seed,
        "n_requested": n,
        "n_written": int(keep.sum()),
        "box": {k: list(v) for k, v in box.items()},
        "true_starts": {
            "fiber_id": [f"f{i:04d}" for i in np.flatnonzero(keep)],
            "theta0": true[keep, 0].tolist(),
            "y0": true[keep, 1].tolist(),
            "length": true[keep, 2].tolist(),
        },
        "failed": failures,
    }
    return table, truth
