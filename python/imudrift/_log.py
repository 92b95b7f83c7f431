"""``imudrift.read_log``: a log file read by the command line's reader, as a pandas DataFrame."""

import os

from ._imudrift import InvalidInput
from ._imudrift import read_log_columns as _read
from . import _args


def reader_settings(rate, gyro_unit, accel_unit, time_unit, columns, topic):
    """The reader's settings as the compiled module takes them (``read_log``'s arguments)."""
    if columns is not None:
        try:
            columns = [(str(k), str(v)) for k, v in dict(columns).items()]
        except (TypeError, ValueError):
            raise InvalidInput(f"columns: expected a dict such as {{\"gx\": \"my_column\"}}, "
                               f"got {type(columns).__name__}") from None
    return {
        "rate": _args.optional_number("rate", rate),
        "gyro_unit": _args.optional_text("gyro_unit", gyro_unit),
        "accel_unit": _args.optional_text("accel_unit", accel_unit),
        "time_unit": _args.optional_text("time_unit", time_unit),
        "columns": columns,
        "topic": _args.optional_text("topic", topic),
    }


def read_log(path, rate=None, gyro_unit=None, accel_unit=None, time_unit=None, columns=None, topic=None):
    """Read an IMU log as ``imudrift`` commands do (crate ``logio``): CSV or gzip CSV (``#``
    comment lines, a header row, columns found by name with their units), a ROS 1 bag or a ROS 2
    MCAP file (``sensor_msgs/Imu``). Returns a ``pandas.DataFrame`` with ``t`` (s, when the log
    has times) and the channels ``gx gy gz`` (rad/s), ``ax ay az`` (m/s^2), ``temp`` (degC) in
    the log's order; ``df.attrs`` holds ``rate_hz`` and ``source``.

    ``rate``: Hz, needed when the log has no time column. ``gyro_unit`` (rad/s, deg/s, deg/h),
    ``accel_unit`` (m/s^2, g, mg), ``time_unit`` (s, ms, us, ns): units that column names do not
    state. ``columns``: ``{"gx": "my_gyro_column", ...}`` maps columns by hand. ``topic``: the IMU
    topic of a bag with several.

    Errors: :class:`imudrift.LogUnreadable` (an ``OSError``) when the file cannot be read,
    :class:`imudrift.InvalidInput` (a ``ValueError``) with the reader's message otherwise.
    """
    try:
        import pandas as pd
    except ImportError:
        raise ImportError("imudrift.read_log needs pandas: pip install pandas") from None
    if not isinstance(path, (str, os.PathLike)):
        raise InvalidInput(f"path: expected a file path, got {type(path).__name__}")
    raw = _read(os.fspath(path), reader_settings(rate, gyro_unit, accel_unit, time_unit, columns, topic))
    data = {} if raw["t"] is None else {"t": raw["t"]}
    data.update(raw["channels"])
    df = pd.DataFrame(data)
    df.attrs["rate_hz"] = raw["rate_hz"]
    df.attrs["source"] = raw["source"]
    return df
