"""imudrift.allan: the analysis of `imudrift allan` for one channel, with intervals and the fit."""

import json
import os
import shutil
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import imudrift
import imudrift.allantools as ia

from conftest import synthetic

RATE_HZ = 100.0
SIGMA = 0.01  # rad/s, white rate noise of the synthetic gyro
# Reason for 1e-9: the same sums as allantools', differing only in rounding (test_allantools.py).
REL_TOL = 1e-9


@pytest.fixture(scope="module")
def white_gyro():
    return np.random.default_rng(7).normal(0.0, SIGMA, 360_000)


def test_deviations_are_allantools_up_to_the_stable32_stop(adis_gz):
    r = imudrift.allan(adis_gz, RATE_HZ)
    taus, devs, _, ns = pytest.importorskip("allantools").oadev(adis_gz, RATE_HZ, "freq", "octave")
    # Stable32's stop ratio for oadev: largest m = N / 4 (crate allan, Estimator::stable32_stop_ratio).
    keep = taus * RATE_HZ <= len(adis_gz) / 4
    np.testing.assert_allclose(r.tau, taus[keep], rtol=1e-15)
    np.testing.assert_allclose(r.deviation, devs[keep], rtol=REL_TOL)
    np.testing.assert_array_equal(r.n_terms, ns[keep])


def test_intervals_bracket_the_deviation(white_gyro):
    r = imudrift.allan(white_gyro, RATE_HZ)
    lo, hi = r.interval
    assert np.all(lo < r.deviation) and np.all(r.deviation < hi)
    assert np.all(r.edf > 0)
    # White rate noise is alpha = 0 (rate PSD flat) at every tau with enough averages.
    assert np.all(r.alpha[:10] == 0)
    assert len(r) == len(r.tau) and r.m[0] == 1 and r.tau[0] == 1 / RATE_HZ


def test_fit_reads_back_white_noise(white_gyro):
    f = imudrift.allan(white_gyro, RATE_HZ).fit()
    n = f.terms["n"]
    # IEEE 952: N = sigma * sqrt(dt) for white rate noise of standard deviation sigma.
    expected = SIGMA / np.sqrt(RATE_HZ)
    # 4 standard errors: a false alarm below 1e-4 if the fit's sigma is right (fixed seed anyway).
    assert abs(n.value - expected) < 4 * n.sigma, (n, expected)
    assert n.interval[0] < n.value < n.interval[1]
    assert f.terms["r"] is None or f.terms["r"].value < 1e-6
    assert set(f.readings) >= {"arw_at_1s", "bi_min", "bi_ieee", "rrw_at_3s"}


def test_only_allan_variance_estimators_have_a_fit(white_gyro):
    with pytest.raises(ValueError, match="no IEEE 952 fit for mdev"):
        imudrift.allan(white_gyro, RATE_HZ, estimator="mdev").fit()
    assert imudrift.allan(white_gyro, RATE_HZ, estimator="totdev").fit().terms["n"] is not None


def test_to_dict_is_json_and_to_pandas(white_gyro, monkeypatch):
    r = imudrift.allan(white_gyro, RATE_HZ, taus="decade")
    d = json.loads(json.dumps(r.to_dict()))
    assert d["tau"] == r.tau.tolist() and d["estimator"] == "oadev"
    assert d["fit"]["terms"]["n"]["value"] == r.fit().terms["n"].value
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(ImportError, match="pip install pandas"):
        r.to_pandas()


def test_to_pandas(white_gyro):
    pytest.importorskip("pandas")
    df = imudrift.allan(white_gyro, RATE_HZ).to_pandas()
    assert list(df["tau"]) == list(imudrift.allan(white_gyro, RATE_HZ).tau)
    assert {"deviation", "lo", "hi", "edf", "alpha"} <= set(df.columns)


def cli_binary():
    here = os.path.dirname(os.path.abspath(__file__))
    built = os.path.join(here, "..", "..", "target", "release", "imudrift")
    return os.environ.get("IMUDRIFT_BIN") or (built if os.path.exists(built) else shutil.which("imudrift"))


def test_same_as_the_cli(tmp_path):
    exe = cli_binary()
    if exe is None:
        pytest.skip("no imudrift binary (cargo build --release, or set IMUDRIFT_BIN)")
    gx = synthetic(50_000) * 1e-3
    path = tmp_path / "log.csv"
    np.savetxt(path, gx, fmt="%.17g", header="gx", comments="")
    out = subprocess.run(
        [exe, "allan", str(path), "--rate", "100", "--json"], capture_output=True, text=True, check=True
    )
    ch = json.loads(out.stdout)["channels"]["gx"]
    r = imudrift.allan(gx, RATE_HZ)
    # Reason for 1e-12: the same code on the same samples (the CSV keeps 17 significant digits).
    for ours, cli in [(r.tau, "tau_s"), (r.deviation, "adev"), (r.lo, "adev_lo"), (r.hi, "adev_hi"), (r.edf, "edf")]:
        np.testing.assert_allclose(ours, ch[cli], rtol=1e-12, err_msg=cli)
    np.testing.assert_array_equal(r.alpha, ch["alpha"])
    for k, t in r.fit().terms.items():
        assert (t is None) == (ch["fit"][k] is None)
        if t is not None:
            assert t.value == pytest.approx(ch["fit"][k], rel=1e-9), k


def test_the_gil_is_released_while_computing():
    # While a thread is inside mdev (hundreds of ms), the main thread wakes from a 10 ms sleep:
    # it could not if the call held the GIL.
    data = synthetic(4_320_000)
    done = {}

    def work():
        ia.mdev(data, RATE_HZ, "freq", "octave")
        done["end"] = time.perf_counter()

    t = threading.Thread(target=work)
    t.start()
    time.sleep(0.01)
    woke = time.perf_counter()
    t.join()
    assert woke < done["end"]


@pytest.mark.parametrize(
    "bad,message",
    [
        (dict(confidence=1.5), "confidence 1.5"),
        (dict(edf="exact"), "edf \"exact\""),
        (dict(estimator="xdev"), "unknown estimator \"xdev\""),
        (dict(taus="weekly"), "taus \"weekly\""),
        (dict(data_type="angle"), "unknown data_type"),
        (dict(rate=0.0), "rate 0"),
        (dict(data=[]), "empty"),
    ],
)
def test_bad_input(bad, message):
    args = dict(data=synthetic(1000), rate=RATE_HZ)
    args.update(bad)
    with pytest.raises(imudrift.InvalidInput, match=message):
        imudrift.allan(**args)


def test_plot(white_gyro, monkeypatch):
    r = imudrift.allan(white_gyro, RATE_HZ)
    plt = pytest.importorskip("matplotlib.pyplot")
    ax = r.plot()
    lines = ax.get_lines()
    assert len(lines) == 2  # the curve and the fit
    np.testing.assert_array_equal(lines[0].get_xdata(), r.tau)
    # The fit's curve is the IEEE 952 model (Annex C) of the fitted terms:
    # sigma^2 = 3Q^2/tau^2 + N^2/tau + (2 ln 2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2.
    tau, fit_y = lines[1].get_xdata(), lines[1].get_ydata()
    assert tau[0] == pytest.approx(r.tau[0]) and tau[-1] == pytest.approx(r.tau[-1])
    c = {k: 0.0 if t is None else t.value**2 for k, t in r.fit().terms.items()}
    var = 3 * c["q"] / tau**2 + c["n"] / tau + 2 * np.log(2) / np.pi * c["b"] + c["k"] * tau / 3 + c["r"] * tau**2 / 2
    # Reason for 1e-12: the same closed form evaluated in another order.
    np.testing.assert_allclose(fit_y, np.sqrt(var), rtol=1e-12)
    plt.close("all")
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    monkeypatch.setitem(sys.modules, "matplotlib.pyplot", None)
    with pytest.raises(ImportError, match="pip install matplotlib"):
        r.plot()


def _allan_child(q):
    g = np.random.default_rng(2).normal(0.0, 0.01, 30_000)
    q.put(len(imudrift.allan(g, 100.0).tau))


@pytest.mark.skipif(sys.platform == "win32", reason="fork")
def test_a_forked_child_runs_allan():
    """Every call runs in a pool of its own: a child forked after the parent's parallel Allan
    work (the fit's null simulation) runs its own (it waited for ever in the process-wide pool)."""
    import multiprocessing

    imudrift.allan(np.random.default_rng(1).normal(0.0, 0.01, 20_000), 100.0)
    ctx = multiprocessing.get_context("fork")
    q = ctx.Queue()
    p = ctx.Process(target=_allan_child, args=(q,))
    p.start()
    n = q.get(timeout=60)
    p.join(timeout=60)
    assert p.exitcode == 0
    assert n == len(imudrift.allan(np.random.default_rng(2).normal(0.0, 0.01, 30_000), 100.0).tau)


def test_an_n_by_3_array_gives_three_channels_equal_to_three_1d_calls():
    # MATLAB allanvar's layout: one channel per column.
    x = np.random.default_rng(7).normal(0.0, [0.01, 0.02, 0.03], size=(20_000, 3))
    results = imudrift.allan(x, 100.0)
    assert isinstance(results, list) and len(results) == 3
    for j, r in enumerate(results):
        one = imudrift.allan(np.ascontiguousarray(x[:, j]), 100.0)
        a, b = r.to_dict(), one.to_dict()
        assert a.keys() == b.keys()
        for k in ("tau", "deviation", "lo", "hi", "edf", "m"):
            np.testing.assert_array_equal(a[k], b[k])
        assert json.dumps(a["fit"], sort_keys=True) == json.dumps(b["fit"], sort_keys=True)


def test_an_n_by_k_array_names_the_column_it_refuses():
    x = np.random.default_rng(7).normal(size=(20_000, 2))
    x[5, 1] = np.nan
    with pytest.raises(imudrift.InvalidInput, match=r"data\[:, 1\]"):
        imudrift.allan(x, 100.0)
    with pytest.raises(imudrift.InvalidInput, match="at least one column"):
        imudrift.allan(np.zeros((10, 0)), 100.0)
