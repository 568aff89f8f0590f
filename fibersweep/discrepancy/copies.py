"""Jittered model copies of the measured fibers: the measurement model and the copy maker.

Measurement model (:class:`NoiseModel`): noise on measured starts and on
observed outcomes. The same model makes synthetic measurements (``fibersweep
synth``) and the model's jittered copies; the gap tests are exact when it
describes the real measurement. Why jittering the *measured* start is right:
with a start distribution that is flat on the scale of the noise, the true
start given the measured one is ``measured + N(0, σ²)``, so the model's copies
``f(measured + ε')`` and the observation ``f(true)`` are exchangeable. A start
column whose true values are all one value (fibers of one length) is not flat
on that scale: there the true value given the measured one is that value, and
the copies start at it (:func:`fixed_columns`).

Copies (:class:`CopyMaker`): copy k of fiber i always uses the same jittered
start, the same run seed and the same measurement-noise draws, whatever effect
is switched on. Comparing effect values on the same draws removes most of the
noise from a fit (common random numbers), and copies of different k are
independent.

Runs are kept per fiber: a copy asked for rows some of which were already
simulated for the same (k, effects) simulates only the missing ones (a fiber's
outcome depends only on its start, its seed and the effects, never on the
batch). So a stage that revisits a value another stage evaluated on a subset
of the fibers (the pooled refit at a fold's value, a pair fit at the first
effect's fold value, the final copies) reuses those runs.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.observables import OBSERVABLES, noise_draws
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.errors import InputError

__all__ = ["CopyMaker", "NoiseModel", "array_noise", "crossfit_copies", "fixed_columns"]


def _default_outcome_sd(tracks: bool = True, geometry: str = "channel") -> dict[str, float]:
    return {
        n: o.noise.sd
        for n, o in OBSERVABLES.items()
        if o.noise is not None and (tracks or not o.track) and o.geometry == geometry
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
    geometry : {'channel', 'array'}
        Whose observables ``outcome`` lists. In an array (:func:`array_noise`) the
        starts are y0 [fraction of period_y, periodic: a jittered y0 is taken
        modulo 1] and length [µm].
    min_length : float
        Shortest jittered length (reflected there), in the length's unit: a small
        floor in the channel; one bead (2a) in an array, below which no fiber exists.
    """

    theta0: float = 1.0
    y0: float = 0.01
    length: float = 0.01
    outcome: Mapping[str, float] = field(default_factory=dict)
    geometry: str = "channel"
    min_length: float = 0.05

    def __post_init__(self) -> None:
        valid = _default_outcome_sd(geometry=self.geometry)
        unknown = [k for k in self.outcome if k not in valid]
        if unknown:
            raise InputError(
                f"noise: no measurement noise law for {', '.join(unknown)}; "
                f"valid: {', '.join(valid)}"
            )
        sd = _default_outcome_sd(tracks=False, geometry=self.geometry)
        sd.update({k: float(v) for k, v in self.outcome.items()})
        object.__setattr__(self, "outcome", sd)
        for name, v in self.as_dict().items():
            if not (np.isfinite(v) and v >= 0):
                raise InputError(f"noise.{name}: must be a finite number >= 0, got {v!r}")

    def __hash__(self) -> int:  # the outcome dict is never mutated after __post_init__
        return hash((self.theta0, self.y0, self.length, tuple(self.outcome.items()),
                     self.geometry, self.min_length))  # fmt: skip

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
        out[:, 2] = np.abs(out[:, 2] - self.min_length) + self.min_length
        if self.geometry == "array":  # the lattice repeats every period_y
            out[:, 1] = np.mod(out[:, 1], 1.0)
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


def array_noise(fiber: FiberSettings, **outcome: float) -> NoiseModel:
    """The measurement noise of fibers through a pillar array (the array measured table).

    Start angle 1° (as in the channel); y0 0.01 period_y (0.8 µm in the shipped
    80 µm cell: sub-pixel centroid tracking); length 1 µm (a fiber's two ends each
    located to about 0.7 µm), reflected at one bead, 2a; the observables' errors
    from the registry (:mod:`.array_observables`) unless given in ``outcome``.
    """
    return NoiseModel(theta0=1.0, y0=0.01, length=1.0, outcome=outcome, geometry="array",
                      min_length=2.0 * float(fiber.bead_radius))  # fmt: skip


#: Fewest fibers from which a start column is checked for a single true value: with fewer,
#: a sample variance is too rough to tell (chi-square with few degrees of freedom).
FIXED_MIN_FIBERS = 20

#: Level of that check: a column is one value unless its spread exceeds the measurement
#: noise at this level (one-sided chi-square test of the sample variance).
FIXED_LEVEL = 0.001


def fixed_columns(starts: np.ndarray, noise: NoiseModel) -> dict[int, float]:
    """Start columns that carry no spread beyond their measurement noise, with their value.

    A copy's start is the measured start jittered by the start noise, which is the
    true start's distribution given the measured one when the starts' own
    distribution is flat on the scale of the noise (module docstring). When every
    fiber has one true value of a column (fibers cut to one length; ``synth`` from
    a config whose sweep has one length), the true value given the measured one is
    that value, and jittered copies are wider than the data by a factor sqrt(2) in
    that column and centred on the measured value instead. Such a column is
    recognised by its sample variance: one value measured with noise sd s has
    ``(n - 1) var / s^2 ~ chi2(n - 1)``; a column whose variance the test at
    :data:`FIXED_LEVEL` does not find larger is taken as one value, its mean.

    Parameters
    ----------
    starts : ndarray, shape (n, 3)
        Measured starts: theta0 [deg], y0 [/h], length [/l_obs].
    noise : NoiseModel
        Its start noise sd per column.

    Returns
    -------
    dict column index -> value
        Empty below :data:`FIXED_MIN_FIBERS` fibers and for noise-free columns.
    """
    from scipy.stats import chi2

    s = np.asarray(starts, dtype=np.float64)
    n = len(s)
    if n < FIXED_MIN_FIBERS:
        return {}
    out = {}
    crit = chi2.ppf(1.0 - FIXED_LEVEL, n - 1) / (n - 1)
    for c, name in enumerate(("theta0", "y0", "length")):
        sd = noise.sd(name)
        col = s[:, c][np.isfinite(s[:, c])]
        if sd > 0 and len(col) >= FIXED_MIN_FIBERS and np.var(col, ddof=1) <= crit * sd**2:
            out[c] = float(col.mean())
    return out


class CopyMaker:
    """Makes measured-like model outcomes at the measured starts.

    Parameters
    ----------
    starts : ndarray, shape (n, 3)
        Measured starts: theta0 [deg], y0 [/h], length [/l_obs].
    noise : NoiseModel
        Start and measurement noise.
    seed : int
        Root seed; copy k draws its starts and run seeds from
        ``default_rng([seed, 7919, k])`` and the measurement noise of each
        observable from its own stream keyed by the name
        (:func:`~fibersweep.discrepancy.observables.noise_draws`).
    simulator : Simulator

    Attributes
    ----------
    fixed : dict column index -> value
        Start columns with one true value (:func:`fixed_columns` of ``starts``):
        every copy starts at that value in them; the other columns are jittered.
    """

    def __init__(self, starts: np.ndarray, noise: NoiseModel, seed: int, simulator: Simulator):
        self.starts = np.asarray(starts, dtype=np.float64)
        self.noise = noise
        self.seed = int(seed)
        self.sim = simulator
        # start columns whose true values are one value (:func:`fixed_columns`): copies
        # start there, not at a jittered measured value
        self.fixed = fixed_columns(self.starts, noise)
        self._draws: dict[int, tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]] = {}
        # (k, effects) -> observed-like outcomes of the fibers simulated so far (index: fiber)
        self._cache: dict[tuple, pd.DataFrame] = {}
        # runs a cache keyed by the exact set of rows would have made (no per-fiber
        # reuse), so a caller can report what the reuse saves
        self._whole: set[tuple] = set()
        self.runs_without_reuse = 0

    @property
    def n(self) -> int:
        return len(self.starts)

    def draws(self, k: int) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        """(jittered starts (n, 3), run seeds (n,), noise normals per observable (n,)) of copy k."""
        if k not in self._draws:
            rng = np.random.default_rng([self.seed, 7919, k])
            starts = self.noise.jitter_starts(self.starts, rng)
            for c, v in self.fixed.items():  # after the draw: the other columns keep theirs
                starts[:, c] = v
            seeds = rng.integers(0, 2**31 - 1, size=self.n)
            z = noise_draws([self.seed, 7919, k], self.n)
            self._draws[k] = (starts, seeds, z)
        return self._draws[k]

    def copy(
        self,
        k: int,
        effects: Mapping[str, float] | None = None,
        rows: np.ndarray | None = None,
        desc: str = "copies",
    ) -> pd.DataFrame:
        """Observed-like outcomes of copy k for the given rows (all when None).

        Returns
        -------
        DataFrame, one row per requested fiber, outcome columns + status, reason.
        """
        return self.copies([k], effects, rows, desc)[0]

    def copies(
        self,
        ks: Iterable[int],
        effects: Mapping[str, float] | None = None,
        rows: np.ndarray | None = None,
        desc: str = "copies",
    ) -> list[pd.DataFrame]:
        """Outcomes of copies ``ks`` for the given rows, the missing runs as one batch.

        The outcomes equal those of :meth:`copy` called per k (a run depends only
        on its start, seed and effects).

        Returns
        -------
        list of DataFrame, one per k, one row per requested fiber.
        """
        ks = [int(k) for k in ks]
        eff = tuple(sorted((n, float(v)) for n, v in (effects or {}).items() if float(v) != 0.0))
        idx = np.arange(self.n) if rows is None else np.asarray(rows, dtype=np.int64)
        todo = []  # (k, missing fibers)
        for k in ks:
            whole = (k, eff, idx.tobytes())
            if (k, eff, None) not in self._whole and whole not in self._whole:
                self.runs_without_reuse += len(idx)
                self._whole.add((k, eff, None) if rows is None else whole)
            have = self._cache.get((k, eff))
            missing = np.unique(idx) if have is None else np.setdiff1d(idx, have.index.to_numpy())
            if len(missing) and k not in {t[0] for t in todo}:
                todo.append((k, missing))
        if todo:
            drawn = [self.draws(k) for k, _ in todo]
            starts = np.concatenate([d[0][m] for d, (_, m) in zip(drawn, todo, strict=True)])
            seeds = np.concatenate([d[1][m] for d, (_, m) in zip(drawn, todo, strict=True)])
            raw = self.sim.run(starts, dict(eff), seeds, desc=desc)
            at = 0
            for d, (k, m) in zip(drawn, todo, strict=True):
                part = raw.iloc[at : at + len(m)].reset_index(drop=True)
                at += len(m)
                out = self.noise.observe(part, {name: zn[m] for name, zn in d[2].items()})
                out.index = m
                have = self._cache.get((k, eff))
                self._cache[(k, eff)] = out if have is None else pd.concat([have, out])
        return [self._cache[(k, eff)].loc[idx].reset_index(drop=True) for k in ks]


def crossfit_copies(
    maker: CopyMaker,
    folds: Sequence[np.ndarray],
    effects_per_fold: Sequence[Mapping[str, float]],
    copies: int,
    desc: str,
) -> list[pd.DataFrame]:
    """Copies 0..copies-1 of every fiber, fold f simulated with ``effects_per_fold[f]``.

    Returns
    -------
    list of DataFrame, each with one row per fiber in the original order.
    """
    order = np.argsort(np.concatenate(folds))
    per_fold = [
        maker.copies(range(copies), dict(eff), held, desc=desc)
        for held, eff in zip(folds, effects_per_fold, strict=True)
    ]
    return [
        pd.concat([p[k] for p in per_fold], ignore_index=True).iloc[order].reset_index(drop=True)
        for k in range(copies)
    ]
