"""What-to-measure-next's estimates on arrays: the debiased shift, the winner's curse
and the window around a proposed start (fibersweep.discrepancy.followup)."""

from __future__ import annotations

import numpy as np

from fibersweep.discrepancy.copies import NoiseModel
from fibersweep.discrepancy.next_measure import WINDOW, _shift2, window_points


def test_the_squared_shift_is_unbiased_and_its_best_of_many_is_not():
    """Two copies per point, unit noise, a true shift of 0.5 at every point.

    The debiased D² averages 0.25 over 16000 points (its se about 0.02: tolerance
    0.1), unclipped; clipped at 0 point by point it would average about 0.9. The
    largest D of 120 points is far above 0.5: the winner's curse the window stage
    removes with new copies, which average 0.25 again.
    """
    rng = np.random.default_rng(11)
    k, n = 2, 16000
    xa = rng.standard_normal((k, n, 1)) + 0.5
    xb = rng.standard_normal((k, n, 1))
    d2 = _shift2(xa, xb, np.ones(1))[:, 0]
    assert abs(d2.mean() - 0.25) < 0.1, d2.mean()
    assert np.clip(d2, 0, None).mean() > 0.6  # why the average comes before the clip
    best = np.sqrt(d2[:120].max())
    assert best > 1.5, best
    fresh = _shift2(rng.standard_normal((k, n, 1)) + 0.5, rng.standard_normal((k, n, 1)),
                    np.ones(1))[:, 0]  # fmt: skip
    assert abs(fresh.mean() - 0.25) < 0.1


def test_window_points_lie_within_the_window_of_their_start():
    noise = NoiseModel()
    centres = np.array([[-5.0, 0.3, 0.8], [2.0, 0.5, 1.2]])
    pts = window_points(centres, noise, 50, np.random.default_rng(0))
    assert pts.shape == (100, 3)
    half = WINDOW * np.array([noise.theta0, noise.y0, noise.length])
    for j, c in enumerate(centres):
        mine = pts[j * 50 : (j + 1) * 50]
        assert np.all(np.abs(mine - c) <= half)
        # uniform, not all at the centre: they fill most of the window
        assert np.all(np.ptp(mine, axis=0) > 1.5 * half)
