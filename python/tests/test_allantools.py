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


# The total family, Theo1 and the time-interval errors (issue 45). allantools computes the total
# estimators and Theo1 by Python loops, O(N m) per tau: the records compared with it are short
# (a 6 s slice of the real log, and synthetic series of 600 points), long enough for every grid's
# factors to reach the estimators' top (N/3 for the totals, N - 1 for Theo1).
TOTAL_FUNCTIONS = ["mtotdev", "ttotdev", "htotdev", "theo1"]
TIME_ERROR_FUNCTIONS = ["mtie", "tierms"]
SHORT_TAUS = np.array([0.01, 0.02, 0.03, 0.04, 0.1, 0.5, 1.0, 3.0, 4.0, 1e7])


@pytest.mark.parametrize("taus", ["octave", "decade", SHORT_TAUS])
def test_adis16405_gz_total_family(adis_gz, taus):
    compare(adis_gz[:600], RATE_HZ, "freq", taus, TOTAL_FUNCTIONS)


@pytest.mark.parametrize("taus", ["octave", "decade", EXPLICIT_TAUS])
def test_adis16405_gz_time_errors(adis_gz, taus):
    # MTIE in allantools takes the maximum over an (N - m) x (m + 1) window view: O(N m) per
    # tau, so a 200 s slice; TIE rms is O(N) per tau: the whole log.
    compare(adis_gz[:20_000], RATE_HZ, "freq", taus, ["mtie"])
    compare(adis_gz, RATE_HZ, "freq", taus, ["tierms"])


@pytest.mark.parametrize("data_type", ["freq", "phase"])
@pytest.mark.parametrize("taus", ["octave", "decade", SHORT_TAUS, "all"])
def test_synthetic_total_family(data_type, taus):
    n = 150 if isinstance(taus, str) and taus == "all" else 600
    data = synthetic(n)
    if data_type == "phase":
        data = np.cumsum(data) / RATE_HZ
    compare(data, RATE_HZ, data_type, taus, TOTAL_FUNCTIONS + TIME_ERROR_FUNCTIONS)


def test_theo1_reports_allantools_taus_and_error_bars():
    # allantools: taus m / rate (not 0.75 m / rate), even m only, ns = (N - m) m / 2 and
    # errs = devs / sqrt(N - m) with N phase points.
    data = synthetic(501)
    taus, devs, errs, ns = ia.theo1(data, 1.0, "phase", "all")
    m = np.arange(2, 501, 2)
    np.testing.assert_array_equal(taus, m)
    np.testing.assert_array_equal(ns, (501 - m) * m // 2)
    np.testing.assert_allclose(errs, devs / np.sqrt(501 - m), rtol=1e-15)


def gap_series(n, seed=3):
    """Phase (integrated synthetic rate) with 2 % of its points missing (NaN) in runs."""
    x = np.cumsum(synthetic(n, seed)) / RATE_HZ
    rng = np.random.default_rng(seed)
    for start in rng.integers(0, n - 20, n // 500):
        x[start:start + 10] = np.nan
    return x


def intended_bounds(devs, ns_present, ms, ci, alpha):
    """The interval allantools' gradev means to return (its call swaps the arguments of
    ``ci.confidence_interval``, giving NaN): SP 1065 eq (45) with Table 5's EDF."""
    from allantools import ci as at_ci
    lo, hi = [], []
    for d, m in zip(devs, ms):
        edf = at_ci.edf_simple(ns_present, m, alpha)
        a, b = at_ci.confidence_interval(d, edf, ci)
        lo.append(a)
        hi.append(b)
    return np.array(lo), np.array(hi)


@pytest.mark.parametrize("noisetype,alpha", [("wp", 2), ("wf", 0), ("fp", 1), ("ff", -1),
                                             ("rf", -2)])
@pytest.mark.parametrize("taus", ["octave", "decade", EXPLICIT_TAUS])
def test_gradev_with_gaps(noisetype, alpha, taus):
    x = gap_series(20_000)
    ours = ia.gradev(x, RATE_HZ, "phase", taus, ci=0.9, noisetype=noisetype)
    ref = allantools.gradev(x, RATE_HZ, "phase", taus, ci=0.9, noisetype=noisetype)
    taus_o, devs_o, (lo_o, hi_o), ns_o = ours
    taus_r, devs_r, _, ns_r = ref
    assert len(taus_o) == len(taus_r) > 0
    np.testing.assert_array_equal(ns_o, ns_r)
    np.testing.assert_allclose(taus_o, taus_r, rtol=1e-15, atol=0)
    np.testing.assert_allclose(devs_o, devs_r, rtol=REL_TOL, atol=0)
    lo, hi = intended_bounds(devs_r, int(np.sum(~np.isnan(x))), np.round(taus_r * RATE_HZ),
                             0.9, alpha)
    # Our chi-squared quantiles agree with scipy's to 1e-10 (crates/allan chi2 tests).
    np.testing.assert_allclose(lo_o, lo, rtol=REL_TOL)
    np.testing.assert_allclose(hi_o, hi, rtol=REL_TOL)
    assert np.all(lo_o < devs_o) and np.all(devs_o < hi_o)


def test_gradev_without_gaps_is_oadev():
    # No gap: every term is present, the sums are the overlapping Allan deviation's.
    data = synthetic(5000)
    t, d, _, n = ia.gradev(data, RATE_HZ, "freq", "octave")
    t2, d2, _, n2 = ia.oadev(data, RATE_HZ, "freq", "octave")
    np.testing.assert_array_equal(n, n2)
    np.testing.assert_allclose(d, d2, rtol=REL_TOL)


def test_gradev_frequency_input_follows_allantools():
    # Frequency with gaps at both ends (dropped) and one inside (every later phase point a gap).
    y = synthetic(3000)
    y[:5] = np.nan
    y[-7:] = np.nan
    y[2000] = np.nan
    ours = ia.gradev(y, RATE_HZ, "freq", "octave")
    ref = allantools.gradev(y, RATE_HZ, "freq", "octave")
    np.testing.assert_array_equal(ours[3], ref[3])
    np.testing.assert_allclose(ours[1], ref[1], rtol=REL_TOL)


NEW_FUNCTIONS = TOTAL_FUNCTIONS + TIME_ERROR_FUNCTIONS + ["gradev"]


@pytest.mark.parametrize("name", NEW_FUNCTIONS)
@pytest.mark.parametrize("bad,message", BAD)
def test_new_functions_refuse_bad_input(name, bad, message):
    args = dict(data=synthetic(100), rate=1.0, data_type="freq", taus=None)
    args.update(bad)
    if name == "gradev" and message.startswith("data\\[1\\] is NaN"):
        # A NaN is a gap for gradev: all gaps leaves no sample.
        args["data"] = [float("nan")] * 5
        message = "0 samples: at least 2"
    with pytest.raises(imudrift.InvalidInput, match=message) as e:
        getattr(ia, name)(**args)
    assert isinstance(e.value, ValueError)


def test_gradev_refuses_a_bad_level():
    with pytest.raises(imudrift.InvalidInput, match="confidence|ci"):
        ia.gradev(synthetic(100), 1.0, "phase", ci=1.5)
