"""float32 population storage (the default) against the float64 reference (flow.precision).

The populations are stored as their deviation from rest, g = f − w, so float32
keeps about seven significant digits of the part that carries the flow. These
tests check that the default loses nothing measurable against float64: the duct
flow against the analytic series, the field past the pillar at dx = 4 µm, and
mass conservation.
"""

from __future__ import annotations

import numpy as np
import pytest
from _duct_case import solve_duct

from fibersweep.flow.analysis import flux_separatrix, peak_speeds


def _duct(precision: str) -> tuple[float, np.ndarray, float]:
    """(relative L2 error of ux against the series, ux, mass change): 2:1 duct, 20 nodes deep."""
    sol, ux, err = solve_duct(20, 40, tau=1.0, precision=precision)
    return err, ux, sol.report.mass_change


def test_float32_duct_as_accurate_as_float64():
    # Duct Poiseuille flow (TRT, 20 nodes across the depth) against the series:
    # the float32 error must equal the float64 one to 1 % of it (the
    # discretisation error dominates; rounding is 1e-7 relative), and the two
    # fields agree to 1e-5 relative L2. Measured: float64 2.3925e-4, float32
    # 2.3805e-4 (0.5 % apart: each stops at the tolerance 1e-7 at a slightly
    # different point), fields 1.3e-6 apart.
    e32, u32, m32 = _duct("float32")
    e64, u64, m64 = _duct("float64")
    assert e64 < 1e-2 and e32 < 1e-2, (e32, e64)
    assert abs(e32 - e64) < 1e-2 * e64, (e32, e64)
    diff = np.linalg.norm(u32 - u64) / np.linalg.norm(u64)
    assert diff < 1e-5, diff
    # mass: half-way bounce-back walls conserve it link by link; tolerance 1e-9
    # relative over the whole solve (measured 7e-12 float32, 0 float64)
    assert abs(m32) < 1e-9 and abs(m64) < 1e-9, (m32, m64)


@pytest.fixture(scope="module")
def pillar_pair(flow_cache_dir, coarse_settings):
    """The dx = 4 µm channel field (default settings) in float32 and float64."""
    from fibersweep.flow.cache import get_flow_field

    f32, _ = get_flow_field(coarse_settings, flow_cache_dir)
    f64, _ = get_flow_field(
        coarse_settings.model_copy(update={"precision": "float64"}), flow_cache_dir
    )
    return f32, f64


def test_float32_pillar_field_matches_float64(pillar_pair):
    # Full channel at dx = 4 µm, default pillar wall and tolerance (1e-6): the
    # separatrix of the two precisions agrees to 0.001 h_obs, the midplane
    # velocity to 1e-4 relative L2 and the peak speeds to 1e-4 U. Both stop at
    # the same tolerance, so the difference is mostly where each stopped, not
    # rounding. Measured: separatrix 2e-7 h_obs apart (0.342225), field 1.1e-6
    # relative L2, peaks 3e-6 U apart.
    f32, f64 = pillar_pair
    # entries cached before the key existed carry no "precision": they are float32
    assert f32.meta["settings"].get("precision", "float32") == "float32"
    assert f64.meta["settings"]["precision"] == "float64"
    s32 = flux_separatrix(f32).y_far_over_h
    s64 = flux_separatrix(f64).y_far_over_h
    assert abs(s32 - s64) < 1e-3, (s32, s64)
    num = np.sqrt(np.sum((f32.ux - f64.ux) ** 2 + (f32.uy - f64.uy) ** 2))
    rel = num / np.sqrt(np.sum(f64.ux**2 + f64.uy**2))
    assert rel < 1e-4, rel
    p32, p64 = np.array(peak_speeds(f32)), np.array(peak_speeds(f64))
    assert np.abs(p32 - p64).max() < 1e-4, (p32, p64)


def test_mass_conserved_in_both_precisions(pillar_pair):
    # Total fluid mass Σ ρ over the whole time loop of the pillar channel:
    # relative change below 1e-8 in either precision (the staircase wall
    # conserves it exactly, interpolated bounce-back leaks a little; measured
    # 7.5e-12 float32 and 0 float64 with the staircase wall, 4e-11 and 4e-12
    # with the interpolated one on a smaller channel).
    for field in pillar_pair:
        change = field.meta["report"]["mass_change"]
        assert abs(change) < 1e-8, (field.meta["settings"].get("precision"), change)
