"""The gap between observations and a model ensemble, per observable, with its significance.

Input is a value matrix per observable (column 0 observed, then the model's
copies; see :mod:`fibersweep.discrepancy.scores`). For each observable two
permutation tests (noise floor = the model's own copies) are run: the proper
score (does the observation sit worse than a copy?) and the signed residual per
component (is it shifted?). A shift that is small against the spread of the
copies, e.g. every contact a few per cent slower, is seen by the signed test
long before the score's; a spread is seen only by the score. All p-values of
both kinds, over all observables, are Holm-corrected together: one family-wise
error rate for "there is a gap".
Descriptive measures (confusion matrix, Wasserstein distance of δ, mismatch
rates, paired residuals) go to the report.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.stats import wasserstein_distance

from fibersweep.discrepancy.observables import OBSERVABLES, geometry_of, has_tracks, scored
from fibersweep.discrepancy.scores import (
    PermTest,
    bootstrap_mean_ci,
    excess,
    holm,
    permutation_test,
    residual_matrix,
    score_matrix,
)

__all__ = [
    "GAP_UNIT",
    "ObservableGap",
    "GapResult",
    "value_matrices",
    "assess_gap",
    "describe",
    "feature_vector",
    "feature_one_sided",
    "weighted_loss",
    "combined_excess",
    "observable_weights",
    "paired_improvement",
]

#: Unit of the gap in every table and figure: an observable's excess score divided by the
#: spread of the copies' own scores (:func:`observable_weights`; 0: as good as a copy).
GAP_UNIT = "copy-spread units"


def value_matrices(
    observed: pd.DataFrame, copies: Sequence[pd.DataFrame], observables: Sequence[str]
) -> dict[str, np.ndarray]:
    """Stack observed values and model copies into per-observable matrices.

    Parameters
    ----------
    observed : DataFrame, n rows
        Canonical measured table (class names, contact bool) or an outcome table
        from :class:`~fibersweep.discrepancy.simulate.Simulator`.
    copies : sequence of DataFrame, each n rows
        Model outcome tables (missing values for failures).
    observables : sequence of str

    Returns
    -------
    dict name -> ndarray, shape (n, 1 + len(copies))
        In registry order; category indices for categorical observables
        (:meth:`~fibersweep.discrepancy.observables.Observable.values`).
    """
    out = {}
    for name in (o for o in OBSERVABLES if o in observables):
        values = OBSERVABLES[name].values
        out[name] = np.column_stack([values(observed[name])] + [values(c[name]) for c in copies])
    return out


@dataclass(frozen=True)
class ObservableGap:
    """Gap of one observable.

    Attributes
    ----------
    name : str
    test : PermTest
        Permutation test of the mean leave-one-out score.
    p_holm : float
        Holm-adjusted p-value over the observables tested together.
    significant : bool
        p_holm <= alpha.
    excess : tuple of float
        (mean, lo, hi): mean per-fiber excess score over the noise floor with
        its bootstrap 95 % interval (0 = as good as the model's own copies).
    bias_z : tuple of float
        z-scores of the signed residual per component (per class for 'class').
    bias_p : tuple of float
        Two-sided permutation p-values of those residuals (raw).
    bias_p_holm : tuple of float
        The same, Holm-adjusted in the family of all tests.
    """

    name: str
    test: PermTest
    p_holm: float
    significant: bool
    excess: tuple[float, float, float]
    bias_z: tuple[float, ...]
    bias_p: tuple[float, ...] = ()
    bias_p_holm: tuple[float, ...] = ()


@dataclass(frozen=True)
class GapResult:
    """Gaps of all observables tested together.

    Attributes
    ----------
    gaps : dict name -> ObservableGap
    alpha : float
    per_fiber : dict name -> ndarray, shape (n,)
        Per-fiber excess scores (NaN where undefined), for localisation.
    """

    gaps: dict[str, ObservableGap]
    alpha: float
    per_fiber: dict[str, np.ndarray] = field(repr=False)

    @property
    def significant(self) -> list[str]:
        """Observables whose score shows a significant gap, strongest first."""
        sig = [g for g in self.gaps.values() if g.significant]
        return [g.name for g in sorted(sig, key=lambda g: g.p_holm)]

    @property
    def biased(self) -> list[str]:
        """Observables with a significant systematic (signed) residual, strongest first.

        A mean shift of the observations against the model's copies is also what
        a zero-mean spread (start noise, Brownian motion) cannot produce.
        """
        best = {
            g.name: min(g.bias_p_holm)
            for g in self.gaps.values()
            if g.bias_p_holm and min(g.bias_p_holm) <= self.alpha
        }
        return sorted(best, key=best.__getitem__)

    @property
    def flagged(self) -> list[str]:
        """Observables with a significant gap of either kind, strongest first."""
        p = {}
        for g in self.gaps.values():
            cands = [g.p_holm] if g.significant else []
            cands += [q for q in g.bias_p_holm if q <= self.alpha]
            if cands:
                p[g.name] = min(cands)
        return sorted(p, key=p.__getitem__)

    @property
    def any(self) -> bool:
        """Whether any test of the family rejects."""
        return bool(self.flagged)


def assess_gap(
    values: Mapping[str, np.ndarray],
    rng: np.random.Generator,
    alpha: float = 0.05,
    n_perm: int = 4999,
    n_boot: int = 1000,
) -> GapResult:
    """Test every observable in ``values`` against the noise floor of the copies.

    Parameters
    ----------
    values : mapping name -> ndarray, shape (n, m)
        From :func:`value_matrices`.
    rng : numpy.random.Generator
    alpha : float
        Family-wise error rate (Holm over the observables).
    """
    names = [o for o in scored(tracks=True, geometry=geometry_of(values)) if o in values]
    tests: dict[str, PermTest] = {}
    per_fiber: dict[str, np.ndarray] = {}
    biases: dict[str, list[PermTest]] = {}
    for name in names:
        S = score_matrix(name, values[name])
        tests[name] = permutation_test(S, rng, n_perm=n_perm)
        per_fiber[name] = excess(S)
        R = residual_matrix(name, values[name])
        biases[name] = [
            permutation_test(R[:, :, c], rng, n_perm=min(n_perm, 1999), two_sided=True)
            for c in range(R.shape[2])
        ]
    # one Holm family: the score test of every observable, then its residual components
    p = [tests[n].p_value for n in names]
    for n in names:
        p += [t.p_value if t.n > 0 else 1.0 for t in biases[n]]
    p_adj = holm(np.array(p)) if p else np.array([])
    gaps = {}
    at = len(names)
    for k, name in enumerate(names):
        nb = len(biases[name])
        b_adj = tuple(float(x) for x in p_adj[at : at + nb])
        at += nb
        gaps[name] = ObservableGap(
            name=name,
            test=tests[name],
            p_holm=float(p_adj[k]),
            significant=bool(p_adj[k] <= alpha and tests[name].n > 0),
            excess=bootstrap_mean_ci(per_fiber[name], rng, n_boot=n_boot),
            bias_z=tuple(t.z for t in biases[name]),
            bias_p=tuple(t.p_value for t in biases[name]),
            bias_p_holm=b_adj,
        )
    return GapResult(gaps=gaps, alpha=alpha, per_fiber=per_fiber)


def _feature_parts(gap: GapResult) -> list[tuple[np.ndarray, bool]]:
    """The blocks of :func:`feature_vector`, each with whether its tests are one-sided."""
    # the track observables' components only when the gap has them (tracks measured):
    # without tracks, no track components: vectors of data sets without tracks compare
    names = scored(tracks=has_tracks(gap.gaps), geometry=geometry_of(gap.gaps))
    parts = []
    for name in names:
        g = gap.gaps.get(name)
        parts.append((np.array([g.test.z if g else 0.0]), True))
    for name in names:
        g = gap.gaps.get(name)
        bias = np.array(g.bias_z) if g else np.zeros(OBSERVABLES[name].width)
        parts.append((bias, False))
    return parts


def feature_vector(gap: GapResult) -> np.ndarray:
    """Signature of a gap: excess z per observable, then signed bias z per component.

    Shape (k + sum of the residual widths,) over the k scored observables of the
    registry (categories or 1 each; the track observables only when the gap has
    them); observables not present give zeros, so vectors from data sets with
    the same kind of data (with or without tracks) are comparable.
    """
    v = np.concatenate([x for x, _ in _feature_parts(gap)])
    return np.where(np.isfinite(v), v, 0.0)


def feature_one_sided(gap: GapResult) -> np.ndarray:
    """Which entries of :func:`feature_vector` are one-sided tests, same layout.

    The score tests reject only when the data score worse than the model's
    copies (one-sided); the signed residual components reject either way.
    """
    return np.concatenate([np.full(len(x), one) for x, one in _feature_parts(gap)])


def observable_weights(values: Mapping[str, np.ndarray]) -> dict[str, float]:
    """1 / per-fiber spread of each observable's scores among the model copies.

    Puts scores of different units (Brier points, degrees, h_obs) on one scale for the
    combined loss; computed from the baseline copies only (columns 1..m-1).
    """
    w = {}
    for name, V in values.items():
        S = score_matrix(name, V)[:, 1:]
        sd = float(np.nanstd(S)) if np.isfinite(S).any() else 0.0
        w[name] = 1.0 / sd if sd > 0 else 0.0
    return w


def weighted_loss(
    values: Mapping[str, np.ndarray], weights: Mapping[str, float]
) -> dict[str, np.ndarray]:
    """Per-fiber observed score of each observable times its weight, shape (n,) each."""
    return {n: score_matrix(n, V)[:, 0] * weights.get(n, 0.0) for n, V in values.items()}


def combined_excess(gap: GapResult, weights: Mapping[str, float]) -> np.ndarray:
    """Per-fiber excess score summed over observables, each times its weight.

    Parameters
    ----------
    gap : GapResult
        Its ``per_fiber`` excess scores (NaN counts as 0).
    weights : mapping name -> float
        From :func:`observable_weights` (1 / spread of the copies' scores).

    Returns
    -------
    ndarray, shape (n,)
        In units of the per-fiber spread of the copies' scores; empty without observables.
    """
    tot = None
    for name, e in gap.per_fiber.items():
        v = np.where(np.isfinite(e), e, 0.0) * weights.get(name, 0.0)
        tot = v if tot is None else tot + v
    return tot if tot is not None else np.zeros(0)


def paired_improvement(
    before: Mapping[str, np.ndarray], after: Mapping[str, np.ndarray]
) -> np.ndarray:
    """Per-fiber decrease of the weighted loss, summed over observables defined in both.

    Returns
    -------
    ndarray, shape (n,)
        Positive where the second model scores the observation better.
    """
    names = [n for n in before if n in after]
    n = len(next(iter(before.values())))
    d = np.zeros(n)
    for name in names:
        b, a = before[name], after[name]
        ok = np.isfinite(b) & np.isfinite(a)
        d[ok] += b[ok] - a[ok]
    return d


def describe(values: Mapping[str, np.ndarray]) -> dict[str, object]:
    """Descriptive gap measures for the report (observed vs the model's copies).

    Returns
    -------
    dict
        In registry order: per class observable the ``confusion`` matrix (observed
        x modal model category counts) and ``<name>_agreement``; per binary one
        ``<name>_mismatch`` (rate); per continuous one ``<name>_residual`` (paired
        residual mean and sd: observed minus the copies' mean) and its extra
        ``measures``: ``<name>_wasserstein`` (distance of the distributions, e.g.
        delta) and ``<name>_ratio`` (median observed / model, e.g. t_pass).
    """
    out: dict[str, object] = {}
    for name, V in values.items():
        o = OBSERVABLES[name]
        if o.kind == "class":
            out.update(_confusion(name, V, o.categories))
        elif o.kind == "binary":
            p = np.nanmean(V[:, 1:], axis=1)
            ok = np.isfinite(V[:, 0]) & np.isfinite(p)
            out[f"{name}_mismatch"] = float(np.mean(np.abs(V[ok, 0] - np.round(p[ok]))))
        else:
            out.update(_residual_measures(name, V, o.measures))
    return out


def _confusion(name: str, V: np.ndarray, labels: tuple[str, ...]) -> dict[str, object]:
    """Observed category x modal model category counts, and the agreement rate."""
    k = len(labels)
    counts = np.stack([(V[:, 1:] == c).sum(axis=1) for c in range(k)], axis=1)
    modal = np.where(counts.sum(axis=1) > 0, counts.argmax(axis=1), -1)
    conf = np.zeros((k, k), dtype=int)
    for o, m in zip(V[:, 0], modal, strict=True):
        if np.isfinite(o) and m >= 0:
            conf[int(o), m] += 1
    key = "confusion" if name == "class" else f"{name}_confusion"
    return {
        key: {"labels": list(labels), "counts": conf.tolist()},
        f"{name}_agreement": float(np.trace(conf) / max(conf.sum(), 1)),
    }


def _residual_measures(name: str, V: np.ndarray, measures: tuple[str, ...]) -> dict[str, object]:
    """Paired residual (observed minus the copies' mean) and the observable's extra measures."""
    out: dict[str, object] = {}
    fin = np.isfinite(V[:, 1:])
    cnt = fin.sum(axis=1)
    mean = np.where(cnt > 0, np.where(fin, V[:, 1:], 0.0).sum(axis=1) / np.maximum(cnt, 1), np.nan)
    r = V[:, 0] - mean
    r = r[np.isfinite(r)]
    out[f"{name}_residual"] = {
        "mean": float(r.mean()) if len(r) else None,
        "sd": float(r.std()) if len(r) > 1 else None,
        "n": int(len(r)),
    }
    if "wasserstein" in measures:
        obs = V[:, 0][np.isfinite(V[:, 0])]
        mod = V[:, 1:][np.isfinite(V[:, 1:])]
        if len(obs) and len(mod):
            out[f"{name}_wasserstein"] = float(wasserstein_distance(obs, mod))
    if "ratio" in measures:
        ratio = V[:, 0] / mean
        ratio = ratio[np.isfinite(ratio)]
        out[f"{name}_ratio"] = float(np.median(ratio)) if len(ratio) else None
    return out
