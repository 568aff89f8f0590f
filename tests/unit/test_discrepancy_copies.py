"""The copies' starts: a start column whose true values are one value is copied at it."""

from __future__ import annotations

import numpy as np

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.copies import FIXED_LEVEL, CopyMaker, NoiseModel, fixed_columns
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.flow.field import FlowField
from fibersweep.units import Geometry


def _measured(rng: np.random.Generator, n: int, length: tuple[float, float]) -> np.ndarray:
    true = np.column_stack([rng.uniform(-8, 8, n), rng.uniform(0.05, 0.9, n),
                            rng.uniform(*length, n)])  # fmt: skip
    return NoiseModel().jitter_starts(true, rng)


def test_one_true_length_is_found_at_the_level_and_a_spread_of_lengths_never():
    # 400 data sets of 100 fibers, every true length 1.0: the length column is taken as
    # one value unless its variance test rejects, which it does with probability
    # FIXED_LEVEL = 0.001 per data set: at most 3 misses of 400 (P(X >= 4) = 8e-4 for a
    # binomial(400, 0.001)). The study box's lengths (0.5..1.4, sd 0.26 against the
    # noise 0.01) and every theta0 and y0 column are never one value.
    assert FIXED_LEVEL == 0.001
    rng = np.random.default_rng(7)
    found = [fixed_columns(_measured(rng, 100, (1.0, 1.0)), NoiseModel()) for _ in range(400)]
    assert sum(2 not in f for f in found) <= 3
    assert all(set(f) <= {2} for f in found)
    # the value is the mean of the measured lengths: within 4 sd of its error, 0.001
    assert all(abs(f[2] - 1.0) < 4 * 0.01 / np.sqrt(100) for f in found if 2 in f)
    spread = [fixed_columns(_measured(rng, 100, (0.5, 1.4)), NoiseModel()) for _ in range(100)]
    assert all(f == {} for f in spread)


def test_too_few_fibers_or_no_noise_keep_every_column_jittered():
    rng = np.random.default_rng(8)
    assert fixed_columns(_measured(rng, 19, (1.0, 1.0)), NoiseModel()) == {}
    exact = np.column_stack([rng.uniform(-8, 8, 50), rng.uniform(0.1, 0.9, 50), np.ones(50)])
    assert fixed_columns(exact, NoiseModel(length=0.0)) == {}


def test_copies_start_a_fixed_column_at_its_value_and_keep_the_other_columns_draws():
    # the same maker's draws with and without the fixed column differ only in it:
    # the other columns' jitter (and the run seeds, the outcome noise) are unchanged
    rng = np.random.default_rng(9)
    starts = _measured(rng, 40, (1.0, 1.0))
    field = FlowField.from_function(lambda X, Y: (600.0 + 0 * X, 0 * X), Geometry(), 8.0)
    with Simulator(field, FiberSettings(), workers=1, progress=False) as sim:
        maker = CopyMaker(starts, NoiseModel(), 3, sim)
        jittered = CopyMaker(starts, NoiseModel(), 3, sim)
        jittered.fixed = {}
        (a, sa, za), (b, sb, zb) = maker.draws(2), jittered.draws(2)
    assert list(maker.fixed) == [2]
    assert np.all(a[:, 2] == maker.fixed[2])
    assert np.array_equal(a[:, :2], b[:, :2]) and np.array_equal(sa, sb)
    assert all(np.array_equal(za[k], zb[k]) for k in za)
    assert np.std(b[:, 2]) > 0.005  # jittered: the measured length plus the noise
