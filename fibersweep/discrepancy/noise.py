"""Measurement model: noise on measured starts and on observed outcomes.

The same model makes synthetic measurements (``fibersweep synth``) and the
model's jittered copies in the discrepancy workflow; the gap tests are exact
when it describes the real measurement. Why jittering the *measured* start is
right: with a start distribution that is flat on the scale of the noise, the
true start given the measured one is ``measured + N(0, σ²)``, so the model's
copies ``f(measured + ε')`` and the observation ``f(true)`` are exchangeable.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
import pandas as pd

from fibersweep.errors import InputError

__all__ = ["NoiseModel", "N_DRAWS"]

#: Standard normal draws per fiber for the outcome noise (delta, theta_c, y_c, t_pass, dwell).
N_DRAWS = 5


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
    delta : float
        Lateral displacement [/h_obs].
    theta_c : float
        Contact angle [deg].
    y_c : float
        Contact position [/h_obs].
    t_pass : float
        Relative error of the time to pass (log-normal) [-]; 0.01 is about one
        frame at 100 fps over a 1 s track.
    dwell : float
        Error of the time from first contact to passing [s] (one frame at 100 fps).
    """

    theta0: float = 1.0
    y0: float = 0.01
    length: float = 0.01
    delta: float = 0.01
    theta_c: float = 1.0
    y_c: float = 0.01
    t_pass: float = 0.01
    dwell: float = 0.01

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if not (np.isfinite(v) and v >= 0):
                raise InputError(f"noise.{f.name}: must be a finite number >= 0, got {v!r}")

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

    def observe(
        self, outcomes: pd.DataFrame, rng: np.random.Generator | None = None, z=None
    ) -> pd.DataFrame:
        """Outcomes as a measurement would report them (noise on continuous values).

        Class and contact are observed without error. NaN stays NaN. The noise
        is drawn for every row whether or not a value is defined, so that the
        random stream does not depend on the outcomes (common random numbers).

        Parameters
        ----------
        outcomes : DataFrame
            Columns delta, theta_c, y_c, t_pass, dwell (others are kept as they are).
        rng : numpy.random.Generator, optional
            Source of the noise, if ``z`` is not given.
        z : ndarray, shape (n, 5), optional
            Standard normal draws to use (delta, theta_c, y_c, t_pass, dwell).
        """
        out = outcomes.copy()
        n = len(out)
        if z is None:
            if rng is None:
                raise ValueError("observe needs rng or z")
            z = rng.standard_normal((n, N_DRAWS))
        z = np.asarray(z, dtype=np.float64)
        if z.shape != (n, N_DRAWS):
            raise ValueError(f"z must have shape ({n}, {N_DRAWS}), got {z.shape}")
        for k, col in enumerate(("delta", "theta_c", "y_c")):
            if col in out:
                out[col] = out[col].to_numpy(dtype=np.float64) + getattr(self, col) * z[:, k]
        if "t_pass" in out:
            out["t_pass"] = out["t_pass"].to_numpy(dtype=np.float64) * np.exp(self.t_pass * z[:, 3])
        if "dwell" in out:
            # reflected at 0: a measured contact never comes after the pass
            out["dwell"] = np.abs(out["dwell"].to_numpy(dtype=np.float64) + self.dwell * z[:, 4])
        return out
