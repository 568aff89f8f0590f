"""Which candidates match the gap: their signatures, ranked.

Signature: a candidate is switched on at a probe value, one measured-like copy
of the fit fibers is simulated and treated as if it were the measurement; its
gap to the baseline copies, read as a vector of z-scores (excess per
observable, signed bias per component; :func:`.gap.feature_vector`), is its
signature. Candidates are ranked by the cosine between their signature and the
measured gap's (:func:`rank_effects`); the best few, and those that tie with
the best, are fitted (:func:`choose_candidates`). A second effect's partners
are ranked by their signature against the gap the first effect leaves
(:func:`rank_partners`).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from fibersweep.discrepancy.candidates import Candidate
from fibersweep.discrepancy.copies import CopyMaker
from fibersweep.discrepancy.gap import GapResult, assess_gap, feature_vector, value_matrices

__all__ = ["Signature", "choose_candidates", "rank_effects", "rank_partners"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Signature:
    """Match of one effect's signature to the gap.

    Attributes
    ----------
    name : str
    probe : float
        Probe value that matched best.
    cosine : float
        Cosine similarity of the signature and the gap's feature vector.
    strength : float
        Norm of the signature (how visible the effect is at the probe).
    vectors : tuple of (probe, ndarray)
        The signature at every probe (forward selection matches them with the
        gap the first effect leaves).
    """

    name: str
    probe: float
    cosine: float
    strength: float
    vectors: tuple[tuple[float, np.ndarray], ...] = field(default=(), repr=False, compare=False)


def rank_effects(
    gap_features: np.ndarray,
    candidates: Sequence[Candidate],
    maker: CopyMaker,
    base_copies: Sequence[pd.DataFrame],
    rows: np.ndarray,
    observables: Sequence[str],
    probe_copy: int,
    rng: np.random.Generator,
) -> list[Signature]:
    """Signatures of the candidates, best match first.

    Parameters
    ----------
    gap_features : ndarray
        :func:`.gap.feature_vector` of the measured gap.
    base_copies : sequence of DataFrame
        Baseline copies restricted to ``rows``.
    rows : ndarray of int
        Fibers used for the probes (the fit split).
    probe_copy : int
        Copy index of the probes (independent of the baseline copies).
    """
    g = np.asarray(gap_features, dtype=np.float64)
    gn = np.linalg.norm(g) or 1.0
    out = []
    for cand in candidates:
        best: Signature | None = None
        vecs = []
        for v in cand.probes:
            probe = maker.copy(probe_copy, {cand.name: v}, rows, desc=f"probe {cand.name}={v:g}")
            vals = value_matrices(probe, base_copies, observables)
            sig = feature_vector(assess_gap(vals, rng, n_perm=999, n_boot=200))
            norm = float(np.linalg.norm(sig))
            cos = float(sig @ g / (norm * gn)) if norm > 0 else 0.0
            vecs.append((float(v), sig))
            s = Signature(cand.name, v, cos, norm)
            if best is None or s.cosine > best.cosine:
                best = s
        log.info("signature %s: cos %.2f at %g", best.name, best.cosine, best.probe)
        out.append(replace(best, vectors=tuple(vecs)))
    return sorted(out, key=lambda s: -s.cosine)


def choose_candidates(
    signatures: Sequence[Signature], k: int, tied: int, window: float
) -> list[Signature]:
    """The effects to fit: the ``k`` best matches, and up to ``tied`` more that tie.

    A further effect ties when its cosine is within ``window`` of the best one's:
    look-alike effects (the slowing ones) have signatures that the noise of an
    N = 100 gap does not order, and an effect outside the fitted few is never named.

    Parameters
    ----------
    signatures : sequence of Signature
        Best match first (:func:`rank_effects`).
    k : int
        Effects always fitted (those with a positive cosine only).
    tied : int
        Most effects added beyond ``k``.
    window : float
        Largest shortfall of a tied effect's cosine below the best's.
    """
    positive = [sg for sg in signatures if sg.cosine > 0]
    chosen = positive[:k]
    if not chosen:
        return []
    floor = chosen[0].cosine - window
    extra = [sg for sg in positive[k:] if sg.cosine >= floor][:tied]
    return chosen + extra


def rank_partners(
    first: str, signatures: Sequence[Signature], left: GapResult, k: int
) -> list[str]:
    """The ``k`` effects whose signature best matches the gap the first effect leaves.

    The single-effect ranking matches signatures with the whole gap, which the
    first effect dominates; its partner's part shows in what is left
    (:func:`gap.feature_vector` of ``left``). Cosine over every probe of an
    effect; only effects with a positive match are returned, best first.
    """
    g = feature_vector(left)
    gn = float(np.linalg.norm(g))
    if gn == 0.0:
        return []
    cos = {}
    for sg in signatures:
        if sg.name == first or not sg.vectors:
            continue
        c = [
            float(v @ g / (np.linalg.norm(v) * gn)) for _, v in sg.vectors if np.linalg.norm(v) > 0
        ]
        if c and max(c) > 0:
            cos[sg.name] = max(c)
    order = sorted(cos, key=lambda n: -cos[n])
    log.info("partners of %s by the gap it leaves: %s", first, {n: round(cos[n], 2) for n in order})
    return order[:k]
