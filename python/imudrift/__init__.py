"""imudrift: Monte Carlo laboratory for inertial-sensor drift, from Python.

The numbers come from the same Rust library as the ``imudrift`` command line (no second
implementation): :mod:`imudrift.allantools` (allantools' API and results),
:func:`imudrift.allan` (deviations with confidence intervals, noise types and the IEEE 952 fit),
:func:`imudrift.read_log` (the CLI's log reader) and :func:`imudrift.generate` (a synthetic
log), :class:`Sensor` (a sensor model from TOML, a dict or a Kalibr / OpenVINS file),
:func:`simulate` (the Monte Carlo drift run) and its shards (:func:`simulate_shard`,
:func:`merge`), :func:`spec` (sensors side by side), :func:`diagnose` (a model against a measured
log: the effects it misses and the corrected model) and :func:`drift` (measured drift against the
model's). Bad input raises :class:`InvalidInput`, a ``ValueError``; an unreadable file
:class:`LogUnreadable`, an ``OSError``.
"""

from ._imudrift import InvalidInput, LogUnreadable, __version__
from ._allan import AllanResult, Fit, Term, allan
from ._log import read_log
from ._generate import generate
from ._sensor import Sensor, plan
from ._simulate import SimulateResult, merge, simulate, simulate_shard
from ._analyse import DiagnoseResult, DriftResult, SpecResult, diagnose, drift, spec
from . import allantools, noise

__all__ = [
    "__version__",
    "InvalidInput",
    "LogUnreadable",
    "allan",
    "AllanResult",
    "Fit",
    "Term",
    "allantools",
    "noise",
    "read_log",
    "generate",
    "Sensor",
    "simulate",
    "simulate_shard",
    "merge",
    "SimulateResult",
    "plan",
    "spec",
    "SpecResult",
    "diagnose",
    "DiagnoseResult",
    "drift",
    "DriftResult",
]
