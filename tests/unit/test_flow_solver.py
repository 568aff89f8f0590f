"""Solver orchestration: τ choice, nested grids, Hele-Shaw start, thread choice."""

from __future__ import annotations

import numpy as np
import pytest

import fibersweep.flow.lbm as lbm
from fibersweep.config.flow import FlowSettings, GeometrySettings
from fibersweep.flow.initial import hele_shaw_pressure
from fibersweep.flow.lattice import make_grid
from fibersweep.units import Geometry

TINY = FlowSettings(
    geometry=GeometrySettings(width=40.0, depth=32.0, length=48.0, pillar_height=12.0),
    dx=4.0,
    tolerance=1e-5,
)


def test_choose_tau_is_critical_damping_for_the_spec_channel():
    # ν = (2 c_s k_min) H² / 12 with k_min = 2π / max(L, 2W): 0.80 at dx = 4 µm, 1.10 at 2.
    assert lbm.choose_tau(make_grid(Geometry(), 4.0, True)) == pytest.approx(0.802, abs=1e-3)
    assert lbm.choose_tau(make_grid(Geometry(), 2.0, True)) == pytest.approx(1.105, abs=1e-3)


def test_coarser_settings_only_when_valid():
    assert lbm.coarser_settings(FlowSettings(dx=2.0)).dx == 4.0
    assert lbm.coarser_settings(FlowSettings(dx=4.0)) is None  # 5 nodes < 8 across the depth


def test_hele_shaw_start_is_exact_without_pillar_and_conserves_flux_with_it():
    solid = np.zeros((30, 12), dtype=bool)
    p, v = hele_shaw_pressure(solid, 1e-6)
    assert np.abs(p).max() < 1e-18 and np.allclose(v[0], 1e-6) and np.abs(v[1]).max() < 1e-18
    grid = make_grid(Geometry(), 4.0, True)
    p, v = hele_shaw_pressure(grid.solid, 1.0)
    flux = v[0].sum(axis=1)  # through every x column (node-averaged face fluxes)
    assert np.ptp(flux) / flux.mean() < 1e-9
    assert np.all(v[:, grid.solid] == 0)
    # the pillar blocks: the far field is slowed a little, the gaps are faster
    assert 0.98 < v[0][0, 100] < 1.0 and v[0][300].max() > 1.3


def test_explicit_thread_count_is_used():
    sol = lbm.solve_lattice(TINY, threads=1)
    assert sol.report.threads == 1 and sol.report.converged


def test_thread_count_is_chosen_by_timing(monkeypatch):
    # force the adaptive path on a tiny grid: both counts are timed, one is kept
    monkeypatch.setattr(lbm, "SERIAL_BELOW_CELLS", 0)
    monkeypatch.setattr(lbm, "REPROBE_EVERY", 2)
    n = lbm.numba.get_num_threads()
    sol = lbm.solve_lattice(TINY.model_copy(update={"check_every": 20}))
    assert sol.report.threads in {1, n}
    assert lbm.numba.get_num_threads() == n  # restored
