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
- ``mtotdev``, ``ttotdev`` and ``htotdev`` are allantools' (SP 1065 eqs (27), (28) and
  §5.2.13): each subsequence of 3m points detrended and reflected, ``ns = N - 3m + 1``
  subsequences, taus up to N/3, no bias correction; ``htotdev`` works on frequency (N - 1
  points from N phase points) and is the overlapping Hadamard deviation at m = 1. These cost
  O(N m) per tau (as in allantools, whose loops are Python's): long records at long taus take
  long (see docs/allan.md).
- ``theo1`` is allantools' Theo1 (SP 1065 eq (30)): even m only, ``ns = (N - m) m / 2``,
  ``errs = devs / sqrt(N - m)``, and like allantools it returns ``taus = m / rate``, not
  Theo1's own tau 0.75 m / rate (which :func:`imudrift.allan` with ``estimator="theo1"`` and
  the command report).
- ``mtie`` and ``tierms`` are the time-interval errors (ITU-T G.810; Stable32 "MTIE (Fast)"
  and "TIE rms"): the largest peak-to-peak phase over windows of m + 1 points and the rms of
  x[i+m] - x[i]; ``ns = N - m``, ``errs`` MTIE / sqrt(ns) and 0 for TIE rms (allantools').
- ``gradev`` is the gap-tolerant overlapping Allan deviation: NaN samples are gaps, the terms
  that touch one are left out, ``ns`` counts the others; it returns ``(taus, devs, [lo, hi],
  ns)``. allantools computes ``[lo, hi]`` with its arguments swapped (every bound is NaN) and
  maps ``noisetype="fp"`` to random-walk FM; here ``[lo, hi]`` is the chi-squared interval at
  level ``ci`` (SP 1065 eq (45)) with SP 1065 Table 5's EDF for the named noise type
  (``wp`` white PM, ``fp`` flicker PM, ``wf`` white FM, ``ff`` flicker FM, ``rf`` random-walk
  FM; N - 1 degrees of freedom for any other name), N the phase points present. Frequency
  input is integrated as allantools does (gaps at the ends dropped, a gap inside makes every
  later phase point a gap): give phase data with gaps.

Where this module departs from allantools: bad input raises :class:`imudrift.InvalidInput` (a
``ValueError``) with the request layer's message, as ``imudrift allan`` refuses it: samples an
analysis cannot use (fewer than 2, a NaN or infinite sample (allantools trims NaNs at the ends
of frequency data), a magnitude of 1e100 or more, all one value: allantools gives deviations of
inf or 0; ``gradev`` takes NaN as gaps and applies these rules to the samples present), a rate outside 1e-6 to 1e9 Hz, an unknown ``data_type`` or ``taus`` keyword, an
averaging time that is not finite and > 0 (allantools drops it), and a tau list that leaves no
point (allantools raises ``UserWarning``). The GIL is released
while the deviations are computed.
"""

from ._imudrift import allantools_dev as _dev
from ._imudrift import allantools_gradev as _gradev
from ._samples import as_samples as _as_samples
from . import _args

__all__ = ["adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "totdev", "mtotdev", "ttotdev",
           "htotdev", "theo1", "mtie", "tierms", "gradev"]


def _taus(taus):
    if taus is not None and not isinstance(taus, str):
        return _args.numbers_list("taus", taus)
    return taus


def _run(function, data, rate, data_type, taus):
    return _dev(_as_samples(data), _args.number("rate", rate),
                _args.text("data_type", data_type), function, _taus(taus))


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


def mtotdev(data, rate=1.0, data_type="phase", taus=None):
    """Modified total deviation, NIST SP 1065 eq (27), without bias correction:
    ``(taus, devs, errs, ns)``."""
    return _run("mtotdev", data, rate, data_type, taus)


def ttotdev(data, rate=1.0, data_type="phase", taus=None):
    """Time total deviation tau * mtotdev / sqrt(3), NIST SP 1065 eq (28) (which misprints
    tau^3): ``(taus, devs, errs, ns)``."""
    return _run("ttotdev", data, rate, data_type, taus)


def htotdev(data, rate=1.0, data_type="phase", taus=None):
    """Hadamard total deviation, NIST SP 1065 §5.2.13 (the overlapping Hadamard deviation at
    m = 1), without bias correction: ``(taus, devs, errs, ns)``."""
    return _run("htotdev", data, rate, data_type, taus)


def theo1(data, rate=1.0, data_type="phase", taus=None):
    """Theo1, NIST SP 1065 eq (30), even m only, ``taus = m / rate`` as allantools returns them
    (Theo1's own tau is 0.75 m / rate): ``(taus, devs, errs, ns)``."""
    return _run("theo1", data, rate, data_type, taus)


def mtie(data, rate=1.0, data_type="phase", taus=None):
    """Maximum time-interval error over windows of m + 1 phase points (ITU-T G.810):
    ``(taus, devs, errs, ns)``."""
    return _run("mtie", data, rate, data_type, taus)


def tierms(data, rate=1.0, data_type="phase", taus=None):
    """Time-interval error rms, the rms of x[i+m] - x[i] (ITU-T G.810):
    ``(taus, devs, errs, ns)`` with ``errs`` 0 as allantools gives."""
    return _run("tierms", data, rate, data_type, taus)


def gradev(data, rate=1.0, data_type="phase", taus=None, ci=0.9, noisetype="wp"):
    """Gap-tolerant overlapping Allan deviation (NaN samples are gaps):
    ``(taus, devs, [lo, hi], ns)``, [lo, hi] the chi-squared interval at level ``ci`` for the
    noise type ``noisetype`` (see the module's notes)."""
    taus_out, devs, (lo, hi), ns = _gradev(
        _as_samples(data), _args.number("rate", rate), _args.text("data_type", data_type),
        _taus(taus), _args.number("ci", ci), _args.text("noisetype", noisetype))
    return taus_out, devs, [lo, hi], ns
