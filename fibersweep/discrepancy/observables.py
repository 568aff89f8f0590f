"""The observables of the discrepancy workflow: what one is, and the registry of them all.

An :class:`Observable` is one measured quantity of a fiber and everything the
workflow needs to know of it: its kind, unit, plausible range and NaN rule,
noise law, scoring scale and how it is read from a run. Every module of the
workflow iterates :data:`OBSERVABLES` instead of naming quantities: the schema
validates the columns it lists, the simulator extracts them from a
:class:`~fibersweep.fiber.result.RunResult`, the measurement model applies
their noise law, ``synth`` writes them, the scores and gap tests compare them
on their scoring scale, and the report lists them. A new observable is one new
entry in ``_REGISTRY`` below.

Values in outcome tables (simulated copies) and measured tables
-----------------------------------------------------------------
- ``class`` kind: the category name (one of ``categories``), None/'' when undefined;
- ``binary`` kind: 0.0 / 1.0 (measured tables: bool), NaN when undefined;
- ``continuous`` kind: a float in ``unit``, NaN when undefined.

:meth:`Observable.values` turns any of these into the float matrix the scores
use (category index for class kinds), the only place where a category is encoded.

Track observables (``track=True``: ``y_out``, ``theta_out``, ``t_transit``) are
derived from the measured trajectories (``discrepancy --trajectories``) and
from ``RunResult.trajectory`` by one function,
:func:`fibersweep.analysis.observables.track_values`; they are not columns of
the fibers table and are compared only when tracks are given.

Random streams
--------------
The measurement noise of observable ``name`` is drawn from its own stream,
``numpy.random.default_rng([*entropy, stream_key(name)])``, so adding,
removing or reordering observables leaves every other observable's draws unchanged.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from types import MappingProxyType

import numpy as np
import pandas as pd

from fibersweep.discrepancy.array_observables import ARRAY_OBSERVABLES
from fibersweep.discrepancy.observable_types import (
    Condition,
    Geometry,
    Kind,
    NoiseLaw,
    Observable,
    log_scale,
)
from fibersweep.fiber.result import CLASSES, RunResult

__all__ = [
    "ARRAY_OBSERVABLES",
    "Condition",
    "Geometry",
    "Kind",
    "NoiseLaw",
    "Observable",
    "OBSERVABLES",
    "has_tracks",
    "log_scale",
    "geometry_of",
    "noise_draws",
    "of_geometry",
    "scored",
    "stream_key",
    "table_columns",
    "track_observables",
]


def _dwell(cols: Mapping[str, np.ndarray]) -> np.ndarray:
    return cols["t_pass"] - cols["t_contact"]


def _undwell(table: pd.DataFrame, dwell: np.ndarray) -> None:
    # first contact on the clock of t_pass, both as measured: t_pass - dwell
    d = np.asarray(dwell, dtype=np.float64)
    table["t_contact"] = np.where(np.isfinite(d), table["t_pass"] - d, table["t_contact"])


def _if_contact(attr: str) -> Callable[[RunResult], float]:
    def get(r: RunResult) -> float:
        return float(getattr(r, attr)) if r.contact else math.nan

    return get


_REGISTRY: dict[str, Observable] = {
    o.name: o
    for o in (
        Observable(
            "class",
            "class",
            "",
            "outcome class",
            extract=lambda r: r.cls,
            required=True,
            categories=CLASSES,
        ),
        Observable(
            "delta",
            "continuous",
            "h_obs",
            "lateral displacement y_f - y0 far downstream",
            extract=lambda r: r.delta,
            defined=("not_trapped",),
            noise=NoiseLaw("additive", 0.01),
            bounds=(-10.0, 10.0),
            unit_hint="delta must be in units of h_obs",
            measures=("wasserstein",),
        ),
        Observable(
            "contact",
            "binary",
            "",
            "whether the fiber touched the pillar",
            extract=lambda r: bool(r.contact),
            categories=("no contact", "contact"),
        ),
        Observable(
            "theta_c",
            "continuous",
            "deg",
            "fiber angle at first contact",
            extract=_if_contact("theta_c"),
            defined=("contact",),
            noise=NoiseLaw("additive", 1.0),
            bounds=(-180.0, 180.0),
            unit_hint="theta_c must be in degrees",
            angle="contact angle",
        ),
        Observable(
            "y_c",
            "continuous",
            "h_obs",
            "lateral position of the contact point from the base",
            extract=_if_contact("y_c"),
            defined=("contact",),
            noise=NoiseLaw("additive", 0.01),
            bounds=(-0.5, 1.5),
            unit_hint="y_c must be measured from the base in units of h_obs",
        ),
        Observable(
            "t_pass",
            "continuous",
            "s",
            "time to pass the pillar",
            extract=lambda r: r.t_pass,
            defined=("not_trapped",),
            strict=False,
            # relative error; 0.01 is about one frame at 100 fps over a 1 s track
            noise=NoiseLaw("lognormal", 0.01),
            transform=log_scale,
            bounds=(0.0, 1e4),
            lower_open=True,
            unit_hint="t_pass must be in seconds",
            measures=("ratio",),
        ),
        Observable(
            "t_contact",
            "continuous",
            "s",
            "time of first contact on the clock of t_pass",
            extract=_if_contact("t_contact"),
            defined=("contact",),
            scored=False,  # compared as the dwell (contact to passing)
            bounds=(0.0, 1e4),
            lower_open=True,
            unit_hint="t_contact must be in seconds",
        ),
        Observable(
            "dwell",
            "continuous",
            "s",
            "time from first contact to passing the pillar (t_pass - t_contact)",
            extract=lambda r: r.t_pass - r.t_contact if r.contact else math.nan,
            defined=("contact", "not_trapped"),
            # reflected at 0: a measured contact never comes after the pass;
            # 0.01 s is one frame at 100 fps
            noise=NoiseLaw("reflected", 0.01),
            derived_from=("t_pass", "t_contact"),
            derive=_dwell,
            underive=_undwell,
        ),
        # Track observables (docs/trajectories.md); noise laws: the error of the derived
        # value for tracks with 1 µm / 1.5° per-frame noise at 100 fps
        Observable(
            "y_out",
            "continuous",
            "h_obs",
            "centre's lateral position from the base where it passes the pillar's downstream end",
            defined=("not_trapped",),
            noise=NoiseLaw("additive", 0.012),
            bounds=(-10.0, 10.0),
            unit_hint="tracks must be in µm in the model's channel frame",
            track=True,
        ),
        Observable(
            "theta_out",
            "continuous",
            "deg",
            "fiber angle where the centre passes the pillar's downstream end",
            defined=("not_trapped",),
            noise=NoiseLaw("additive", 1.2),
            bounds=(-90.0, 90.0),
            unit_hint="trajectory angles must be in degrees",
            track=True,
        ),
        Observable(
            "t_transit",
            "continuous",
            "s",
            "time for the centre to go from the pillar's upstream end to one fiber length "
            "past its downstream end",
            defined=("not_trapped",),
            # the error of two crossing times (~2 ms each), not of the duration
            noise=NoiseLaw("additive", 0.003),
            transform=log_scale,
            bounds=(0.0, 1e4),
            lower_open=True,
            unit_hint="trajectory times must be in seconds",
            measures=("ratio",),
            track=True,
        ),
    )
}

# the array's observables (geometry 'array'), after the channel's
_REGISTRY.update({o.name: o for o in ARRAY_OBSERVABLES})

#: Every observable, name -> Observable, in table and report order (read-only view).
OBSERVABLES: Mapping[str, Observable] = MappingProxyType(_REGISTRY)


def of_geometry(geometry: Geometry = "channel") -> tuple[str, ...]:
    """Names of the observables measured in ``geometry`` ('channel' or 'array'), in order."""
    if geometry not in ("channel", "array"):
        raise ValueError(f"geometry must be 'channel' or 'array', got {geometry!r}")
    return tuple(n for n, o in OBSERVABLES.items() if o.geometry == geometry)


def geometry_of(names: Iterable[str]) -> Geometry:
    """'array' when any of ``names`` is an array observable, else 'channel'."""
    arr = any(n in OBSERVABLES and OBSERVABLES[n].geometry == "array" for n in names)
    return "array" if arr else "channel"


def scored(tracks: bool = False, geometry: Geometry = "channel") -> tuple[str, ...]:
    """Names of the observables the workflow compares, in report order.

    Parameters
    ----------
    tracks : bool
        Include the track observables (compared only when tracks are measured).
    geometry : {'channel', 'array'}
        Only the observables of this geometry.
    """
    return tuple(
        n for n in of_geometry(geometry)
        if OBSERVABLES[n].scored and (tracks or not OBSERVABLES[n].track)
    )  # fmt: skip


def track_observables() -> tuple[str, ...]:
    """Names of the observables derived from trajectories, in report order."""
    return tuple(n for n, o in OBSERVABLES.items() if o.track)


def has_tracks(names: Iterable[str]) -> bool:
    """Whether any of ``names`` is a track observable (tracks were measured)."""
    return any(n in OBSERVABLES and OBSERVABLES[n].track for n in names)


def table_columns(geometry: Geometry = "channel") -> tuple[str, ...]:
    """Observed columns of a measured table of ``geometry`` (not derived from others)."""
    return tuple(
        n for n in of_geometry(geometry)
        if not OBSERVABLES[n].derived_from and not OBSERVABLES[n].track
    )  # fmt: skip


def stream_key(name: str) -> int:
    """Stable 64-bit key of an observable's random stream (SHA-256 of the name)."""
    return int.from_bytes(hashlib.sha256(name.encode()).digest()[:8], "little")


def noise_draws(entropy: Sequence[int], n: int) -> dict[str, np.ndarray]:
    """Standard normal draws of every observable with a noise law, keyed by name.

    Parameters
    ----------
    entropy : sequence of int
        Root of the streams (e.g. ``[seed, 7919, k]`` for copy k).
    n : int
        Fibers.

    Returns
    -------
    dict name -> ndarray, shape (n,)
        Drawn from ``default_rng([*entropy, stream_key(name)])``: independent of
        which other observables exist.
    """
    return {
        name: np.random.default_rng([*entropy, stream_key(name)]).standard_normal(n)
        for name, o in OBSERVABLES.items()
        if o.noise is not None
    }
