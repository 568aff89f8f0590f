"""Measured-data schema: messages name the column and the rows; nothing is dropped."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from fibersweep.discrepancy.measured import load_measured
from fibersweep.discrepancy.schema import validate_measured, write_table
from fibersweep.errors import InputError
from fibersweep.units import Geometry


def _table(n: int = 6) -> pd.DataFrame:
    rng = np.random.default_rng(0)
    cls = ["Below", "Above", "Pole-vaulting", "Trapping", "Above", "Below"][:n]
    contact = [False, True, True, True, False, True][:n]
    return pd.DataFrame(
        {
            "theta0": rng.uniform(-10, 10, n),
            "y0": rng.uniform(0, 1, n),
            "length": rng.uniform(0.5, 1.4, n),
            "class": cls,
            "delta": [0.01, 0.2, 0.3, np.nan, 0.0, -0.05][:n],
            "contact": contact,
            "theta_c": [np.nan, 10.0, -20.0, 5.0, np.nan, 30.0][:n],
            "y_c": [np.nan, 0.5, 0.2, 0.3, np.nan, 0.1][:n],
            "t_pass": [1.2, 1.3, 1.6, np.nan, 1.2, 1.4][:n],
            "t_contact": [np.nan, 1.1, 1.2, 1.0, np.nan, 1.3][:n],
        }
    )


def test_valid_table_round_trips_parquet_and_csv(tmp_path):
    df = _table()
    for suffix in (".parquet", ".csv"):
        p = write_table(df, tmp_path / f"m{suffix}")
        m = load_measured(p)
        assert len(m) == len(df)  # nothing dropped
        assert m.observed == ("class", "delta", "contact", "theta_c", "y_c", "t_pass", "dwell")
        np.testing.assert_allclose(m.table["dwell"], df["t_pass"] - df["t_contact"])
        assert m.table["contact"].dtype == bool
        np.testing.assert_allclose(m.starts, df[["theta0", "y0", "length"]].to_numpy())


def test_missing_column_is_named():
    with pytest.raises(InputError, match="missing required column.*y0"):
        validate_measured(_table().drop(columns=["y0"]))


def test_radians_are_caught_and_angle_unit_converts():
    df = _table()
    df["theta0"] = np.radians(df["theta0"])
    with pytest.raises(InputError, match="look like radians"):
        validate_measured(df)
    df["theta_c"] = np.radians(df["theta_c"])
    df["angle_unit"] = "rad"
    m = validate_measured(df)
    np.testing.assert_allclose(m.table["theta0"], np.degrees(df["theta0"]))
    np.testing.assert_allclose(m.table["theta_c"], np.degrees(df["theta_c"]))


def test_out_of_range_and_non_finite_name_rows():
    df = _table()
    df.loc[2, "y0"] = 30.0  # µm instead of h_obs (messages count data rows from 1)
    df.loc[4, "length"] = np.inf
    with pytest.raises(InputError) as exc:
        validate_measured(df)
    msg = str(exc.value)
    assert "y0: out of range" in msg and "row 3" in msg and "h_obs" in msg
    assert "length: infinite value in row 5" in msg


def test_nan_only_where_undefined():
    df = _table()
    df.loc[0, "delta"] = np.nan  # a Below fiber must have delta
    df.loc[1, "theta_c"] = np.nan  # contact without contact angle
    df.loc[0, "theta_c"] = 3.0  # contact angle without contact
    with pytest.raises(InputError) as exc:
        validate_measured(df)
    msg = str(exc.value)
    assert "delta: missing/NaN value in row 1" in msg
    assert "theta_c: missing/NaN value in row 2" in msg
    assert "theta_c: given for a fiber without contact in row 1" in msg


def test_bad_class_and_inconsistent_contact():
    df = _table()
    df.loc[1, "class"] = "sideways"
    df.loc[2, "contact"] = False  # Pole-vaulting requires contact
    df.loc[2, ["theta_c", "y_c"]] = np.nan
    with pytest.raises(InputError) as exc:
        validate_measured(df)
    msg = str(exc.value)
    assert "class: unknown value in row 2" in msg and "Pole-vaulting" in msg
    assert "contact: false for a Trapping or Pole-vaulting fiber in row 3" in msg


def test_class_names_are_case_insensitive_and_optional_columns_optional():
    df = _table()[["theta0", "y0", "length", "class"]].copy()
    df["class"] = df["class"].str.upper()
    m = validate_measured(df)
    assert m.observed == ("class",)
    assert m.table["class"].iloc[2] == "Pole-vaulting"


def test_misspelled_columns_are_errors_with_did_you_mean():
    df = _table().rename(columns={"delta": "Delta", "theta_c": "thetac"})
    with pytest.raises(InputError) as exc:
        validate_measured(df, source="m.csv")
    msg = str(exc.value)
    assert "Delta: unknown column; did you mean 'delta'?" in msg
    assert "thetac: unknown column; did you mean 'theta_c'?" in msg
    assert "--ignore-extra-columns" in msg
    # asked to, the same table loads without them (and says which observables it has)
    m = validate_measured(df.drop(columns=["y_c"]), ignore_extra=True)
    assert "delta" not in m.observed and "theta_c" not in m.observed
    assert len(m) == len(df)


def test_contact_angles_in_radians_are_caught_alone():
    df = _table()
    df["theta_c"] = np.radians(df["theta_c"])  # theta0 stays in degrees
    with pytest.raises(InputError, match=r"theta_c: all 4 contact angles lie within ±π"):
        validate_measured(df)
    df["angle_unit"] = "deg"  # the user states degrees: no guess
    assert "theta_c" in validate_measured(df).observed


def test_trajectory_angles_in_radians_are_caught(tmp_path):
    df = _table()
    p = write_table(df, tmp_path / "m.csv")
    t = np.linspace(0.0, 1.0, 5)
    rows = [
        # across the default pillar (x 1156.7 .. 1243.3 µm) in the channel frame
        {
            "fiber_id": str(i),
            "t": tk,
            "x": 1000.0 + 500.0 * tk,
            "y": 400.0,
            "theta": df["theta0"][i],
        }
        for i in range(len(df))
        for tk in t
    ]
    ok = pd.DataFrame(rows)
    write_table(ok, tmp_path / "t.csv")
    geo = Geometry()
    assert load_measured(p, tmp_path / "t.csv", geometry=geo).trajectories is not None
    rad = ok.assign(theta=np.radians(ok["theta"]))
    write_table(rad, tmp_path / "t_rad.csv")
    with pytest.raises(InputError, match="trajectories.theta: the first sample .* radians"):
        load_measured(p, tmp_path / "t_rad.csv", geometry=geo)


def test_rows_in_messages_count_data_rows_from_one_as_in_the_csv(tmp_path):
    """The first data row of a CSV (the line after the header) is 'row 1'."""
    df = _table()
    df.loc[0, "y0"] = 30.0
    path = tmp_path / "measured.csv"
    df.to_csv(path, index=False)
    with pytest.raises(InputError) as exc:
        load_measured(path)
    msg = str(exc.value)
    assert "y0: out of range" in msg and "in row 1 " in msg, msg
    assert path.read_text().splitlines()[1].split(",")[1] == "30.0"  # line 2: data row 1
