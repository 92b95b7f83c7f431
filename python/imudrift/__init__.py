"""imudrift: Monte Carlo laboratory for inertial-sensor drift, from Python.

The numbers come from the same Rust library as the ``imudrift`` command line (no second
implementation): :mod:`imudrift.allantools` (allantools' API and results),
:func:`imudrift.allan` (deviations with confidence intervals, noise types and the IEEE 952 fit),
:func:`imudrift.read_log` (the CLI's log reader) and :func:`imudrift.generate` (a synthetic
log). Bad input raises :class:`InvalidInput`, a ``ValueError``; an unreadable file
:class:`LogUnreadable`, an ``OSError``.
"""

from ._imudrift import InvalidInput, LogUnreadable, __version__
from ._allan import AllanResult, Fit, Term, allan
from ._log import read_log
from ._generate import generate
from . import allantools

__all__ = [
    "__version__",
    "InvalidInput",
    "LogUnreadable",
    "allan",
    "AllanResult",
    "Fit",
    "Term",
    "allantools",
    "read_log",
    "generate",
]
