"""Shared data of the Python tests: the ADIS16405 run 1 z gyro from $IMUDRIFT_DATA (tests that
need it are skipped without it) and a synthetic white + random-walk channel."""

import gzip
import os

import numpy as np
import pytest


def read_column(path, name):
    """One named column of a comma-separated log whose comment lines start with '#'."""
    with gzip.open(path, "rt") if path.endswith(".gz") else open(path) as f:
        for line in f:
            if not line.startswith("#"):
                header = line.strip().split(",")
                break
        col = header.index(name)
        return np.loadtxt(f, delimiter=",", comments="#", usecols=col, dtype=np.float64)


@pytest.fixture(scope="session")
def adis_gz():
    """ADIS16405 static run 1, gyro z in deg/s at 100 Hz (1,000,000 samples)."""
    root = os.environ.get("IMUDRIFT_DATA")
    if not root:
        pytest.skip("IMUDRIFT_DATA is not set: the ADIS16405 log is not available")
    path = os.path.join(root, "adis16405_imudata", "adis16405_imu1.csv.gz")
    if not os.path.exists(path):
        pytest.skip(f"{path} not found")
    return read_column(path, "gyro_z_dps")


def synthetic(n, seed=20261126):
    """White noise (sigma 1) plus a random walk (step 1e-3 per sample), a fixed numpy seed."""
    rng = np.random.default_rng(seed)
    return rng.normal(0.0, 1.0, n) + np.cumsum(rng.normal(0.0, 1e-3, n))


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: a test on the 4.32 M-sample record (about 20 s)")
