"""imudrift.Sensor: read by the CLI's reader (TOML path or text, dict, Kalibr / OpenVINS noise
file), written back as TOML and as a noise file, accepted by generate and simulate."""

import os

import numpy as np
import pytest

import imudrift

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
MTX = os.path.join(ROOT, "configs", "sensors", "mtx.toml")


def test_toml_path_text_and_round_trip():
    s = imudrift.Sensor(MTX)
    assert s.name == "Xsens MTx"
    t = s.to_toml()
    assert imudrift.Sensor.from_toml(t).to_toml() == t
    with open(MTX) as f:
        assert imudrift.Sensor(f.read()).to_toml() == t


def test_dict_gives_the_same_model():
    tomllib = pytest.importorskip("tomllib")
    with open(MTX, "rb") as f:
        d = tomllib.load(f)
    assert imudrift.Sensor(d).to_toml() == imudrift.Sensor(MTX).to_toml()
    assert imudrift.Sensor(imudrift.Sensor(MTX).to_dict()).to_toml() == imudrift.Sensor(MTX).to_toml()


@pytest.mark.parametrize("flavor,name", [("kalibr", "imu.yaml"), ("openvins", "kalibr_imu_chain.yaml")])
def test_noise_file_round_trip(tmp_path, flavor, name):
    s = imudrift.Sensor(MTX)
    text = s.to_kalibr(rate_hz=200.0, flavor=flavor)
    assert "gyroscope_noise_density" in text and "update_rate: 200" in text
    path = tmp_path / name
    path.write_text(text)
    k = imudrift.Sensor(str(path))
    back = k.to_kalibr(rate_hz=200.0, flavor=flavor)
    # Written with 5 significant digits: the values written again are the same.
    line = lambda t, key: next(l for l in t.splitlines() if l.strip().startswith(key))
    for key in ["gyroscope_noise_density", "accelerometer_random_walk"]:
        assert line(back, key) == line(text, key)
    assert imudrift.Sensor.from_kalibr(str(path)).to_toml() == k.to_toml()


def test_a_missing_file_is_an_os_error(tmp_path):
    with pytest.raises(OSError, match="no such file"):
        imudrift.Sensor(str(tmp_path / "missing.toml"))


def test_bad_sensors_raise_value_errors():
    with pytest.raises(imudrift.InvalidInput, match="white_noise"):
        imudrift.Sensor('name = "x"\n[gyro.x]\nwhite_noise = "-1 rad/s/sqrt(Hz)"\n')
    with pytest.raises(ValueError):
        imudrift.Sensor({"name": "x", "gyro": {"x": {"white_noise": None}}})
    with pytest.raises(imudrift.InvalidInput, match="flavor"):
        imudrift.Sensor(MTX).to_kalibr(100.0, flavor="rovio")


def test_generate_and_simulate_take_a_sensor():
    pytest.importorskip("pandas")
    s = imudrift.Sensor(MTX)
    a = imudrift.generate(s, duration_s=2, rate_hz=100, seed=3)
    b = imudrift.generate(MTX, duration_s=2, rate_hz=100, seed=3)
    np.testing.assert_array_equal(a.to_numpy(), b.to_numpy())
    r = imudrift.simulate(s, runs=8, duration_s=2, rate_hz=50)
    assert r.values.shape[0] == 8 and r.sensor == "Xsens MTx"


@pytest.mark.parametrize("sensor", ["mtx.toml", "adis16405.toml"])
def test_plan_equals_the_cli(sensor):
    import json
    import subprocess

    from test_allan import cli_binary

    exe = cli_binary()
    if exe is None:
        pytest.skip("no imudrift binary (cargo build --release, or set IMUDRIFT_BIN)")
    path = os.path.join(ROOT, "configs", "sensors", sensor)
    out = subprocess.run([exe, "plan", path, "--uncertainty", "5%", "--duration", "3600",
                          "--rate", "200", "--json"], check=True, capture_output=True)
    ours = imudrift.plan(imudrift.Sensor(path), uncertainty="5%", duration_s=3600, rate_hz=200)
    assert ours == json.loads(out.stdout)
    assert ours["required_duration_s"] > 0
    with pytest.raises(imudrift.InvalidInput, match="uncertainty"):
        imudrift.plan(path, uncertainty=1.5)
