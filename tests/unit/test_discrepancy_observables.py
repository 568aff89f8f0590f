"""Contract of the observable registry: every observable goes through schema, synth and scores.

Parametrised over :data:`OBSERVABLES`, so a new registry entry is tested by
these tests without a new test.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from fibersweep.discrepancy import observables as obs_mod
from fibersweep.discrepancy.copies import NoiseModel
from fibersweep.discrepancy.gap import describe, value_matrices
from fibersweep.discrepancy.measured import load_measured
from fibersweep.discrepancy.observables import (
    OBSERVABLES,
    NoiseLaw,
    Observable,
    noise_draws,
    of_geometry,
    scored,
    stream_key,
    table_columns,
)
from fibersweep.discrepancy.schema import validate_measured, write_table
from fibersweep.discrepancy.scores import residual_matrix, score_matrix
from fibersweep.discrepancy.simulate import _failed, outcome_row
from fibersweep.discrepancy.synth import measured_table
from fibersweep.errors import InputError
from fibersweep.fiber.result import FiberStart, RunResult

NAMES = list(of_geometry("channel"))


@pytest.fixture()
def registry():
    """The registry's dict, restored afterwards in its order (monkeypatch would reorder it)."""
    saved = dict(obs_mod._REGISTRY)
    yield obs_mod._REGISTRY
    obs_mod._REGISTRY.clear()
    obs_mod._REGISTRY.update(saved)


def _runs(shift: float = 0.0) -> list[RunResult]:
    """Eight plausible runs covering every class, with and without contact."""
    start = FiberStart(0.0, 0.3, 1.0)
    base = [
        dict(cls="Below", delta=-0.1, contact=False, t_pass=1.2),
        dict(
            cls="Above", delta=0.2, contact=True, theta_c=12.0, y_c=0.6, t_contact=0.9, t_pass=1.4
        ),
        dict(
            cls="Pole-vaulting",
            delta=0.4,
            contact=True,
            theta_c=-35.0,
            y_c=0.2,
            t_contact=1.0,
            t_pass=1.9,
        ),
        dict(cls="Trapping", contact=True, theta_c=48.0, y_c=0.4, t_contact=1.1),
    ]
    out = []
    for k in range(8):
        d = dict(base[k % 4])
        for key in ("delta", "theta_c", "y_c"):
            if key in d:
                d[key] += shift + 0.01 * k
        for key in ("t_pass", "t_contact"):
            if key in d:
                d[key] *= 1.0 + shift + 0.01 * k
        out.append(RunResult(start=start, status="ok", theta_f=3.0 + k, **d))
    return out


def _outcomes(shift: float = 0.0) -> pd.DataFrame:
    return pd.DataFrame([outcome_row(r) for r in _runs(shift)])


def _measured(n_seed: int = 1) -> tuple[pd.DataFrame, np.ndarray]:
    """A full measured table written the way ``synth`` writes it."""
    out = _outcomes()
    starts = np.column_stack([np.linspace(-8, 8, 8), np.linspace(0.1, 0.6, 8), np.ones(8)])
    obs = NoiseModel().observe(out, noise_draws([n_seed, 2], len(out)))
    return measured_table(obs, starts), starts


def _needed(o: Observable) -> list[str]:
    """Table columns a table with only observable ``o`` needs (its sources, the NaN rule's)."""
    cols = list(o.derived_from) or [o.name]
    if "contact" in o.defined:
        cols.append("contact")
    return cols


@pytest.mark.parametrize("name", NAMES)
def test_entry_is_consistent(name):
    o = OBSERVABLES[name]
    assert o.kind in ("class", "binary", "continuous")
    assert bool(o.categories) == o.categorical
    assert o.noise is None or o.kind == "continuous"  # categories are observed without error
    assert (o.derive is None) == (o.underive is None) == (not o.derived_from)
    if not o.derived_from and o.kind == "continuous":
        assert o.bounds is not None and o.unit_hint and o.unit  # what schema messages need


@pytest.mark.parametrize("name", [n for n in NAMES if not OBSERVABLES[n].track])
def test_observable_round_trips_schema_synth_and_scores(name, tmp_path):
    # (the track observables' round trip: tests/unit/test_discrepancy_tracks.py)
    o = OBSERVABLES[name]
    table, _ = _measured()
    cols = ["fiber_id", "theta0", "y0", "length", "class", *_needed(o)]
    sub = table[list(dict.fromkeys(cols))]
    m = validate_measured(sub, source="contract")
    assert len(m) == 8
    assert (name in m.observed) == o.scored
    p = write_table(sub, tmp_path / "m.csv")  # and through a file
    assert load_measured(p).observed == m.observed
    if not o.scored:
        return
    copies = [_outcomes(shift) for shift in (0.0, 0.01, -0.02, 0.03)]
    V = value_matrices(m.table, copies, [name])[name]
    assert V.shape == (8, 5)
    # defined exactly where the registry says, the same in the observed column and the copies
    trapped = (m.table["class"] == "Trapping").to_numpy()
    contact = m.table["contact"].to_numpy() if "contact" in m.table else None
    defined = o.defined_mask(trapped, contact)
    assert np.array_equal(np.isfinite(V[:, 0]), defined)
    assert np.array_equal(np.isfinite(V[:, 1:]), np.repeat(defined[:, None], 4, axis=1))
    S = score_matrix(name, V)
    assert np.isfinite(S[defined]).all() and np.isnan(S[~defined]).all()
    R = residual_matrix(name, V)
    assert R.shape == (8, 5, o.width)
    assert np.isfinite(R[defined]).all()
    assert describe({name: V})  # a descriptive measure for the report


@pytest.mark.parametrize("name", [n for n in table_columns() if OBSERVABLES[n].bounds])
def test_range_check_names_the_observable_and_its_unit(name):
    o = OBSERVABLES[name]
    table, _ = _measured()
    defined = np.isfinite(table[name].to_numpy())
    row = int(np.flatnonzero(defined)[0])
    table.loc[row, name] = o.bounds[1] * 10 + 1.0
    with pytest.raises(InputError) as exc:
        validate_measured(table)
    msg = str(exc.value)
    assert f"{name}: out of range" in msg and f"row {row + 1}" in msg and o.unit_hint in msg


@pytest.mark.parametrize("name", [n for n in table_columns() if OBSERVABLES[n].defined])
def test_nan_rule(name):
    o = OBSERVABLES[name]
    table, _ = _measured()
    v = table[name].to_numpy(dtype=np.float64)
    where = int(np.flatnonzero(np.isfinite(v))[0])
    bad = table.copy()
    bad.loc[where, name] = np.nan  # missing where the quantity exists
    with pytest.raises(InputError, match=rf"{name}: missing/NaN value in row {where + 1}"):
        validate_measured(bad)
    if o.strict:
        undefined = int(np.flatnonzero(~np.isfinite(v))[0])
        bad = table.copy()
        bad.loc[undefined, name] = float(np.nanmedian(v))  # given where it does not exist
        with pytest.raises(InputError, match=rf"{name}: given for .* in row {undefined + 1}"):
            validate_measured(bad)


def test_outcome_rows_follow_the_registry():
    row = outcome_row(_runs()[1])
    assert list(row)[: len(NAMES)] == NAMES and row["status"] == "ok"
    assert row["class"] == "Above" and row["contact"] == 1.0
    assert row["dwell"] == pytest.approx(1.4 * 1.01 - 0.9 * 1.01)
    failed = outcome_row(RunResult(start=FiberStart(0, 0, 1), status="failed", reason="nan"))
    assert failed == _failed("nan")
    assert failed["class"] is None and all(
        math.isnan(failed[n]) for n in NAMES if OBSERVABLES[n].kind != "class"
    )


def test_noise_laws_by_hand():
    out = _outcomes()
    z = {n: np.full(8, 2.0) for n in noise_draws([0], 8)}
    nm = NoiseModel(outcome={"delta": 0.05})
    noisy = nm.observe(out, z)
    np.testing.assert_allclose(noisy["delta"], out["delta"] + 0.1)  # additive, 2 sd
    np.testing.assert_allclose(noisy["t_pass"], out["t_pass"] * math.exp(0.02))  # log-normal
    np.testing.assert_allclose(noisy["dwell"], np.abs(out["dwell"] + 0.02))  # reflected
    assert noisy["class"].equals(out["class"]) and noisy["contact"].equals(out["contact"])
    assert nm.as_dict()["delta"] == 0.05 and nm.as_dict()["theta_c"] == 1.0
    with pytest.raises(InputError, match="no measurement noise law for class"):
        NoiseModel(outcome={"class": 0.1})


def test_noise_streams_are_keyed_by_name(registry):
    full = noise_draws([5, 7919, 3], 16)
    assert set(full) == {n for n, o in OBSERVABLES.items() if o.noise is not None}
    for name, z in full.items():
        expect = np.random.default_rng([5, 7919, 3, stream_key(name)]).standard_normal(16)
        np.testing.assert_array_equal(z, expect)
    # removing (or adding, or reordering) an observable leaves the others' draws unchanged
    del registry["delta"]
    fewer = noise_draws([5, 7919, 3], 16)
    assert "delta" not in fewer
    for name, z in fewer.items():
        np.testing.assert_array_equal(z, full[name])


def test_synth_writes_measured_dwell_back_into_t_contact():
    table, _ = _measured()
    m = validate_measured(table)
    out = _outcomes()
    obs = NoiseModel().observe(out, noise_draws([1, 2], 8))
    ok = np.isfinite(obs["dwell"].to_numpy())
    # the dwell the schema reads back is the measured-like dwell synth drew (to rounding)
    np.testing.assert_allclose(m.table["dwell"][ok], obs["dwell"][ok], rtol=0, atol=1e-12)
    trapped_contact = (out["class"] == "Trapping").to_numpy()
    np.testing.assert_array_equal(
        m.table["t_contact"][trapped_contact], out["t_contact"][trapped_contact]
    )


def test_a_new_observable_is_one_registry_entry(registry):
    """Adding an entry is all it takes: schema, outcome rows, synth, noise, scores, report."""
    new = Observable(
        "theta_f",
        "continuous",
        "deg",
        "final fiber angle",
        extract=lambda r: r.theta_f,
        noise=NoiseLaw("additive", 0.5),
        bounds=(-180.0, 180.0),
        unit_hint="theta_f must be in degrees",
    )
    registry["theta_f"] = new
    assert "theta_f" in scored() and "theta_f" in table_columns()
    table, _ = _measured()
    assert "theta_f" in table.columns  # synth writes it (noisy)
    assert not np.allclose(table["theta_f"], 3.0 + np.arange(8))
    m = validate_measured(table)
    assert m.observed[-1] == "theta_f"
    V = value_matrices(m.table, [_outcomes(), _outcomes(0.01)], m.observed)["theta_f"]
    assert np.isfinite(score_matrix("theta_f", V)).all()
    assert "theta_f_residual" in describe({"theta_f": V})
    table.loc[3, "theta_f"] = 400.0
    with pytest.raises(InputError, match="theta_f: out of range .* degrees"):
        validate_measured(table)


def test_registry_order_is_the_report_order():
    assert NAMES == [
        "class", "delta", "contact", "theta_c", "y_c", "t_pass", "t_contact", "dwell",
        "y_out", "theta_out", "t_transit",
    ]  # fmt: skip


def test_synth_drops_runs_missing_a_quantity_where_it_must_exist():
    from fibersweep.discrepancy.synth import _missing

    table, _ = _measured()
    assert (_missing(table) == "").all()
    table.loc[0, "t_pass"] = np.nan  # a Below fiber that never passed within the run
    table.loc[1, "theta_c"] = np.nan  # contact without a contact angle
    missing = _missing(table)
    assert missing[0] == OBSERVABLES["t_pass"].description
    assert missing[1] == OBSERVABLES["theta_c"].description
    assert (missing[2:] == "").all()
