"""imudrift.noise: allantools' generators follow allantools' formulas exactly (same seed, same
draws), and Kasdin's power-law noise has the Allan variance of its PSD (NIST SP 1065 Table 2:
white FM h0/(2 tau), flicker FM 2 ln2 h_-1, random-walk FM (2 pi^2 / 3) h_-2 tau)."""

import math

import numpy as np
import pytest

import imudrift
import imudrift.allantools as ia
from imudrift import noise


def test_white_brown_violet_are_allantools_formulas():
    # allantools noise.white: sqrt(b0 fs / 2) randn; brown: cumsum(white(b0 = 4 pi^2 b_-2, fs = 1/fs)) / fs;
    # violet: fs * diff(white(n + 1, b0 = b2 / (4 pi^2), fs = 1/fs)).
    n, fs, seed = 1000, 50.0, 3
    z = np.random.default_rng(seed).standard_normal(n + 1)
    np.testing.assert_array_equal(noise.white(n, 2.0, fs, seed), math.sqrt(2.0 * fs / 2.0) * z[:n])
    w = math.sqrt(4 * math.pi**2 * 0.5 / fs / 2.0) * z[:n]
    np.testing.assert_allclose(noise.brown(n, 0.5, fs, seed), np.cumsum(w) / fs, rtol=1e-15)
    v = math.sqrt(3.0 / (4 * math.pi**2) / fs / 2.0) * z
    np.testing.assert_allclose(noise.violet(n, 3.0, fs, seed), fs * np.diff(v), rtol=1e-15)
    np.testing.assert_array_equal(noise.pink(n, seed=seed), noise.pink(n, depth=20, seed=seed))


def test_kasdin_filter_recursion():
    # g_k = g_{k-1} (a/2 + k - 1)/k, a = -alpha: white is a unit impulse, random walk all ones,
    # flicker (a = 1) the binomial series of (1 - z^-1)^(-1/2): 1, 1/2, 3/8, 5/16.
    np.testing.assert_array_equal(noise.kasdin_filter(4, 0.0), [1, 0, 0, 0])
    np.testing.assert_array_equal(noise.kasdin_filter(4, -2.0), [1, 1, 1, 1])
    np.testing.assert_allclose(noise.kasdin_filter(4, -1.0), [1, 0.5, 0.375, 0.3125], rtol=1e-15)


SEEDS = 40
N = 1 << 15
FS = 10.0
M = [16, 64, 256]
# 4.5 standard errors of the mean over the seeds (the spread measured on the seeds themselves,
# t with 39 degrees of freedom): about 1e-4 two-sided per comparison, 12 comparisons.
Z = 4.5


def mean_avar(alpha, h):
    taus = [m / FS for m in M]
    avars = np.array(
        [ia.oadev(noise.power_law(N, alpha, h, FS, seed), rate=FS, data_type="freq", taus=taus)[1] ** 2
         for seed in range(SEEDS)]
    )
    return avars.mean(axis=0), avars.std(axis=0, ddof=1) / math.sqrt(SEEDS)


@pytest.mark.parametrize(
    "alpha,law",
    [
        (0.0, lambda h, tau: h / (2 * tau)),
        (-1.0, lambda h, tau: 2 * math.log(2) * h),
        # discrete random walk: q (2 m^2 + 1) / (6 m) with q = 2 pi^2 h tau0, i.e. the
        # continuous law times 1 + 1/(2 m^2) (0.2 % at m = 16)
        (-2.0, lambda h, tau: 2 * math.pi**2 / 3 * h * tau * (1 + 1 / (2 * (tau * FS) ** 2))),
    ],
)
def test_power_law_allan_variance_matches_its_psd(alpha, law):
    h = 3e-4
    mean, se = mean_avar(alpha, h)
    for m, a, s in zip(M, mean, se):
        want = law(h, m / FS)
        assert abs(a - want) < Z * s, (alpha, m, a, want, s)


def test_fractional_slope():
    # alpha = -1.5: AVAR ~ tau^(-alpha - 1) = tau^0.5 (SP 1065 Table 2's mu = -alpha - 1), so a
    # factor 4 in tau is a factor 2 in AVAR; ratio of the seed means, delta-method error.
    mean, se = mean_avar(-1.5, 1e-3)
    for i in range(len(M) - 1):
        r = mean[i + 1] / mean[i]
        r_se = r * math.hypot(se[i] / mean[i], se[i + 1] / mean[i + 1])
        assert abs(r - 2.0) < Z * r_se, (M[i], r, r_se)


def test_same_seed_same_samples_and_bad_arguments():
    np.testing.assert_array_equal(noise.power_law(500, -1.5, seed=9), noise.power_law(500, -1.5, seed=9))
    assert not np.array_equal(noise.power_law(500, -1.5, seed=9), noise.power_law(500, -1.5, seed=10))
    for bad in (dict(alpha=-5.0), dict(alpha=float("nan")), dict(h=-1.0), dict(fs=0.0), dict(num_points=0)):
        kw = dict(num_points=100, alpha=-1.0)
        kw.update(bad)
        with pytest.raises(imudrift.InvalidInput):
            noise.power_law(**kw)
