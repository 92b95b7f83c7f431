"""imudrift.read_log: the CLI's log reader (crate logio) into a pandas DataFrame."""

import math

import numpy as np
import pytest

import imudrift

pd = pytest.importorskip("pandas")


def test_adis16405_in_si(adis_gz):
    import os

    path = os.path.join(os.environ["IMUDRIFT_DATA"], "adis16405_imudata", "adis16405_imu1.csv.gz")
    df = imudrift.read_log(path, rate=100)
    assert list(df.columns) == ["gx", "gy", "gz", "ax", "ay", "az"]
    assert df.attrs["rate_hz"] == 100.0 and len(df) == len(adis_gz)
    # deg/s to rad/s, the unit stated by the column name (gyro_z_dps). Reason for 1e-15: one
    # multiplication by pi/180, rounded once on each side.
    np.testing.assert_allclose(df["gz"].to_numpy(), adis_gz * math.pi / 180, rtol=1e-15, atol=0)


def test_time_column_units_and_mapping(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text("# a comment\ntime_ms,w_z,acc_x_g\n0,0.5,1\n10,0.25,1\n20,0.5,1\n30,0.125,1\n")
    df = imudrift.read_log(path, time_unit="ms", gyro_unit="deg/s", columns={"gz": "w_z"})
    assert list(df.columns) == ["t", "gz", "ax"]
    assert df.attrs["rate_hz"] == pytest.approx(100.0)
    np.testing.assert_allclose(df["t"], [0.0, 0.01, 0.02, 0.03])
    np.testing.assert_allclose(df["gz"], np.array([0.5, 0.25, 0.5, 0.125]) * math.pi / 180, rtol=1e-15)
    np.testing.assert_allclose(df["ax"], 9.80665)


def test_errors(tmp_path):
    with pytest.raises(imudrift.LogUnreadable, match="cannot read") as e:
        imudrift.read_log(tmp_path / "missing.csv", rate=100)
    assert isinstance(e.value, OSError)
    path = tmp_path / "log.csv"
    path.write_text("gx,gy\n0.1,0.2\n0.2,0.1\n")
    with pytest.raises(imudrift.InvalidInput, match="rate"):
        imudrift.read_log(path)  # no time column and no rate
    with pytest.raises(imudrift.InvalidInput, match="rate"):
        imudrift.read_log(path, rate=-5)
    with pytest.raises(imudrift.InvalidInput, match="gyro_unit \"rpm\""):
        imudrift.read_log(path, rate=100, gyro_unit="rpm")
