//! The wide normal sampler (`noise::NormalStream`, every stochastic term's draws) against the
//! standard normal distribution: goodness of fit over the whole range, the tails the ziggurat
//! handles separately, and independence between draws (lags 1-16 cover the eight lanes: lag 8 is
//! the same lane's next output) and between streams.
//!
//! Each check is a test at a stated level; together they fail a correct sampler with probability
//! at most ALPHA (Bonferroni over the checks of each test function), so a failure is a defect,
//! not bad luck.

use allan::chi2::{chi2_ppf, normal_cdf, normal_ppf};
use noise::{ImuRng, NormalStream};
use rand::SeedableRng;

/// Family-wise false-failure probability of each test function.
const ALPHA: f64 = 1e-4;
const N: usize = 4_000_000;

fn draws(seed: u64, n: usize) -> Vec<f64> {
    let mut out = vec![0.0; n];
    NormalStream::new(ImuRng::seed_from_u64(seed)).fill(&mut out);
    out
}

/// P(X <= c) and P(X >= c) for X ~ Poisson(mean), by summing the probability mass in logs.
fn poisson_tails(mean: f64, c: usize) -> (f64, f64) {
    let mut log_p = -mean; // ln P(X = 0)
    let (mut below, mut at) = (0.0, 0.0);
    for k in 0..=c {
        if k > 0 {
            log_p += mean.ln() - (k as f64).ln();
        }
        below += log_p.exp();
        at = log_p.exp();
    }
    (below, 1.0 - below + at)
}

#[test]
fn chi_square_goodness_of_fit_and_tails() {
    // Three checks per seed, two seeds: each at level ALPHA / 6.
    let level = ALPHA / 6.0;
    for seed in [1u64, 2] {
        let x = draws(seed, N);
        // 200 equiprobable bins (Pearson's chi-square, k - 1 = 199 degrees of freedom; expected
        // count 20 000 per bin, far inside the asymptotic regime).
        let k = 200;
        let mut counts = vec![0usize; k];
        for &v in &x {
            let b = ((normal_cdf(v) * k as f64) as usize).min(k - 1);
            counts[b] += 1;
        }
        let e = N as f64 / k as f64;
        let stat: f64 = counts.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
        let limit = chi2_ppf(1.0 - level, (k - 1) as f64);
        assert!(
            stat < limit,
            "seed {seed}: chi-square {stat:.1} >= {limit:.1}"
        );
        // Beyond the ziggurat's base strip R = 3.6542 (its tail algorithm) and beyond 4.5: the
        // count is binomial(N, p), p < 3e-4, i.e. Poisson(N p) to relative order p; both
        // one-sided Poisson tail probabilities of the observed count must exceed level / 2.
        for r in [3.654152885361009, 4.5] {
            let mean = N as f64 * 2.0 * normal_cdf(-r);
            let count = x.iter().filter(|v| v.abs() > r).count();
            let (below, above) = poisson_tails(mean, count);
            assert!(
                below > level / 2.0 && above > level / 2.0,
                "seed {seed}: {count} beyond {r}, expected {mean:.1} (P(X <= c) = {below:.2e}, P(X >= c) = {above:.2e})"
            );
        }
    }
}

#[test]
fn draws_are_uncorrelated_across_lags_and_streams() {
    // Lags 1..=16 of one stream and lag 0 between two streams: 17 checks, each at ALPHA / 17.
    // Under independence the sample correlation of n pairs is N(0, 1/n) to first order.
    let z = normal_ppf(1.0 - ALPHA / 17.0 / 2.0);
    let x = draws(5, N);
    let corr = |a: &[f64], b: &[f64]| {
        let n = a.len() as f64;
        let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
        let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
        for (p, q) in a.iter().zip(b) {
            sab += (p - ma) * (q - mb);
            saa += (p - ma).powi(2);
            sbb += (q - mb).powi(2);
        }
        sab / (saa * sbb).sqrt()
    };
    for lag in 1..=16 {
        let r = corr(&x[..N - lag], &x[lag..]);
        let bound = z / ((N - lag) as f64).sqrt();
        assert!(r.abs() < bound, "lag {lag}: r = {r:.2e}, bound {bound:.2e}");
    }
    let y = draws(6, N);
    let r = corr(&x, &y);
    assert!(
        r.abs() < z / (N as f64).sqrt(),
        "streams 5 and 6: r = {r:.2e}"
    );
}
