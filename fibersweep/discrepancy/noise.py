"""Measurement model: noise on measured starts and on observed outcomes.

The same model makes synthetic measurements (``fibersweep synth``) and the
model's jittered copies in the discrepancy workflow; the gap tests are exact
when it describes the real measurement. Why jittering the *measured* start is
right: with a start distribution that is flat on the scale of the noise, the
true start given the measured one is ``measured + N(0, σ²)``, so the model's
copies ``f(measured + ε')`` and the observation ``f(true)`` are exchangeable.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from fibersweep.discrepancy.observables import OBSERVABLES
from fibersweep.errors import InputError

__all__ = ["NoiseModel"]


def _default_outcome_sd(tracks: bool = True) -> dict[str, float]:
    return {
        n: o.noise.sd
        for n, o in OBSERVABLES.items()
        if o.noise is not None and (tracks or not o.track)
    }


@dataclass(frozen=True)
class NoiseModel:
    """Standard deviations of the measurement errors (Gaussian, independent).

    Attributes
    ----------
    theta0 : float
        Start angle [deg].
    y0 : float
        Start lateral position [/h_obs].
    length : float
        Fiber length [/l_obs].
    outcome : mapping name -> float
        Error of each observable with a noise law, in its unit (relative for a
        log-normal law), e.g. ``delta`` [/h_obs], ``theta_c`` [deg], ``t_pass``
        [-], ``dwell`` [s]; observables left out get their registry default
        (:mod:`fibersweep.discrepancy.observables`). The track observables' are
        listed only when given (so reports without tracks are unchanged).
    """

    theta0: float = 1.0
    y0: float = 0.01
    length: float = 0.01
    outcome: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        valid = _default_outcome_sd()
        unknown = [k for k in self.outcome if k not in valid]
        if unknown:
            raise InputError(
                f"noise: no measurement noise law for {', '.join(unknown)}; "
                f"valid: {', '.join(valid)}"
            )
        sd = _default_outcome_sd(tracks=False)
        sd.update({k: float(v) for k, v in self.outcome.items()})
        object.__setattr__(self, "outcome", sd)
        for name, v in self.as_dict().items():
            if not (np.isfinite(v) and v >= 0):
                raise InputError(f"noise.{name}: must be a finite number >= 0, got {v!r}")

    def __hash__(self) -> int:  # the outcome dict is never mutated after __post_init__
        return hash((self.theta0, self.y0, self.length, tuple(self.outcome.items())))

    def sd(self, name: str) -> float:
        """Standard deviation of the start column or observable ``name``."""
        if name in ("theta0", "y0", "length"):
            return float(getattr(self, name))
        if name not in self.outcome and name in OBSERVABLES and OBSERVABLES[name].track:
            return _default_outcome_sd()[name]
        return self.outcome[name]

    def as_dict(self) -> dict[str, float]:
        """Flat ``{name: sd}``: the start columns, then the observables (for reports)."""
        return {"theta0": self.theta0, "y0": self.y0, "length": self.length, **self.outcome}

    def jitter_starts(self, starts: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Measured-like starts: ``starts`` plus start noise.

        Parameters
        ----------
        starts : ndarray, shape (n, 3)
            theta0 [deg], y0 [/h], length [/l_obs].

        Returns
        -------
        ndarray, shape (n, 3)
            Lengths are kept positive (reflected at a small floor).
        """
        s = np.asarray(starts, dtype=np.float64)
        if s.ndim != 2 or s.shape[1] != 3:
            raise ValueError(f"starts must have shape (n, 3), got {s.shape}")
        sd = np.array([self.theta0, self.y0, self.length])
        out = s + rng.standard_normal(s.shape) * sd
        out[:, 2] = np.abs(out[:, 2] - 0.05) + 0.05
        return out

    def observe(self, outcomes: pd.DataFrame, z: Mapping[str, np.ndarray]) -> pd.DataFrame:
        """Outcomes as a measurement would report them (each observable's noise law).

        Observables without a noise law (class, contact) are observed without
        error. NaN stays NaN. The draws come per observable name
        (:func:`~fibersweep.discrepancy.observables.noise_draws`) for every row
        whether or not a value is defined, so the random stream depends neither
        on the outcomes nor on the other observables (common random numbers).

        Parameters
        ----------
        outcomes : DataFrame, n rows
            Outcome columns (others are kept as they are).
        z : mapping name -> ndarray, shape (n,)
            Standard normal draws of each observable with a noise law present.
        """
        out = outcomes.copy()
        n = len(out)
        for name, o in OBSERVABLES.items():
            if o.noise is None or name not in out:
                continue
            zn = np.asarray(z[name], dtype=np.float64)
            if zn.shape != (n,):
                raise ValueError(f"z[{name!r}] must have shape ({n},), got {zn.shape}")
            out[name] = o.noise.apply(out[name].to_numpy(dtype=np.float64), self.sd(name), zn)
        return out
