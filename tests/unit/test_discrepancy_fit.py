"""The 1D effect fit on a stand-in model whose outcome is known in closed form."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from fibersweep.discrepancy.fit import fit_effect
from fibersweep.discrepancy.library import LIBRARY


class _ShiftModel:
    """δ of copy k = x_i + value + 0.01 z_ik: an effect that shifts δ by its value."""

    def __init__(self, n: int):
        rng = np.random.default_rng(0)
        self.x = rng.uniform(0.0, 0.5, n)
        self.z = rng.standard_normal((4, n))
        self.calls = 0

    def copy(self, k, effects=None, rows=None, desc=""):
        self.calls += 1
        v = float((effects or {}).get("pillar_scale", 0.0))
        idx = np.arange(len(self.x)) if rows is None else rows
        return pd.DataFrame({"delta": self.x[idx] + v + 0.01 * self.z[k, idx]})


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_signed_fit_recovers_the_value_whichever_side_the_signature_said(side):
    # truth +0.08 on a signed effect; a signature pointing at -1 is overruled by the one
    # evaluation in the other half. Tolerance 0.01 (5 Brent steps on [0, 0.2]).
    n = 40
    model = _ShiftModel(n)
    observed = pd.DataFrame({"delta": model.x + 0.08})
    base = [model.copy(k) for k in range(2)]
    model.calls = 0
    fit = fit_effect(
        LIBRARY["pillar_scale"],
        model,
        observed,
        base,
        np.arange(n),
        ["delta"],
        {"delta": 1.0},
        max_evals=5,
        side=side,
    )
    assert fit.value == pytest.approx(0.08, abs=0.01)
    assert fit.loss < fit.loss0
    # 2 copies per evaluation: at most 5 Brent evaluations + 1 side check
    assert model.calls <= 2 * 6
