"""The power statement's own error (issue 30, item 3): percentile intervals over the
simulated starts, for the limits and for the fibers needed (pure functions and a
stand-in read-out; no simulations)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest
from scipy.stats import norm

from fibersweep.discrepancy.candidates import Candidate
from fibersweep.discrepancy.detection import (
    EffectPower,
    PowerResult,
    detection_limit,
    growth_exponent,
    percentile_interval,
)
from fibersweep.discrepancy.gap import assess_gap, feature_one_sided, value_matrices
from fibersweep.discrepancy.power import _z_of, limit_intervals

CAND = Candidate("pillar_scale", -0.2, 0.2, (0.1,), 0.08, "")


def test_percentile_interval_is_two_order_statistics_and_never_nan():
    vals = [float(v) for v in range(1, 41)]  # 40 resamples: 2.5 % -> the 1st, 97.5 % -> 39th
    assert percentile_interval(vals) == (1.0, 39.0)
    # resamples that never reach the target (infinite) give an open end, never NaN
    assert percentile_interval([*vals[:30], *[math.inf] * 10]) == (1.0, None)
    assert percentile_interval([math.inf] * 5) == (None, None)
    assert percentile_interval([]) == (None, None)


def test_fibers_to_detect_interval_follows_each_resamples_read_out():
    # one two-sided test, z = 2 on 50 simulated fibers: N = 50 ((zc + z_0.8) / z)^2.
    # Resamples with z from 1.5 to 2.5 give their own N, exactly (to the ceiling); the
    # 95 % interval of 40 resamples is their 1st and 39th order statistics.
    zc = 2.8
    zs = np.linspace(1.5, 2.5, 40)
    e = EffectPower("x", 0.1, (2.0,), 1.0, None, boot=tuple(((float(z),), 1.0) for z in zs))
    need = sorted(math.ceil(50 * ((zc + norm.ppf(0.8)) / z) ** 2) for z in zs)
    lo, hi = e.fibers_to_detect_ci(0.1, 50, zc, 0.8)
    assert (lo, hi) == (need[0], need[38])
    assert lo <= e.fibers_to_detect(0.1, 50, zc, 0.8) <= hi
    # a resample that sees nothing needs more than any number of fibers: open upper end
    e0 = EffectPower(
        "x", 0.1, (2.0,), 1.0, None, boot=(((2.0,), 1.0),) * 30 + (((0.0,), 1.0),) * 10
    )
    assert e0.fibers_to_detect_ci(0.1, 50, zc, 0.8)[1] is None
    # without resamples: no interval; PowerResult finds the entry by name and sign
    assert EffectPower("x", 0.1, (2.0,), 1.0, None).fibers_to_detect_ci(0.1, 50, zc, 0.8) is None
    pw = PowerResult(100, 50, 0.05, 0.8, zc, [e], [], {}, 0)
    assert pw.fibers_to_detect_ci("x", 0.1) == (lo, hi)
    assert pw.fibers_to_detect_ci("x", -0.1) is None


def _read_out(rng: np.random.Generator, n_sim: int, n_boot: int, sigma: float = 0.05):
    """A stand-in effect read out like analyse_power: δ shifted by m r_i, where fibers
    near x = 0.25 respond 3 times as much (the limit depends on which starts were
    drawn), noise sigma, 3 copies, probes 0.1 and 0.05; limits for N = 100."""
    x = rng.uniform(0.0, 0.5, n_sim)
    resp = 1.0 + 2.0 * np.exp(-(((x - 0.25) / 0.05) ** 2))

    def copies(m):
        return [pd.DataFrame({"delta": x + m * resp + sigma * rng.standard_normal(n_sim)})
                for _ in range(3)]  # fmt: skip

    base, full, half = copies(0.0), copies(0.1), copies(0.05)
    g0 = assess_gap(value_matrices(base[0], base[1:], ["delta"]), rng, n_perm=99)
    one = tuple(bool(v) for v in feature_one_sided(g0))
    zc = float(norm.ppf(1 - 0.05 / (2 * len(one))))
    zf, zh = _z_of(full, base, ["delta"], rng), _z_of(half, base, ["delta"], rng)
    e = EffectPower("pillar_scale", 0.1, tuple(zf), growth_exponent(zf, zh), None, one)
    lim = detection_limit(e, CAND, 100, n_sim, zc, 0.8)
    e = EffectPower(e.name, e.probe, e.z, e.gamma, lim, one)
    if not n_boot:
        return e
    (eb,) = limit_intervals([e], [(full, half)], base, [CAND], 100, ["delta"], zc, 0.8, rng,
                            n_boot=n_boot)  # fmt: skip
    return eb


def test_limit_interval_over_40_starts_covers_the_limit_of_many_starts():
    # The limit that 2000 simulated starts give (the reference: 0.0091, 0.0091, 0.0089
    # over 3 draws) against the 95 % bootstrap interval (30 resamples) from sets of 40
    # starts, as the report draws them. Measured coverage: 30 of 30 sets here (seed 5;
    # the single set's limit 0.0098 ± 0.0021), 96 of 100 and 28 of 30 on seeds 3 and 1.
    # Stated: at least 25 of 30 sets (0.83: the binomial 3 sd of 30 draws at 0.95 is
    # 0.12). Not claimed for a probe far below the limit (docs: 83 of 100 there).
    rng = np.random.default_rng(5)
    ref = float(np.mean([_read_out(rng, 2000, 0).limit for _ in range(3)]))
    hits = 0
    for _ in range(30):
        lo, hi = _read_out(rng, 40, 30).limit_ci
        hits += lo <= ref <= (math.inf if hi is None else hi)
    assert hits >= 25


def test_limit_interval_is_reproducible_from_its_seed():
    a = _read_out(np.random.default_rng(9), 40, 20)
    b = _read_out(np.random.default_rng(9), 40, 20)
    assert a.limit_ci == b.limit_ci and a.boot == b.boot and len(a.boot) == 20
    assert a.limit_ci[0] <= a.limit <= a.limit_ci[1]


def test_each_resamples_read_out_reproduces_its_limit():
    # the kept read-outs are the ones the limit interval was taken over
    e = _read_out(np.random.default_rng(11), 40, 20)
    zc = float(norm.ppf(1 - 0.05 / (2 * len(e.z))))
    lims = []
    for z, g in e.boot:
        eb = EffectPower(e.name, e.probe, z, g, None, e.one_sided)
        lim = detection_limit(eb, CAND, 100, 40, zc, 0.8)
        lims.append(math.inf if lim is None else lim)
    assert percentile_interval(lims) == pytest.approx(e.limit_ci)


def test_a_refined_read_out_passes_through_both_magnitudes_per_test():
    # Two tests read at m = 0.01 and 0.04: z = (1, 0.2) and (4, 3.2). Each follows its
    # own power law between them (exponents 1 and 2), exact at both ends to 1e-12,
    # and the exponents are clipped to [0.5, 3] (a test that reads nothing below
    # grows as fast as allowed).
    from fibersweep.discrepancy.detection import pair_exponents

    za, zb = np.array([1.0, -0.2]), np.array([4.0, -3.2])
    assert np.allclose(pair_exponents(za, 0.01, zb, 0.04), [1.0, 2.0], rtol=0, atol=1e-12)
    assert np.allclose(pair_exponents(zb, 0.04, za, 0.01), [1.0, 2.0], rtol=0, atol=1e-12)
    g = pair_exponents(np.array([0.0, 4.0]), 0.01, np.array([5.0, 1.0]), 0.04)
    assert g.tolist() == [3.0, 0.5]
    e = EffectPower("x", 0.15, tuple(za), 1.0, None, read_at=0.01, against=0.04,
                    z_against=tuple(zb))  # fmt: skip
    assert np.allclose(e.z_of(0.01), za, rtol=0, atol=1e-12)
    assert np.allclose(e.z_of(0.04), zb, rtol=0, atol=1e-12)
    assert np.allclose(e.z_of(0.02), [2.0, -0.8], rtol=0, atol=1e-12)
    # detection follows: 4 x the fibers doubles every z
    assert e.detect(0.02, 40, 10, 2.5) == pytest.approx(
        1 - np.prod(1 - norm.cdf(np.array([4.0, 1.6]) - 2.5)), abs=1e-12
    )
    # a bootstrap read-out of a refined entry carries its second z-vector
    eb = replace(e, boot=((tuple(za), 1.0, tuple(zb)),) * 3)
    need = eb.fibers_to_detect(0.02, 10, 2.5, 0.8)
    assert eb.fibers_to_detect_ci(0.02, 10, 2.5, 0.8) == (need,) * 2
