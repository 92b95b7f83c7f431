"""imudrift: Monte Carlo laboratory for inertial-sensor drift, from Python.

The numbers come from the same Rust library as the ``imudrift`` command line (no second
implementation): :mod:`imudrift.allantools` (allantools' API and results) and
:func:`imudrift.allan` (deviations with confidence intervals, noise types and the IEEE 952 fit).
Bad input raises :class:`InvalidInput`, a ``ValueError``.
"""

from ._imudrift import InvalidInput, __version__
from ._allan import AllanResult, Fit, Term, allan
from . import allantools

__all__ = ["__version__", "InvalidInput", "allan", "AllanResult", "Fit", "Term", "allantools"]
