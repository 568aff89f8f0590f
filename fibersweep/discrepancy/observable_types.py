"""What an observable of the discrepancy workflow is: its kind, noise law and scoring scale.

The types of :mod:`fibersweep.discrepancy.observables` (the registry), kept apart so that
the registry's geometry parts (:mod:`.array_observables`) build on them without a cycle.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import pandas as pd

from fibersweep.fiber.result import RunResult

__all__ = ["Condition", "Geometry", "Kind", "NoiseLaw", "Observable", "log_scale"]

Kind = Literal["class", "binary", "continuous"]
#: Where an observable is measured: past one pillar in a channel, or through a pillar array.
Geometry = Literal["channel", "array"]
#: Conditions for a quantity to exist: the fiber is not trapped; it touched the pillar.
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
    geometry : {'channel', 'array'}
        Where it is measured: a channel run and an array run each score only the
        observables of their geometry.
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
    geometry: Geometry = "channel"

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
