"""``imudrift.Sensor``: a sensor model, read by the same reader as the CLI."""

import json
import os

from ._imudrift import sensor_noise_file as _noise_file
from ._imudrift import InvalidInput
from ._imudrift import sensor_parse as _parse
from ._imudrift import sensor_source as _source
from . import _args
from ._imudrift import sensor_toml_of_json as _toml_of_json


class Sensor:
    """A sensor error model (docs/model.md): accepted by :func:`imudrift.simulate` and
    :func:`imudrift.generate` wherever a sensor file is.

    ``Sensor(x)``: ``x`` is the path of a sensor TOML or of a Kalibr ``imu.yaml`` / OpenVINS
    ``kalibr_imu_chain.yaml`` / VINS-Fusion noise file, the text of one, or a dict with the TOML
    file's keys. Bad input raises :class:`imudrift.InvalidInput` (a ``ValueError``) with the
    CLI's message; an unreadable file an ``OSError``.

    >>> s = imudrift.Sensor("configs/sensors/mtx.toml")
    >>> s.name
    >>> k = imudrift.Sensor(s.to_kalibr(rate_hz=200.0), source="imu.yaml")   # round trip
    >>> imudrift.simulate(s, runs=100, duration_s=30).to_pandas()
    """

    def __init__(self, x, source=None):
        if isinstance(x, Sensor):
            text, src = x._text, x._source
        elif isinstance(x, dict):
            try:
                as_json = json.dumps(x)
            except (TypeError, ValueError) as e:
                raise InvalidInput(f"sensor dict: {e}") from None
            text, src = _toml_of_json(as_json), "<sensor dict>.toml"
        elif isinstance(x, os.PathLike):
            text, src = _source(os.fspath(x), True)
        elif isinstance(x, str):
            # An existing path is the file (a directory one that cannot be read); a line that is
            # neither a path nor a model's text is a missing file (request::files, the rule).
            text, src = _source(x, False)
        else:
            raise InvalidInput(
                f"Sensor: expected a path, a text or a dict, got {type(x).__name__}")
        self._text = text
        self._source = source if source is not None else src
        parsed = _parse(self._text, self._source)
        self.name = parsed["name"]
        self._toml = parsed["toml"]

    @classmethod
    def from_toml(cls, text):
        """A sensor from the text of a sensor TOML."""
        return cls(text, source="<sensor text>.toml")

    @classmethod
    def from_kalibr(cls, path_or_text):
        """A sensor from a Kalibr / OpenVINS noise file (path or YAML text): white noise and rate
        random walk per axis (docs/noise-files.md)."""
        if isinstance(path_or_text, os.PathLike) or "\n" not in str(path_or_text):
            return cls(path_or_text)
        return cls(str(path_or_text), source="<noise file>.yaml")

    def to_toml(self):
        """The model as a sensor TOML text (the library's writer; reads back to the same model)."""
        return self._toml

    def to_kalibr(self, rate_hz, rostopic="/imu0", flavor="kalibr"):
        """The model as the noise file visual-inertial tools read (``flavor``: ``"kalibr"``
        imu.yaml, ``"openvins"`` kalibr_imu_chain.yaml, ``"vins-fusion"``): continuous-time
        noise density and random walk, the worst axis, per-axis values in comments. A model
        without a rate random walk gets the largest one its Allan curve allows (octave taus from
        1 / rate_hz to 1e4 s)."""
        return _noise_file(self._text, self._source, _args.text("flavor", flavor),
                           _args.number("rate_hz", rate_hz), _args.text("rostopic", rostopic))

    def to_dict(self):
        """The TOML's keys and values as a dict (needs Python 3.11's tomllib or tomli)."""
        try:
            import tomllib
        except ImportError:
            import tomli as tomllib
        return tomllib.loads(self._toml)

    def __repr__(self):
        return f"Sensor({self.name!r}, source={self._source!r})"


def plan(sensor, uncertainty=0.1, duration_s=None, rate_hz=100.0):
    """``imudrift plan SENSOR --json``: how long a static log must be to read each noise term of
    each axis off its Allan deviation to a relative standard uncertainty ``uncertainty`` (a
    fraction, or a percentage such as ``"10%"``), and what a log of ``duration_s`` gives, at
    ``rate_hz``. ``sensor``: an :class:`imudrift.Sensor` or anything ``Sensor()`` takes. Returns
    the CLI's JSON document as a dict (``required_duration_s``, per axis and term ``tau_s``,
    ``share``, ``required_duration_s``, ``uncertainty_at_duration``, ``note``).

    >>> imudrift.plan("configs/sensors/mtx.toml", uncertainty="10%")["required_duration_s"]
    """
    from ._imudrift import sensor_plan as _plan

    s = sensor if isinstance(sensor, Sensor) else Sensor(sensor)
    if isinstance(uncertainty, str):
        t = uncertainty.strip()
        try:
            u = float(t[:-1]) / 100.0 if t.endswith("%") else float(t)
        except ValueError:
            u = float("nan")
    else:
        u = _args.number("uncertainty", uncertainty)
    d = _args.optional_number("duration_s", duration_s)
    return json.loads(_plan(s._text, s._source, u, d, _args.number("rate_hz", rate_hz)))
