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

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.copies import NoiseModel
from fibersweep.discrepancy.measured import validate_trajectories, with_tracks
from fibersweep.discrepancy.observables import OBSERVABLES, noise_draws, table_columns
from fibersweep.discrepancy.schema import validate_measured
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.errors import InputError
from fibersweep.flow.field import FlowField

__all__ = [
    "STUDY_BOX",
    "TRACK_NOISE",
    "measured_table",
    "parse_effects",
    "synthesize",
    "synthesize_near",
    "synthesize_with_tracks",
]

#: Starts around the pillar: the source's ranges of θ0 [deg] and L [l_obs], and y0 [h_obs]
#: over the band where fibers meet the pillar. The box of the method's calibration studies
#: (scripts/studies/discrepancy/) and of its validation tests.
STUDY_BOX: dict[str, tuple[float, float]] = {
    "theta0": (-10.0, 10.0),
    "y0": (0.15, 0.65),
    "length": (0.5, 1.4),
}

#: Per-frame error of synthetic tracks: centre position [µm] (x, y each), angle [deg].
#: 1 µm is sub-pixel centroid tracking; the angle of a fiber from its two ends, each
#: located to ~1 µm, errs by ~√2 µm / L, 1-2° for L = 40-90 µm.
TRACK_NOISE = (1.0, 1.5)

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


def measured_table(
    outcomes: pd.DataFrame, starts: np.ndarray, fiber_ids: list[str] | None = None
) -> pd.DataFrame:
    """A measured-fiber table (schema columns) from measured-like outcomes.

    Parameters
    ----------
    outcomes : DataFrame, n rows
        Outcome table with measurement noise (:meth:`NoiseModel.observe`), one
        column per observable of the registry.
    starts : ndarray, shape (n, 3)
        Reported starts: theta0 [deg], y0 [/h], length [/l_obs].
    fiber_ids : list of str, optional
        Default ``f0000, f0001, ...``.

    Returns
    -------
    DataFrame
        ``fiber_id``, the start columns and every observed column of the schema;
        an observable derived from others (dwell) is written back into them.
    """
    n = len(outcomes)
    table = pd.DataFrame(
        {
            "fiber_id": fiber_ids if fiber_ids is not None else [f"f{i:04d}" for i in range(n)],
            "theta0": starts[:, 0],
            "y0": starts[:, 1],
            "length": starts[:, 2],
        }
    )
    for name in table_columns():  # the channel's (an array's: .array_synth)
        table[name] = OBSERVABLES[name].to_table(outcomes[name])
    for name, o in OBSERVABLES.items():
        if o.underive is not None:
            o.underive(table, outcomes[name].to_numpy(dtype=np.float64))
    return table


def _missing(table: pd.DataFrame) -> np.ndarray:
    """Per row, the continuous observables missing where they must exist ('' if none).

    Returns
    -------
    ndarray, shape (n,), str
        Descriptions joined by ', ' (e.g. 'time to pass the pillar').
    """
    trapped = (table["class"] == "Trapping").to_numpy()
    contact = table["contact"].to_numpy(dtype=bool) if "contact" in table else None
    out = np.full(len(table), "", dtype=object)
    for name in table.columns.intersection(list(OBSERVABLES)):
        o = OBSERVABLES[name]
        need = o.defined_mask(trapped, contact)
        if o.kind != "continuous" or need is None:
            continue
        gone = need & ~np.isfinite(table[name].to_numpy(dtype=np.float64))
        out[gone] = [f"{w}, {o.description}" if w else o.description for w in out[gone]]
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
    """Make a measured-fiber table and its truth (:func:`synthesize_with_tracks` without tracks).

    Returns
    -------
    table : DataFrame
        Follows :mod:`fibersweep.discrepancy.schema` (validated).
    truth : dict
        JSON-ready: effects, noise, seed, box, true starts, failed runs.
    """
    table, _, truth = synthesize_with_tracks(
        field, fiber, box, n, effects, noise, seed, workers, progress, executor, scheduler
    )
    return table, truth


def synthesize_near(
    field: FlowField,
    fiber: FiberSettings,
    centres: np.ndarray,
    fibers: int,
    effects: Mapping[str, float] | None = None,
    noise: NoiseModel | None = None,
    seed: int = 0,
    window: float = 3.0,
    scatter: float = 6.0,
    workers: int = 2,
) -> pd.DataFrame:
    """Follow-up fibers near proposed starts, kept as an experimenter keeps them.

    Fibers arrive anywhere around each centre (true starts uniform within
    ``scatter`` start-noise sd either side); those whose *reported* start lies
    within ``window`` sd of it are kept, until each centre has its share
    (``fibers`` shared equally, the first centres one more). Selecting on the
    reported start leaves the true start spread around it as the copies of the
    follow-up test assume (:mod:`.discriminant`); selecting on the true start would not,
    near the window's edges.

    Parameters
    ----------
    centres : ndarray, shape (m, 3)
        Proposed starts: θ0 [deg], y0 [/h_obs], L [/l_obs].
    fibers : int
        Fibers in all (>= 1).
    window, scatter : float
        Half-widths in start-noise sd (``scatter`` > ``window``).

    Returns
    -------
    DataFrame
        As :func:`synthesize`; fiber ids ``m<centre>-<k>``.
    """
    if fibers < 1 or scatter <= window:
        raise ValueError(
            f"need fibers >= 1 and scatter > window, got {fibers}, {scatter}, {window}"
        )
    noise = noise or NoiseModel()
    centres = np.atleast_2d(np.asarray(centres, dtype=np.float64))
    half = np.array([noise.theta0, noise.y0, noise.length])
    share = np.full(len(centres), fibers // len(centres))
    share[: fibers % len(centres)] += 1
    accept = float(np.prod(np.where(half > 0, window / scatter, 1.0)))  # of those that arrive
    parts = []
    for j, (c, k) in enumerate(zip(centres, share, strict=True)):
        box = {key: (v - scatter * h, v + scatter * h)
               for key, v, h in zip(("theta0", "y0", "length"), c, half, strict=True)}  # fmt: skip
        kept: list[pd.DataFrame] = []
        rnd = 0
        while sum(len(t) for t in kept) < k:
            t, _ = synthesize(field, fiber, box, int(np.ceil(1.5 * k / accept)), effects, noise,
                              seed=seed + 7919 * j + 104729 * rnd, workers=workers,
                              progress=False)  # fmt: skip
            dev = np.abs(t[["theta0", "y0", "length"]].to_numpy() - c)
            kept.append(t[np.all(dev <= window * half + 1e-12, axis=1)])
            rnd += 1
        t = pd.concat(kept, ignore_index=True).iloc[: int(k)].copy()
        t["fiber_id"] = [f"m{j:02d}-{i:03d}" for i in range(len(t))]
        parts.append(t)
    return pd.concat(parts, ignore_index=True)


def synthesize_with_tracks(
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
    fps: float | None = None,
    track_noise: tuple[float, float] = TRACK_NOISE,
) -> tuple[pd.DataFrame, pd.DataFrame | None, dict[str, Any]]:
    """Make a measured-fiber table, optionally its trajectories, and its truth.

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
    fps : float, optional
        Also make the trajectories, sampled at this frame rate [1/s].
    track_noise : (float, float)
        Per-frame measurement error of the tracks: position [µm] (x and y, each)
        and angle [deg], Gaussian, independent between frames.

    Returns
    -------
    table : DataFrame
        Follows :mod:`fibersweep.discrepancy.schema` (validated).
    tracks : DataFrame or None
        ``fiber_id, t [s], x, y [µm, channel frame], theta [deg]`` of every fiber
        of the table (with ``fps``), with the measurement error; None without ``fps``.
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
    z = noise_draws([seed, 4242], n)
    effects = {**fiber.effects, **effects}  # hidden effects on top of the config's own
    # the frames of the tracks come with fps; the track observables are not written
    with Simulator(
        field, fiber, workers=workers, progress=progress, executor=executor,
        scheduler=scheduler, tracks=False, planned=n,
    ) as sim:  # fmt: skip
        raw = sim.run(true, effects, seeds, desc="synth", fps=fps)
    obs = noise.observe(raw, z)
    ok = (obs["status"] == "ok").to_numpy()
    table = measured_table(obs, reported)
    # A run that leaves a quantity undefined where it must exist (a passing fiber whose
    # rear never crossed the pillar line has no time to pass) is incomplete: a failure.
    missing = _missing(table)
    incomplete = ok & (missing != "")
    keep = ok & ~incomplete
    failures = [
        {
            "fiber_id": table["fiber_id"][i],
            "true_start": true[i].tolist(),
            "reason": raw["reason"][i] or f"no {missing[i]}",
        }
        for i in np.flatnonzero(~keep)
    ]
    if failures:
        log.warning(
            "synth: %d of %d runs failed and are left out (listed in the truth)", len(failures), n
        )
    tracks = None
    if fps is not None:
        tracks = _noisy_tracks(raw, table["fiber_id"], keep, track_noise, seed)
    table = table[keep].reset_index(drop=True)
    data = validate_measured(table, source="synth")  # the writer's own output must follow
    if tracks is not None:  # the schema, with its tracks too
        with_tracks(data, validate_trajectories(tracks, data.table, "synth"), field.geometry)
    truth = {
        "effects": effects,
        "noise": noise.as_dict(),
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
    if fps is not None:
        truth["tracks"] = {"fps": fps, "sd_xy_um": track_noise[0], "sd_theta_deg": track_noise[1]}
    return table, tracks, truth


def _noisy_tracks(
    raw: pd.DataFrame,
    ids: pd.Series,
    keep: np.ndarray,
    sd: tuple[float, float],
    seed: int,
) -> pd.DataFrame:
    """The kept runs' frames (column ``track`` of ``raw``) with per-frame noise, one table.

    The noise comes from its own stream (``[seed, 4243]``), so the fibers table
    is the same with or without tracks.
    """
    rng = np.random.default_rng([seed, 4243])
    parts = []
    for i in np.flatnonzero(keep):
        f = raw["track"][i]
        m = len(f["t"])
        z = rng.standard_normal((3, m))
        parts.append(
            pd.DataFrame(
                {
                    "fiber_id": ids[i],
                    "t": f["t"],
                    "x": f["x"] + sd[0] * z[0],
                    "y": f["y"] + sd[0] * z[1],
                    "theta": f["theta"] + sd[1] * z[2],
                }
            )
        )
    return pd.concat(parts, ignore_index=True)
