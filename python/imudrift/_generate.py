"""``imudrift.generate``: a synthetic static IMU log from a sensor model, as a pandas DataFrame."""

import os

from ._imudrift import generate_columns as _generate


def generate(sensor, duration_s, rate_hz, seed=1, run=0, only=None, without=None):
    """The log ``imudrift generate SENSOR --duration S --rate HZ --seed SEED --run RUN`` writes,
    as a ``pandas.DataFrame`` (the same values, bit for bit): a static, level IMU under standard
    gravity, columns ``t`` (k / rate, s), ``gx gy gz`` (rad/s), ``ax ay az`` (m/s^2, specific
    force: az about -9.81), ``temp`` (degC). ``df.attrs`` holds ``sensor``, ``seed``, ``run`` and
    ``rate_hz``.

    ``sensor``: an :class:`imudrift.Sensor`, or the path of a sensor TOML (or a Kalibr / OpenVINS
    noise file) or its text
    (configs/sensors/ has examples; docs/model.md the keys and units).

    ``only`` / ``without``: the CLI's ``--only`` / ``--without`` term switches (``"gyro.white_noise"``,
    ``"accel"``; a string or a list).

    >>> df = imudrift.generate("configs/sensors/mtx.toml", duration_s=60, rate_hz=100, seed=7)
    """
    try:
        import pandas as pd
    except ImportError:
        raise ImportError("imudrift.generate needs pandas: pip install pandas") from None
    if getattr(sensor, "_text", None) is not None:
        source, text = sensor._source, sensor._text
    elif isinstance(sensor, os.PathLike) or (isinstance(sensor, str) and "\n" not in sensor and os.path.isfile(sensor)):
        source = os.fspath(sensor)
        with open(source, encoding="utf-8") as f:
            text = f.read()
    else:
        source, text = "<sensor text>", str(sensor)
    as_list = lambda t: [t] if isinstance(t, str) else list(t)
    raw = _generate(text, source, float(duration_s), float(rate_hz), int(seed), int(run),
                    None if only is None else as_list(only),
                    [] if without is None else as_list(without))
    name = raw.pop("sensor")
    df = pd.DataFrame(raw)
    df.attrs.update(sensor=name, seed=int(seed), run=int(run), rate_hz=float(rate_hz))
    return df
