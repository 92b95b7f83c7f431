"""allantools' noise generators, with a seed: ``white``, ``brown``, ``violet``, ``pink`` and the
power-law family of Kasdin & Walter, for tests and teaching beside ``imudrift.allantools``.

Each returns a numpy array of ``num_points`` samples of a fractional-frequency-like series (or a
rate: rad/s, m/s^2) whose one-sided power spectral density is the level given, in allantools'
(and NIST SP 1065's) convention ``S_y(f) = h_alpha f^alpha``:

- ``white(num_points, b0, fs)``: ``S = b0`` up to ``fs/2``; the samples are ``sqrt(b0 fs / 2)``
  times standard normals (allantools ``noise.white``). Allan variance ``b0 / (2 tau)``.
- ``brown(num_points, b_minus2, fs)``: the cumulative sum of white noise of level
  ``4 pi^2 b_minus2`` drawn at ``1/fs``, times ``1/fs`` (allantools ``noise.brown``).
- ``violet(num_points, b2, fs)``: ``fs`` times the difference of white noise of level
  ``b2 / (4 pi^2)`` drawn at ``1/fs`` (allantools ``noise.violet``).
- ``power_law(num_points, alpha, h, fs)``: ``S = h f^alpha`` for any real ``alpha`` in
  [-4, 4] (0 white, -1 flicker, -2 random walk, -1.5 between), by Kasdin & Walter's filter
  (Kasdin, Proc. IEEE 83(5), 1995, eqs 39-41; allantools ``noise_kasdin``): impulse response
  ``g_0 = 1, g_k = g_{k-1} (a/2 + k - 1) / k`` with ``a = -alpha``, convolved (FFT, zero-padded
  to at least 2n) with white noise of variance ``Q_d = h / (2 tau0^(1+alpha) (2 pi)^alpha)``,
  which gives the one-sided PSD ``2 Q_d tau0^(1-a) / (2 pi f)^a = h f^alpha`` at frequencies
  well below ``fs/2``. The filter's memory is the whole record (n taps): exact for the
  record's length, no low-frequency cut-off inside it.
- ``pink(num_points, depth, b_minus1, fs)``: ``power_law`` with ``alpha = -1`` (flicker,
  Allan variance ``2 ln 2 b_minus1`` for tau well inside the record). allantools' ``pink`` is
  Voss's algorithm with ``depth`` octaves and no level; ``depth`` is accepted so calls written
  for allantools run, and not used (Kasdin's filter has the record's length of memory).

``seed`` (an int, or None for fresh entropy) seeds numpy's PCG64 generator
(``numpy.random.default_rng``): the same seed gives the same samples. allantools draws from
numpy's global generator instead.
"""

import math

import numpy as np

from ._imudrift import InvalidInput
from . import _args

__all__ = ["white", "brown", "violet", "pink", "power_law"]

# Kasdin's filter is defined for any real exponent; outside this range the series are dominated
# by their first or last samples and no Allan-family estimator converges on them.
ALPHA_RANGE = (-4.0, 4.0)


def _count(num_points):
    n = _args.integer("num_points", num_points)
    if n < 1 or n > 1 << 31:
        raise InvalidInput(f"num_points: expected 1 to 2^31 samples, got {n}")
    return n


def _level(name, value):
    v = _args.number(name, value)
    if not (math.isfinite(v) and 0.0 <= v < 1e100):
        raise InvalidInput(f"{name}: expected a finite level >= 0 and below 1e100, got {v}")
    return v


def _rate(fs):
    v = _args.number("fs", fs)
    if not (math.isfinite(v) and 1e-6 <= v <= 1e9):
        raise InvalidInput(f"fs: expected a sample rate from 1e-6 to 1e9 Hz, got {v}")
    return v


def _rng(seed):
    if seed is None:
        return np.random.default_rng()
    return np.random.default_rng(_args.integer("seed", seed))


def white(num_points=1024, b0=1.0, fs=1.0, seed=None):
    """White noise of one-sided PSD ``b0`` (allantools ``noise.white``)."""
    n, b0, fs = _count(num_points), _level("b0", b0), _rate(fs)
    return math.sqrt(b0 * fs / 2.0) * _rng(seed).standard_normal(n)


def brown(num_points=1024, b_minus2=1.0, fs=1.0, seed=None):
    """Brownian (random-walk) noise (allantools ``noise.brown``)."""
    fs = _rate(fs)
    w = white(num_points, b0=_level("b_minus2", b_minus2) * 4.0 * math.pi**2, fs=1.0 / fs, seed=seed)
    return np.cumsum(w) / fs


def violet(num_points=1024, b2=1.0, fs=1.0, seed=None):
    """Violet (differenced white) noise (allantools ``noise.violet``)."""
    n, fs = _count(num_points), _rate(fs)
    w = white(n + 1, b0=_level("b2", b2) / (4.0 * math.pi**2), fs=1.0 / fs, seed=seed)
    return fs * np.diff(w)


def kasdin_filter(num_points, alpha):
    """Kasdin & Walter's impulse response for ``S ~ f^alpha``: ``g_0 = 1``,
    ``g_k = g_{k-1} (a/2 + k - 1) / k``, ``a = -alpha`` (Kasdin 1995, eq 41)."""
    n = _count(num_points)
    a = -float(alpha)
    k = np.arange(1, n, dtype=np.float64)
    g = np.empty(n)
    g[0] = 1.0
    g[1:] = np.cumprod((a / 2.0 + k - 1.0) / k)
    return g


def power_law(num_points, alpha, h=1.0, fs=1.0, seed=None):
    """Power-law noise of one-sided PSD ``h f^alpha`` by Kasdin & Walter's filter (see the
    module docs for the filter, its memory and the variance of the white noise it filters)."""
    n = _count(num_points)
    alpha = _args.number("alpha", alpha)
    if not (ALPHA_RANGE[0] <= alpha <= ALPHA_RANGE[1]):
        raise InvalidInput(
            f"alpha: expected an exponent from {ALPHA_RANGE[0]:g} to {ALPHA_RANGE[1]:g} "
            f"(S(f) = h f^alpha: 0 white, -1 flicker, -2 random walk), got {alpha}"
        )
    h, fs = _level("h", h), _rate(fs)
    tau0 = 1.0 / fs
    q_d = h / (2.0 * tau0 ** (1.0 + alpha) * (2.0 * math.pi) ** alpha)
    w = math.sqrt(q_d) * _rng(seed).standard_normal(n)
    size = 1 << (2 * n - 1).bit_length()  # a power of two >= 2n: the circular convolution is linear
    x = np.fft.irfft(np.fft.rfft(kasdin_filter(n, alpha), size) * np.fft.rfft(w, size), size)
    return x[:n]


def pink(num_points=1024, depth=80, b_minus1=1.0, fs=1.0, seed=None):
    """Flicker (1/f) noise of one-sided PSD ``b_minus1 / f``: :func:`power_law` with alpha -1.
    ``depth`` (allantools' Voss octaves) is accepted and not used."""
    del depth
    return power_law(num_points, -1.0, b_minus1, fs, seed)
