"""``imudrift.spec``, ``imudrift.diagnose`` and ``imudrift.drift``: the CLI's ``spec``,
``diagnose`` and ``drift`` from Python, through the same library code (``montecarlo::spec_job``,
``diagnose::document``); each result's ``to_dict()`` is the command's ``--json`` document."""

import os

import numpy as np

from ._imudrift import InvalidInput
from ._imudrift import diagnose_run as _diagnose
from ._imudrift import drift_run as _drift
from ._imudrift import spec_run as _spec
from ._document import Document as _Document
from . import _args
from ._samples import as_samples as _as_samples
from ._log import reader_settings
from ._sensor import Sensor

from ._imudrift import CHANNELS as _CHANNELS, TEMPERATURE as _TEMPERATURE
from ._imudrift import DIAGNOSE_DEFAULTS as _DD, DRIFT_DEFAULTS as _FD


def _terms(name, t):
    return _args.texts(name, t)


def _seconds_list(name, xs):
    """Times in seconds: numbers, or texts with a unit the library reads ("10 min", "1h")."""
    if isinstance(xs, (int, float, str, np.number)):
        xs = [xs]
    try:
        xs = list(xs)
    except TypeError:
        raise InvalidInput(f"{name}: expected times (s, or texts such as \"10 min\"), got "
                           f"{type(xs).__name__}") from None
    out = []
    for i, x in enumerate(xs):
        if isinstance(x, str):
            from ._imudrift import seconds_of as _seconds_of

            out.append(_seconds_of(name, x))
        else:
            out.append(_args.number(f"{name}[{i}]", x))
    return out


def _sensor_arg(x):
    """(text, source) of a model: an :class:`imudrift.Sensor` or anything ``Sensor()`` takes."""
    s = x if isinstance(x, Sensor) else Sensor(x)
    return (s._text, s._source)


def _pandas(what):
    try:
        import pandas as pd
    except ImportError:
        raise ImportError(f"{what} needs pandas: pip install pandas") from None
    return pd


class SpecResult(_Document):
    """The result of :func:`spec`: ``sensors`` (per sensor ``name``, ``gyro`` spec values and
    readbacks per axis, ``drift`` rows, ``drift_runs``, ``model_notes``, ``requirements``),
    ``seed``, ``readback_duration_s``, ...; ``to_dict()`` is ``imudrift spec --json``;
    ``to_pandas()`` the drift table; ``requirements()`` the requirements' verdicts."""

    def to_pandas(self):
        """One row per sensor and drift time: ``sensor, t_s, heading_rms_sim_rad,
        heading_rms_law_rad, horizontal_mean_sim_m, horizontal_mean_law_m, horizontal_rms_sim_m,
        horizontal_rms_law_m, horizontal_p95_sim_m, law_note`` (the CLI's drift.csv)."""
        pd = _pandas("SpecResult.to_pandas")
        rows = [dict(sensor=s["name"], **d) for s in self._doc["sensors"] for d in s["drift"]]
        return pd.DataFrame(rows)

    def requirements(self):
        """One row per sensor and requirement: ``sensor, requirement, verdict, value, value_lo,
        value_hi, threshold, margin, ...`` (empty without requirements)."""
        pd = _pandas("SpecResult.requirements")
        rows = [dict(sensor=s["name"], **r) for s in self._doc["sensors"]
                for r in s.get("requirements", [])]
        return pd.DataFrame(rows)

    def __repr__(self):
        names = [s["name"] for s in self._doc["sensors"]]
        return f"SpecResult(sensors={names!r}, seed={self._doc['seed']})"


def spec(sensors, times=None, require=None, runs=None, seed=1, rate_hz=100.0, readback=False,
         readback_duration_s=None, only=None, without=None, threads=None):
    """``imudrift spec SENSOR...``: sensors side by side, the same numbers as the CLI.

    ``sensors``: one or a list of :class:`imudrift.Sensor` or sensor file paths. Per sensor the
    gyro spec values (with ``readback=True`` beside the values read back from a simulated 12 h,
    100 Hz static log, Woodman's method; ``readback_duration_s`` sets its length), the static
    drift at ``times`` (s, or texts such as ``"10 min"``; default 60, 600, 3600) from ``runs``
    Monte Carlo runs (default 200, 500 with requirements) at ``rate_hz``, law beside simulation,
    and each requirement of ``require`` (``"pos_horizontal_m < 10 m @ 300 s"``) answered with
    its margin. ``only`` / ``without`` switch error terms; ``threads``: worker threads (the
    results do not depend on it). The GIL is released; Ctrl-C stops the drift runs (a readback
    in progress finishes first).

    >>> r = imudrift.spec(["configs/sensors/mtx.toml", "configs/sensors/adis16405.toml"],
    ...                   times=[60, 600], runs=100, require="pos_horizontal_m < 10 m @ 60 s")
    >>> r.to_pandas()[["sensor", "t_s", "horizontal_rms_sim_m"]]
    >>> r.requirements()[["sensor", "verdict", "margin"]]
    """
    if isinstance(sensors, (str, os.PathLike, Sensor)):
        sensors = [sensors]
    settings = {
        "require": [] if require is None else _terms("require", require),
        "times": None if times is None else _seconds_list("times", times),
        "rate_hz": _args.number("rate_hz", rate_hz),
        "runs": _args.optional_integer("runs", runs),
        "seed": _args.integer("seed", seed),
        "readback": bool(readback),
        "readback_duration_s": _args.optional_number("readback_duration_s", readback_duration_s),
        "only": None if only is None else _terms("only", only),
        "without": [] if without is None else _terms("without", without),
        "threads": _args.optional_integer("threads", threads),
    }
    return SpecResult(_spec([_sensor_arg(s) for s in sensors], settings))


def _log_arg(x, rate):
    """A log as the Rust side takes it: a path, or a dict of SI arrays with its rate."""
    if isinstance(x, (str, os.PathLike)):
        return os.fspath(x)
    attrs = getattr(x, "attrs", None)
    if hasattr(x, "columns") and attrs is not None:  # a pandas DataFrame (read_log's columns)
        r = rate if rate is not None else attrs.get("rate_hz")
        source = attrs.get("source", "<DataFrame>")
        cols = {c: x[c].to_numpy() for c in list(_CHANNELS) + [_TEMPERATURE] if c in x.columns}
    elif isinstance(x, dict):
        r, source = rate, "<arrays>"
        cols = dict(x)
    else:
        if x is None:
            raise InvalidInput("logs: expected a path, a DataFrame, a dict of channels or an "
                               "n x 6 array (gx gy gz ax ay az), got None")
        a = np.asarray(x)
        if a.dtype.kind not in "biufO":
            raise InvalidInput(f"logs: expected an n x 6 array of real numbers, got dtype {a.dtype}")
        try:
            a = np.asarray(a, dtype=np.float64)
        except (TypeError, ValueError, OverflowError) as e:
            raise InvalidInput(f"logs: expected an n x 6 array of real numbers ({e})") from None
        if a.ndim != 2 or a.shape[1] != 6:
            raise InvalidInput(
                f"logs: expected a path, a DataFrame, a dict of channels or an n x 6 array "
                f"(gx gy gz ax ay az), got shape {a.shape}")
        r, source = rate, "<array>"
        cols = {c: a[:, i] for i, c in enumerate(_CHANNELS)}
    if r is None:
        raise InvalidInput(f"{source}: rate: the sample rate in Hz is needed for samples given as arrays")
    channels = [(str(k), _as_samples(v, f"{source}: {k}")) for k, v in cols.items()]
    return {"source": str(source), "rate_hz": _args.number("rate", r), "channels": channels}


def _logs(logs, rate):
    if isinstance(logs, (list, tuple)):
        return [_log_arg(x, rate) for x in logs]
    return [_log_arg(logs, rate)]


class DiagnoseResult(_Document):
    """The result of :func:`diagnose`: ``to_dict()`` is ``imudrift diagnose --json``;
    ``effects`` the effects found (one dict per channel and effect: ``channel, effect, kind,
    parameters, parameters_lo, parameters_hi, gap_before, gap_after, delta_bic, round, ...``,
    SI units); ``to_pandas()`` the same as a DataFrame; ``corrected`` the corrected model as an
    :class:`imudrift.Sensor` (``corrected.to_toml()`` is the CLI's ``*-diagnosed.toml``);
    ``channels``, ``drift``, ``drift_check``, ``checks``, ``seed`` ... the document's keys."""

    def __init__(self, raw):
        super().__init__(raw["document"])
        self.corrected = Sensor(raw["corrected"], source=raw["corrected_source"])

    @property
    def effects(self):
        return [dict(channel=ch, **e) for ch, r in self._doc["channels"].items()
                for e in r["effects"]]

    def to_pandas(self):
        """The effects table: one row per channel and effect found."""
        pd = _pandas("DiagnoseResult.to_pandas")
        cols = ["channel", "effect", "kind", "parameters", "parameters_lo", "parameters_hi",
                "gap_before", "gap_after", "delta_bic", "round", "cannot_tell_from"]
        rows = self.effects
        return pd.DataFrame([{k: e.get(k) for k in cols} for e in rows], columns=cols)

    def __repr__(self):
        return (f"DiagnoseResult(log={self._doc['log']!r}, model={self._doc['model']!r}, "
                f"effects={len(self.effects)})")


def diagnose(logs, model, rate=None, gyro_unit=None, accel_unit=None, time_unit=None,
             columns=None, topic=None, seed=_DD["seed"], seeds=_DD["seeds"],
             rounds=_DD["rounds"], horizons=tuple(_DD["horizons"]),
             min_delta_bic=_DD["min_delta_bic"], tau_min=_DD["tau_min"], check=None,
             drift_check=False, calibration=None, init=None, threads=None,
             latitude=_DD["latitude"]):
    """``imudrift diagnose LOG... --model MODEL``: where the model and the measured static log
    disagree, which effect is missing, the corrected model; the same numbers as the CLI.

    ``logs``: one log or a list of runs of one sensor, each a path (every format
    :func:`imudrift.read_log` reads, with its reader arguments ``rate``, ``gyro_unit``,
    ``accel_unit``, ``time_unit``, ``columns``, ``topic``), a DataFrame of ``read_log``
    (channels ``gx gy gz ax ay az [temp]`` in SI), a dict of such arrays or an n x 6 array (then
    ``rate`` is needed). ``model``: an :class:`imudrift.Sensor` or a sensor file path. The CLI's
    options: ``seed``, ``seeds`` (simulated logs per band), ``rounds``, ``horizons`` (s),
    ``min_delta_bic``, ``tau_min`` (s), ``check`` (held-out logs), ``drift_check``,
    ``calibration`` (``"none"``, ``"log-mean"``, ``"window:60"``), ``init`` (``"perfect"``,
    ``"level:10"``), ``threads``, ``latitude`` (deg: the logs are dead-reckoned on the rotating
    WGS-84 Earth there, Earth rate kept as signal; ``None``: Woodman's flat Earth, the CLI's
    ``--flat-earth``). The GIL is released while it works; Ctrl-C stops it within a second
    (``KeyboardInterrupt``).

    >>> r = imudrift.diagnose("adis16405_imu1.csv.gz", "configs/sensors/adis16405.toml",
    ...                       rate=100, horizons=[60])
    >>> r.to_pandas()[["channel", "effect", "gap_before", "gap_after"]]
    >>> r.corrected.to_toml()
    """
    settings = {
        "seed": _args.integer("seed", seed),
        "seeds": _args.integer("seeds", seeds),
        "rounds": _args.integer("rounds", rounds),
        "horizons": _seconds_list("horizons", horizons),
        "min_delta_bic": _args.number("min_delta_bic", min_delta_bic),
        "tau_min": _args.number("tau_min", tau_min),
        "drift_check": bool(drift_check),
        "calibration": _args.optional_text("calibration", calibration),
        "init": _args.optional_text("init", init),
        "threads": _args.optional_integer("threads", threads),
        "latitude": _args.optional_number("latitude", latitude),
    }
    reader = reader_settings(rate, gyro_unit, accel_unit, time_unit, columns, topic)
    held = [] if check is None else _logs(check, rate)
    raw = _diagnose(_logs(logs, rate), _sensor_arg(model), reader, settings, held)
    return DiagnoseResult(raw)


class DriftResult(_Document):
    """The result of :func:`drift`: ``to_dict()`` is ``imudrift drift --json``; ``horizons``
    (per horizon ``t_s``, ``segments`` and per quantity ``measured``, ``model``, ``verdict``,
    ``ratio`` ...), ``protocol_text``, ``parameters``; ``to_pandas()`` the verdict table."""

    def to_pandas(self):
        """One row per horizon and quantity: ``t_s, segments, quantity, measured_rms,
        measured_rms_lo, measured_rms_hi, model_rms, band_lo, band_hi, ratio, verdict, note,
        likely_cause``."""
        pd = _pandas("DriftResult.to_pandas")
        rows = []
        for h in self._doc["horizons"]:
            for q, c in h["channels"].items():
                m, mo = c.get("measured") or {}, c.get("model") or {}
                rows.append({
                    "t_s": h["t_s"], "segments": h["segments"], "quantity": q,
                    "measured_rms": m.get("rms"), "measured_rms_lo": m.get("rms_lo"),
                    "measured_rms_hi": m.get("rms_hi"), "model_rms": mo.get("rms"),
                    "band_lo": mo.get("band_lo"), "band_hi": mo.get("band_hi"),
                    "ratio": c.get("ratio"), "verdict": c["verdict"], "note": c.get("note"),
                    "likely_cause": c.get("likely_cause"),
                })
        return pd.DataFrame(rows)

    def __repr__(self):
        return f"DriftResult(logs={self._doc['logs']!r}, model={self._doc['model']!r})"


def drift(logs, model, rate=None, gyro_unit=None, accel_unit=None, time_unit=None, columns=None,
          topic=None, calibration="log-mean", init="perfect", horizons=tuple(_FD["horizons"]),
          overlap=False, replicates=_FD["replicates"], exact_parameters=False,
          one_structure=False, seed=_FD["seed"], threads=None, latitude=_FD["latitude"]):
    """``imudrift drift LOG... --model MODEL``: the drift measured on static logs against the
    drift the model predicts under one protocol, with intervals and a verdict; the same numbers
    as the CLI.

    ``logs`` and ``model`` as for :func:`diagnose`. The protocol: ``calibration`` (``"none"``,
    ``"log-mean"``, ``"window:60"``), ``init`` (``"perfect"``, ``"level:10"``), ``horizons``
    (s), ``overlap`` (half-overlapping segments); ``replicates`` simulated experiments for the
    model's 95 % band; ``exact_parameters`` takes a diagnosed model's levels and
    run-to-run spreads as exact (no parametric bootstrap, no draw of the spreads); ``one_structure`` takes its structure as certain (no averaging over
    the ``[[alternatives]]`` a diagnosed model lists); ``seed``; ``threads``; ``latitude`` (deg,
    or ``None`` for the flat Earth, as for :func:`diagnose`). The GIL is released while it works;
    Ctrl-C stops it within a second (``KeyboardInterrupt``).

    >>> r = imudrift.drift(["adis16405_imu1.csv.gz", "adis16405_imu2.csv.gz"],
    ...                    "configs/sensors/adis16405.toml", rate=100, horizons=[60, 600])
    >>> r.to_pandas().query("verdict != 'inside'")
    """
    settings = {
        "calibration": _args.text("calibration", calibration),
        "init": _args.text("init", init),
        "horizons": _seconds_list("horizons", horizons),
        "overlap": bool(overlap),
        "replicates": _args.integer("replicates", replicates),
        "exact_parameters": bool(exact_parameters),
        "one_structure": bool(one_structure),
        "seed": _args.integer("seed", seed),
        "threads": _args.optional_integer("threads", threads),
        "latitude": _args.optional_number("latitude", latitude),
    }
    reader = reader_settings(rate, gyro_unit, accel_unit, time_unit, columns, topic)
    return DriftResult(_drift(_logs(logs, rate), _sensor_arg(model), reader, settings))
