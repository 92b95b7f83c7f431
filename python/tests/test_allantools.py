"""imudrift.allantools against allantools itself: same taus, deviations, error bars and counts.

Reason for the 1e-9 relative tolerance: both compute the same sums from the same samples;
they differ only in rounding (allantools integrates frequency with a plain cumulative sum,
imudrift with a compensated one, and orders its additions differently), which stays below
1e-10 relative on these records.
"""

import numpy as np
import pytest

allantools = pytest.importorskip("allantools")
import imudrift  # noqa: E402
import imudrift.allantools as ia  # noqa: E402

from conftest import synthetic  # noqa: E402

REL_TOL = 1e-9
FUNCTIONS = ["adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "totdev"]
RATE_HZ = 100.0
# Averaging times in seconds, including some that round to the same m, one below tau0 (dropped)
# and one beyond the record (dropped), as allantools' tau_generator does.
EXPLICIT_TAUS = np.array([0.004, 0.01, 0.02, 0.021, 0.5, 1.0, 3.33, 60.0, 600.0, 1e7])


def assert_same(ours, ref, what):
    taus, devs, errs, ns = ours
    rtaus, rdevs, rerrs, rns = ref
    assert len(taus) == len(rtaus) > 0, f"{what}: {len(taus)} vs {len(rtaus)} taus"
    np.testing.assert_array_equal(ns, rns, err_msg=what)
    np.testing.assert_allclose(taus, rtaus, rtol=1e-15, atol=0, err_msg=what)
    np.testing.assert_allclose(devs, rdevs, rtol=REL_TOL, atol=0, err_msg=what)
    np.testing.assert_allclose(errs, rerrs, rtol=REL_TOL, atol=0, err_msg=what)


def compare(data, rate, data_type, taus, functions=FUNCTIONS):
    for name in functions:
        ours = getattr(ia, name)(data, rate=rate, data_type=data_type, taus=taus)
        ref = getattr(allantools, name)(data, rate=rate, data_type=data_type, taus=taus)
        assert_same(ours, ref, f"{name} {data_type} taus={taus!r}")


@pytest.mark.parametrize("taus", ["octave", "decade", None, EXPLICIT_TAUS, list(EXPLICIT_TAUS)])
def test_adis16405_gz(adis_gz, taus):
    compare(adis_gz, RATE_HZ, "freq", taus)


def test_adis16405_gz_all_taus_short(adis_gz):
    compare(adis_gz[:1500], RATE_HZ, "freq", "all")


@pytest.mark.parametrize("data_type", ["freq", "phase"])
@pytest.mark.parametrize("taus", ["all", "octave", "decade", EXPLICIT_TAUS])
def test_synthetic(data_type, taus):
    n = 1000 if isinstance(taus, str) and taus == "all" else 200_000
    data = synthetic(n)
    if data_type == "phase":
        data = np.cumsum(data) / RATE_HZ
    compare(data, RATE_HZ, data_type, taus)


@pytest.mark.slow
def test_synthetic_4_32_m_samples():
    compare(synthetic(4_320_000), RATE_HZ, "freq", "octave")


def test_totdev_is_allantools_not_stable32():
    # allantools: n = N - 2 at every tau and taus up to N - 1 phase points; Stable32 stops at N/2.
    taus, devs, errs, ns = ia.totdev(synthetic(100), 1.0, "freq", "all")
    assert taus[-1] == 100.0 and np.all(ns == 99)


BAD = [
    (dict(data=[]), "empty"),
    (dict(data=[1.0, float("nan"), 2.0]), "data\\[1\\] is NaN"),
    (dict(data=[1.0, 2.0, float("inf")]), "data\\[2\\] is inf"),
    (dict(data=np.ones((3, 4))), "1-D"),
    (dict(data=["a", "b"]), "array of numbers"),
    (dict(rate=0.0), "rate 0"),
    (dict(rate=-100.0), "rate -100"),
    (dict(rate=float("nan")), "rate NaN"),
    (dict(data_type="frequency"), "unknown data_type"),
    (dict(taus="weekly"), "taus \"weekly\""),
    (dict(taus=[1e9]), "no averaging time"),
]


@pytest.mark.parametrize("name", FUNCTIONS)
@pytest.mark.parametrize("bad,message", BAD)
def test_bad_input_raises_value_error(name, bad, message):
    args = dict(data=synthetic(100), rate=1.0, data_type="freq", taus=None)
    args.update(bad)
    with pytest.raises(imudrift.InvalidInput, match=message) as e:
        getattr(ia, name)(**args)
    assert isinstance(e.value, ValueError)
