"""allantools' deviation functions, computed by imudrift's Rust library.

Each function takes and returns what ``allantools`` (https://github.com/aewallin/allantools)
does: ``f(data, rate=1.0, data_type="phase", taus=None) -> (taus, devs, errs, ns)``, numpy
arrays, equal to allantools' results (tested to 1e-9 relative). The sums are those of the
``imudrift allan`` command (crate ``allan``); this module only follows allantools' conventions:

- ``data_type="freq"`` integrates frequency (rate) samples to phase after removing their mean
  (allantools ``frequency2phase``); ``"phase"`` takes the samples as phase.
- ``taus``: ``None`` or ``"octave"`` (m = 1, 2, 4, ...), ``"decade"`` (1, 2, 4, 10, 20, 40, ...),
  ``"all"`` (every m), or averaging times in seconds (m = round(tau * rate), numpy's rounding),
  each kept when 0 < m < the number of phase points; the returned taus are m / rate.
- no Stable32 stop ratio: a point is kept whenever its sum has 2 or more terms (``ns > 1``).
- ``errs = devs / sqrt(ns)``, allantools' error bar (not a confidence interval: for intervals
  from the equivalent degrees of freedom use :func:`imudrift.allan`).
- ``totdev`` is allantools' total deviation: the doubly reflected series, ``ns = N - 2`` at every
  tau, taus up to N - 1 and no bias correction. Stable32 divides the total variance by its
  flicker / random-walk FM bias and stops at N/2; :func:`imudrift.allan` with
  ``estimator="totdev"`` follows Stable32.

Where this module departs from allantools: bad input raises :class:`imudrift.InvalidInput` (a
``ValueError``) with the request layer's message, as ``imudrift allan`` refuses it: samples an
analysis cannot use (fewer than 2, a NaN or infinite sample (allantools trims NaNs at the ends
of frequency data), a magnitude of 1e100 or more, all one value: allantools gives deviations of
inf or 0), a rate outside 1e-6 to 1e9 Hz, an unknown ``data_type`` or ``taus`` keyword, an
averaging time that is not finite and > 0 (allantools drops it), and a tau list that leaves no
point (allantools raises ``UserWarning``). The GIL is released
while the deviations are computed.
"""

from ._imudrift import allantools_dev as _dev
from ._samples import as_samples as _as_samples
from . import _args

__all__ = ["adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "totdev"]


def _run(function, data, rate, data_type, taus):
    if taus is not None and not isinstance(taus, str):
        taus = _args.numbers_list("taus", taus)
    return _dev(_as_samples(data), _args.number("rate", rate),
                _args.text("data_type", data_type), function, taus)


def adev(data, rate=1.0, data_type="phase", taus=None):
    """Non-overlapping Allan deviation, NIST SP 1065 eq (7): ``(taus, devs, errs, ns)``.

    >>> import numpy as np, imudrift.allantools as at
    >>> taus, devs, errs, ns = at.adev(np.random.default_rng(1).normal(size=1000), 10.0, "freq")
    """
    return _run("adev", data, rate, data_type, taus)


def oadev(data, rate=1.0, data_type="phase", taus=None):
    """Overlapping Allan deviation, NIST SP 1065 eq (11): ``(taus, devs, errs, ns)``."""
    return _run("oadev", data, rate, data_type, taus)


def mdev(data, rate=1.0, data_type="phase", taus=None):
    """Modified Allan deviation, NIST SP 1065 eq (14): ``(taus, devs, errs, ns)``."""
    return _run("mdev", data, rate, data_type, taus)


def tdev(data, rate=1.0, data_type="phase", taus=None):
    """Time deviation tau * mdev / sqrt(3), NIST SP 1065 eq (15): ``(taus, devs, errs, ns)``."""
    return _run("tdev", data, rate, data_type, taus)


def hdev(data, rate=1.0, data_type="phase", taus=None):
    """Non-overlapping Hadamard deviation, NIST SP 1065 eq (18): ``(taus, devs, errs, ns)``."""
    return _run("hdev", data, rate, data_type, taus)


def ohdev(data, rate=1.0, data_type="phase", taus=None):
    """Overlapping Hadamard deviation, NIST SP 1065 eq (20): ``(taus, devs, errs, ns)``."""
    return _run("ohdev", data, rate, data_type, taus)


def totdev(data, rate=1.0, data_type="phase", taus=None):
    """Total deviation as allantools computes it, NIST SP 1065 eq (25) without the bias
    correction Stable32 applies: ``(taus, devs, errs, ns)``."""
    return _run("totdev", data, rate, data_type, taus)
