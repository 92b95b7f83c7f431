"""``imudrift.generate``: a synthetic static IMU log from a sensor model, as a pandas DataFrame."""

import os

from ._imudrift import generate_columns as _generate
from ._imudrift import sensor_source as _source
from . import _args


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
    elif isinstance(sensor, os.PathLike):
        text, source = _source(os.fspath(sensor), True)
    else:
        # A path names the file; a model's text is read as such (request::files, the rule).
        text, source = _source(_args.text("sensor", sensor), False)
    duration_s = _args.number("duration_s", duration_s)
    rate_hz = _args.number("rate_hz", rate_hz)
    seed, run = _args.integer("seed", seed), _args.integer("run", run)
    raw = _generate(text, source, duration_s, rate_hz, seed, run,
                    None if only is None else _args.texts("only", only),
                    [] if without is None else _args.texts("without", without))
    name = raw.pop("sensor")
    df = pd.DataFrame(raw)
    df.attrs.update(sensor=name, seed=seed, run=run, rate_hz=rate_hz)
    return df
