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
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Literal

import numpy as np
import pandas as pd

from fibersweep.fiber.result import CLASSES, RunResult

__all__ = [
    "Condition",
    "Kind",
    "NoiseLaw",
    "Observable",
    "OBSERVABLES",
    "has_tracks",
    "log_scale",
    "noise_draws",
    "scored",
    "stream_key",
    "table_columns",
    "track_observables",
]

Kind = Literal["class", "binary", "continuous"]
#: Conditions for a quantity to exist: the fiber is not Trapping; it touched the pillar.
Condition = Literal["not_trapped", "contact"]


@dataclass(frozen=True)
class NoiseLaw:
    """Measurement error of a continuous observable (Gaussian, independent per fiber).

    Attributes
    ----------
    kind : {'additive', 'lognormal', 'reflected'}
        ``x + sd z``; ``x exp(sd z)`` (sd is a relative error); ``|x + sd z|``
        (a non-negative quantity, reflected at 0).
    sd : float
        Default standard deviation, in the observable's unit (relative for lognormal).
    """

    kind: Literal["additive", "lognormal", "reflected"]
    sd: float

    def apply(self, x: np.ndarray, sd: float, z: np.ndarray) -> np.ndarray:
        """Noisy values, shape of ``x``; NaN stays NaN.

        Parameters
        ----------
        x : ndarray, shape (n,)
            True values [unit of the observable].
        sd : float
            Standard deviation to use (the noise model's, defaults to ``self.sd``).
        z : ndarray, shape (n,)
            Standard normal draws.
        """
        x = np.asarray(x, dtype=np.float64)
        if self.kind == "additive":
            return x + sd * z
        if self.kind == "lognormal":
            return x * np.exp(sd * z)
        return np.abs(x + sd * z)


def _identity(v: np.ndarray) -> np.ndarray:
    return v


def log_scale(v: np.ndarray) -> np.ndarray:
    """Natural log of positive values, NaN elsewhere (scoring scale of times)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(v > 0, np.log(np.where(v > 0, v, 1.0)), np.nan)


@dataclass(frozen=True)
class Observable:
    """One measured quantity of a fiber and everything the workflow needs to know of it.

    Attributes
    ----------
    name : str
        Column name in measured and outcome tables.
    kind : {'class', 'binary', 'continuous'}
        Scored by the fair Brier score over ``categories`` (class, binary) or the fair CRPS
        on the ``transform`` scale (continuous).
    unit : str
        Unit of the values ('' for categories), e.g. 'h_obs', 'deg', 's'.
    description : str
        One line for messages and the report.
    extract : callable RunResult -> value, or None
        The value of a successful run (NaN or '' where undefined); None for a
        track observable (its value comes from
        :func:`fibersweep.analysis.observables.track_values`).
    defined : tuple of {'not_trapped', 'contact'}
        Where the quantity exists: every condition holds (``()``: always). NaN is
        accepted only outside it (and anywhere for 'contact' when the table has
        no contact column).
    strict : bool
        A value given where the quantity does not exist is an error.
    required : bool
        The measured table must have this column.
    scored : bool
        Compared by the workflow (False: a column only used to derive another).
    noise : NoiseLaw or None
        Measurement error (None: observed without error).
    transform : callable ndarray -> ndarray
        Scale on which a continuous observable is scored and its residual taken.
    bounds : (float, float) or None
        Plausible range [unit] (inclusive); outside points to a unit error.
    lower_open : bool
        The lower bound itself is out of range (times > 0).
    unit_hint : str
        How the column must be given, appended to a range error.
    angle : str
        For an angle, its name in messages (e.g. 'contact angle'): degrees are
        expected, radians caught, converted with ``angle_unit``; '' otherwise.
    categories : tuple
        Category labels of a class or binary observable.
    derived_from : tuple of str
        Measured columns this observable is computed from (then it is not a table
        column itself): see ``derive`` and ``underive``.
    derive : callable mapping -> ndarray, optional
        Values from the ``derived_from`` columns (validated floats).
    underive : callable (table, values) -> None, optional
        Writes measured-like ``values`` back into the ``derived_from`` columns of
        an outcome table (``synth``).
    measures : tuple of {'wasserstein', 'ratio'}
        Extra descriptive measures for the report (distance of the distributions,
        median ratio observed / model).
    track : bool
        Derived from the trajectories (not a fibers-table column); scored only
        when the measured data has tracks.
    """

    name: str
    kind: Kind
    unit: str
    description: str
    extract: Callable[[RunResult], Any] | None = None
    defined: tuple[Condition, ...] = ()
    strict: bool = True
    required: bool = False
    scored: bool = True
    noise: NoiseLaw | None = None
    transform: Callable[[np.ndarray], np.ndarray] = _identity
    bounds: tuple[float, float] | None = None
    lower_open: bool = False
    unit_hint: str = ""
    angle: str = ""
    categories: tuple[str, ...] = ()
    derived_from: tuple[str, ...] = ()
    derive: Callable[[Mapping[str, np.ndarray]], np.ndarray] | None = None
    underive: Callable[[pd.DataFrame, np.ndarray], None] | None = None
    measures: tuple[str, ...] = ()
    track: bool = False

    @property
    def categorical(self) -> bool:
        """Scored by the fair Brier score over categories."""
        return self.kind in ("class", "binary")

    @property
    def width(self) -> int:
        """Components of the signed residual: categories, or 1."""
        return len(self.categories) if self.categorical else 1

    def defined_mask(self, trapped: np.ndarray, contact: np.ndarray | None) -> np.ndarray | None:
        """Where the quantity exists, shape (n,) bool; None when it cannot be told.

        Parameters
        ----------
        trapped : ndarray, shape (n,), bool
            Fibers of class Trapping.
        contact : ndarray, shape (n,), bool, or None
            Fibers that touched the pillar; None when contact was not measured.
        """
        mask = np.ones(len(trapped), dtype=bool)
        if "not_trapped" in self.defined:
            mask &= ~np.asarray(trapped, dtype=bool)
        if "contact" in self.defined:
            if contact is None:
                return None
            mask &= np.asarray(contact, dtype=bool)
        return mask

    def outcome(self, result: RunResult | None, tracks: Mapping[str, float] | None = None) -> Any:
        """Value in an outcome table: extracted from an ok run, missing otherwise.

        Parameters
        ----------
        result : RunResult or None
            None for a failed run.
        tracks : mapping name -> float, optional
            The run's track values (:func:`fibersweep.analysis.observables.track_values`);
            a track observable is NaN without them.
        """
        if result is None:
            return None if self.kind == "class" else math.nan
        if self.extract is None:
            return float(tracks.get(self.name, math.nan)) if tracks else math.nan
        v = self.extract(result)
        return v if self.kind == "class" else float(v)

    def values(self, column: pd.Series | np.ndarray | Sequence[Any]) -> np.ndarray:
        """Float values for scoring, shape (n,): category index or value; NaN undefined.

        Parameters
        ----------
        column : Series or array, shape (n,)
            Class names (class kind), bool or 0/1 (binary), floats (continuous);
            None, '' or NaN where undefined.
        """
        if self.kind == "class":
            lookup = {c: float(i) for i, c in enumerate(self.categories)}
            return np.array([lookup.get(v, np.nan) for v in column], dtype=np.float64)
        s = pd.Series(column)
        if s.dtype == object:
            s = pd.to_numeric(s.map(lambda v: float(v) if v is not None else np.nan))
        return s.to_numpy(dtype=np.float64)

    def to_table(self, outcome: pd.Series) -> np.ndarray:
        """Outcome-table values as a measured table writes them (class names, bool contact)."""
        if self.kind == "class":
            return np.array([v if isinstance(v, str) else "" for v in outcome], dtype=object)
        if self.kind == "binary":
            return outcome.to_numpy(dtype=np.float64) > 0.5
        return outcome.to_numpy(dtype=np.float64)


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

#: Every observable, name -> Observable, in table and report order (read-only view).
OBSERVABLES: Mapping[str, Observable] = MappingProxyType(_REGISTRY)


def scored(tracks: bool = False) -> tuple[str, ...]:
    """Names of the observables the workflow compares, in report order.

    Parameters
    ----------
    tracks : bool
        Include the track observables (compared only when tracks are measured).
    """
    return tuple(n for n, o in OBSERVABLES.items() if o.scored and (tracks or not o.track))


def track_observables() -> tuple[str, ...]:
    """Names of the observables derived from trajectories, in report order."""
    return tuple(n for n, o in OBSERVABLES.items() if o.track)


def has_tracks(names: Iterable[str]) -> bool:
    """Whether any of ``names`` is a track observable (tracks were measured)."""
    return any(n in OBSERVABLES and OBSERVABLES[n].track for n in names)


def table_columns() -> tuple[str, ...]:
    """Observed columns of a measured table (observables not derived from others)."""
    return tuple(n for n, o in OBSERVABLES.items() if not o.derived_from and not o.track)


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
