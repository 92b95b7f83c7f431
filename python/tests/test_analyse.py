"""imudrift.spec, diagnose, drift: to_dict() equal to the CLI's --json (a shipped sensor pair; the
ADIS16405 logs from $IMUDRIFT_DATA, skipped without them), logs given as arrays equal to the same
log as a file, the tables, the corrected Sensor, errors named by the Python arguments, the GIL
released and Ctrl-C stopping spec's drift runs. Kept short (horizon 60 s, few seeds/replicates)."""

import os
import subprocess

import numpy as np
import pytest

import imudrift

from test_simulate import ROOT, assert_same, cli_binary, interrupted_after, python_loops_beside

MTX = os.path.join(ROOT, "configs", "sensors", "mtx.toml")
ADIS = os.path.join(ROOT, "configs", "sensors", "adis16405.toml")
REQ = "pos_horizontal_m < 100 m @ 60 s"


def cli(*args):
    import json

    exe = cli_binary()
    if exe is None:
        pytest.skip("no imudrift binary (cargo build --release, or set IMUDRIFT_BIN)")
    out = subprocess.run([exe, *args, "--json"], check=True, capture_output=True)
    return json.loads(out.stdout)


@pytest.fixture(scope="module")
def adis_logs():
    """Paths of ADIS16405 static runs 1 and 2 (100 Hz, no time column)."""
    root = os.environ.get("IMUDRIFT_DATA")
    if not root:
        pytest.skip("IMUDRIFT_DATA is not set: the ADIS16405 logs are not available")
    paths = [os.path.join(root, "adis16405_imudata", f"adis16405_imu{i}.csv.gz") for i in (1, 2)]
    if not all(os.path.exists(p) for p in paths):
        pytest.skip(f"{paths} not found")
    return paths


def test_spec_to_dict_equals_the_cli_json():
    c = cli("spec", MTX, ADIS, "--times", "60,600", "--runs", "50", "--require", REQ,
            "--readback-duration", "3600", "--seed", "5")
    r = imudrift.spec([MTX, imudrift.Sensor(ADIS)], times=[60, "10 min"], runs=50, require=REQ,
                      readback_duration_s=3600, seed=5)
    assert_same(r.to_dict(), c)
    df = r.to_pandas()
    assert list(df["sensor"]) == ["Xsens MTx"] * 2 + ["ADIS16405"] * 2
    assert list(df["t_s"]) == [60.0, 600.0] * 2
    req = r.requirements()
    assert list(req["sensor"]) == ["Xsens MTx", "ADIS16405"]
    assert set(req["verdict"]) <= {"pass", "fail", "undecided", "not_informed"}
    assert r.seed == 5 and r.readback_duration_s == 3600


def test_spec_errors_name_the_arguments():
    with pytest.raises(imudrift.InvalidInput, match="^require: "):
        imudrift.spec(MTX, require="pos_horizontal_m < 10 m")
    with pytest.raises(imudrift.InvalidInput, match="^rate_hz: expected a sample rate"):
        imudrift.spec(MTX, rate_hz=-1)
    with pytest.raises(imudrift.InvalidInput, match="^runs: expected an integer >= 1"):
        imudrift.spec(MTX, runs=0)
    with pytest.raises(imudrift.InvalidInput, match="shorter than one sample at rate_hz"):
        imudrift.spec(MTX, times=[0.001])
    with pytest.raises(imudrift.InvalidInput, match="^readback_duration_s: expected at least 10 s"):
        imudrift.spec(MTX, readback_duration_s=1)


def test_diagnose_to_dict_equals_the_cli_json(adis_logs):
    log = adis_logs[0]
    c = cli("diagnose", log, "--model", ADIS, "--rate", "100", "--horizons", "60", "--seeds", "4",
            "--rounds", "1")
    r = imudrift.diagnose(log, ADIS, rate=100, horizons=[60], seeds=4, rounds=1)
    assert_same(r.to_dict(), c)
    # The effects table, and the corrected model: the CLI's TOML, read back as a Sensor.
    effects = r.effects
    assert effects and {e["channel"] for e in effects} <= set(c["channels"])
    n = sum(len(ch["effects"]) for ch in c["channels"].values())
    df = r.to_pandas()
    assert len(df) == n and {"channel", "effect", "gap_before", "gap_after"} <= set(df.columns)
    assert isinstance(r.corrected, imudrift.Sensor)
    assert r.corrected.name == "ADIS16405"
    assert imudrift.Sensor(c["corrected_model_toml"]).to_toml() == r.corrected.to_toml()


def test_drift_to_dict_equals_the_cli_json(adis_logs):
    c = cli("drift", *adis_logs, "--model", ADIS, "--rate", "100", "--horizons", "60",
            "--replicates", "10", "--calibration", "window:60", "--init", "level:60")
    r = imudrift.drift(adis_logs, imudrift.Sensor(ADIS), rate=100, horizons=[60], replicates=10,
                       calibration="window:60", init="level:1 min")
    assert_same(r.to_dict(), c)
    df = r.to_pandas()
    quantities = c["horizons"][0]["channels"]
    assert len(df) == len(quantities) and set(df["quantity"]) == set(quantities)
    assert set(df["verdict"]) <= {"inside", "above", "below", "not_informed"}


def test_drift_latitude_is_the_clis(adis_logs):
    """``latitude`` is the CLI's ``--latitude`` (``None``: ``--flat-earth``); out of range: a
    ValueError naming it."""
    for lat, flags in [(30.0, ["--latitude", "30"]), (None, ["--flat-earth"])]:
        c = cli("drift", *adis_logs, "--model", ADIS, "--rate", "100", "--horizons", "60",
                "--replicates", "10", *flags)
        r = imudrift.drift(adis_logs, imudrift.Sensor(ADIS), rate=100, horizons=[60],
                           replicates=10, latitude=lat)
        assert_same(r.to_dict(), c)
    with pytest.raises(ValueError, match="latitude"):
        imudrift.drift(adis_logs, imudrift.Sensor(ADIS), rate=100, horizons=[60],
                       replicates=10, latitude=95.0)


def synthetic_log(tmp_path):
    """A 10-minute static MTx log at 100 Hz as a DataFrame and as a CSV file of the same values."""
    df = imudrift.generate(imudrift.Sensor(MTX), duration_s=600, rate_hz=100, seed=3)
    cols = ["gx", "gy", "gz", "ax", "ay", "az"]
    path = tmp_path / "mtx.csv"
    np.savetxt(path, df[cols].to_numpy(), fmt="%.17g", delimiter=",", header=",".join(cols),
               comments="")
    return df[cols], str(path)


def test_arrays_are_the_same_log_as_a_file(tmp_path):
    df, path = synthetic_log(tmp_path)
    kw = dict(rate=100, horizons=[60], seeds=4, rounds=1)
    named = ("log", "columns", "skipped_columns")
    strip = lambda d: {k: v for k, v in d.items() if k not in named}
    from_file = imudrift.diagnose(path, MTX, **kw).to_dict()
    for given in (df, df.to_numpy(), {c: df[c].to_numpy() for c in df.columns}):
        d = imudrift.diagnose(given, MTX, **kw).to_dict()
        assert_same(strip(d), strip(from_file))
        assert [c["channel_from"] for c in d["columns"]] == ["name"] * 6
    a = imudrift.drift(df, MTX, rate=100, horizons=[60], replicates=10).to_dict()
    b = imudrift.drift(path, MTX, rate=100, horizons=[60], replicates=10).to_dict()
    assert a.pop("logs") != b.pop("logs")
    assert_same(a, b)


def test_diagnose_and_drift_errors_name_the_arguments(tmp_path):
    df, _ = synthetic_log(tmp_path)
    with pytest.raises(imudrift.InvalidInput, match="rate: the sample rate in Hz is needed"):
        imudrift.diagnose(df.to_numpy(), MTX)
    with pytest.raises(imudrift.InvalidInput, match="^seeds 1: at least 2"):
        imudrift.diagnose(df, MTX, rate=100, seeds=1)
    with pytest.raises(imudrift.InvalidInput, match="^replicates 5: expected 10 to 100000"):
        imudrift.drift(df, MTX, rate=100, replicates=5)
    with pytest.raises(imudrift.InvalidInput, match="^horizons 0.015: 1.5 samples"):
        imudrift.drift(df, MTX, rate=100, horizons=[0.015], replicates=10)
    with pytest.raises(imudrift.InvalidInput, match="^calibration window:700: the window is longer"):
        imudrift.drift(df, MTX, rate=100, horizons=[60], calibration="window:700")
    with pytest.raises(imudrift.InvalidInput, match="channel gx is constant"):
        imudrift.drift(dict(df, gx=np.zeros(len(df))), MTX, rate=100, horizons=[60])
    with pytest.raises(imudrift.LogUnreadable):
        imudrift.drift(str(tmp_path / "missing.csv"), MTX, rate=100)


def test_the_gil_is_released_during_spec():
    still_running, loops = python_loops_beside(
        lambda: imudrift.spec(MTX, times=[600], runs=300, threads=1))
    assert still_running, "spec ended too soon to tell"
    assert loops > 1000


CTRL_C_CHILD = r"""
import sys, imudrift
import signal
# A parent started in the background passes SIGINT on as ignored: take Python's default back.
signal.signal(signal.SIGINT, signal.default_int_handler)
print("start", flush=True)
try:
    imudrift.spec(sys.argv[1], times=[3600], runs=100000, threads=1)
except KeyboardInterrupt:
    print("interrupted", flush=True)
"""


def test_ctrl_c_stops_spec_drift_runs():
    out, took = interrupted_after(CTRL_C_CHILD, MTX)
    assert "interrupted" in out
    assert took < 1.0


def test_drift_averages_over_a_models_alternatives(tmp_path):
    """A model with [[alternatives]] (as diagnose writes them): the band is averaged over its
    structures as by the CLI, and one_structure=True takes the model's own alone."""
    df, path = synthetic_log(tmp_path)
    model = tmp_path / "alt.toml"
    model.write_text(open(MTX).read() + """
[[alternatives]]
channel = "gz"
weight = 0.3
delta_bic = 1.7
effects = ["rate_random_walk"]
removed = []
[alternatives.terms]
white_noise = "0.05 deg/s/sqrt(Hz)"
rate_random_walk = "100 deg/h/sqrt(h)"
""")
    kw = dict(rate=100, horizons=[60], replicates=10)
    r = imudrift.drift(path, str(model), **kw).to_dict()
    assert [s["replicates"] for s in r["structures"]] == [7, 3]
    assert r["structures"][1]["label"] == "gz: rate_random_walk"
    c = cli("drift", path, "--model", str(model), "--rate", "100", "--horizons", "60",
            "--replicates", "10")
    assert_same(r, c)
    one = imudrift.drift(path, str(model), one_structure=True, **kw).to_dict()
    assert "structures" not in one
