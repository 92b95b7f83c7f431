"""imudrift: Monte Carlo laboratory for inertial-sensor drift, from Python.

The numbers come from the same Rust library as the ``imudrift`` command line (no second
implementation): ``imudrift.allantools`` (allantools' API) and ``imudrift.allan`` (deviations
with confidence intervals, noise types and the IEEE 952 fit).
"""

from ._imudrift import __version__

__all__ = ["__version__"]
