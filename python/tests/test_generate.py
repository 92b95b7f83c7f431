"""imudrift.generate: the same values, bit for bit, as `imudrift generate` for the same seed."""

import os
import subprocess

import numpy as np
import pytest

import imudrift

from test_allan import cli_binary

pd = pytest.importorskip("pandas")

SENSORS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "configs", "sensors")


@pytest.mark.parametrize("sensor,seed,run,switches", [
    ("mtx.toml", 7, 0, {}),
    ("adis16405.toml", 3, 2, {}),
    ("mtx.toml", 4, 1, {"without": ["gyro.white_noise"]}),
    ("mtx.toml", 4, 1, {"only": ["accel", "gyro.bias_instability"]}),
])
def test_same_as_the_cli(tmp_path, sensor, seed, run, switches):
    exe = cli_binary()
    if exe is None:
        pytest.skip("no imudrift binary (cargo build --release, or set IMUDRIFT_BIN)")
    path = os.path.join(SENSORS, sensor)
    out = tmp_path / "log.csv"
    flags = [f for k, v in switches.items() for f in (f"--{k}", ",".join(v))]
    subprocess.run(
        [exe, "generate", path, "--duration", "100", "--rate", "200", "--seed", str(seed),
         "--run", str(run), "-o", str(out), *flags],
        check=True, capture_output=True,
    )
    with open(out) as f:
        header = next(line for line in f if not line.startswith("#")).strip().split(",")
        values = np.loadtxt(f, delimiter=",", comments="#")
    cli = {c: values[:, i] for i, c in enumerate(header)}
    df = imudrift.generate(path, duration_s=100, rate_hz=200, seed=seed, run=run, **switches)
    assert list(df.columns) == header == ["t", "gx", "gy", "gz", "ax", "ay", "az", "temp"]
    assert len(df) == len(values) == 20_000
    for c in df.columns:
        # The CLI writes shortest round-trip decimals, so reading them back gives the same doubles.
        np.testing.assert_array_equal(df[c].to_numpy(), cli[c], err_msg=c)


def test_text_and_path_agree_and_seed_matters():
    path = os.path.join(SENSORS, "mtx.toml")
    with open(path) as f:
        text = f.read()
    a = imudrift.generate(path, 10, 100, seed=5)
    b = imudrift.generate(text, 10, 100, seed=5)
    c = imudrift.generate(path, 10, 100, seed=6)
    np.testing.assert_array_equal(a["gx"], b["gx"])
    assert not np.array_equal(a["gx"], c["gx"])
    assert a.attrs["seed"] == 5 and len(a) == 1000


def test_errors():
    path = os.path.join(SENSORS, "mtx.toml")
    with pytest.raises(imudrift.InvalidInput, match="rate_hz: expected a sample rate in Hz > 0, found 0"):
        imudrift.generate(path, 10, 0)
    with pytest.raises(imudrift.InvalidInput, match="gives 0 samples"):
        imudrift.generate(path, 0.001, 100)
    with pytest.raises(ValueError):
        imudrift.generate("[gyro]\nwhite_noise = \"3 parsecs\"\n", 10, 100)
