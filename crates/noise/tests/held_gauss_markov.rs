//! The multi-rate Gauss-Markov components (`GaussMarkovBank::multirate`): a component of correlation
//! time T >= 1000 dt is advanced exactly every m = floor(T / (1000 dt)) samples and held in between.
//! Here: (1) the generator holds and steps as stated, with the exact coarse-grid increment variance;
//! (2) the exact Allan variance of the held process, averaged over the grid's phase (as the
//! overlapping estimator averages it), differs from the every-sample process's by less than
//! `HELD_AVAR_BOUND` relative at every averaging time, for every hold the rule produces.

mod common;

use common::*;
use noise::closed_form as cf;
use noise::process::{GaussMarkovBank, HOLD_FRACTION};
use noise::stream_rng;

/// Bound on |avar_held / avar_exact - 1| claimed in the crate docs (the worst case computed below is
/// printed by `cargo test -- --nocapture`; it is about M/(2T) with M = m dt the hold).
const HELD_AVAR_BOUND: f64 = 6e-4;

/// Exact Allan variance, averaged over the m phases of the hold grid, of y_i = x_{floor(i/m)} where
/// x_c is the stationary AR(1) sequence of variance sigma^2 and coefficient `phi_m` (the component
/// advanced every m samples), at averaging time n samples: (1/2) E[(mean W2 - mean W1)^2] for
/// adjacent windows W1 = [s, s+n), W2 = [s+n, s+2n). The difference is sum_c a_c x_c with
/// a_c = (|cell c ∩ W2| - |cell c ∩ W1|) / n, and E = sigma^2 sum_{c,c'} a_c a_c' phi_m^|c-c'|,
/// summed in O(cells) with the running r_c = phi_m (r_{c-1} + a_{c-1}).
fn held_avar(sigma: f64, phi_m: f64, m: u64, n: u64) -> f64 {
    let overlap = |lo: u64, hi: u64, a: u64, b: u64| hi.min(b).saturating_sub(lo.max(a)) as f64;
    let mut total = 0.0;
    for s in 0..m {
        let last = (s + 2 * n - 1) / m;
        let (mut r, mut prev, mut q) = (0.0, 0.0, 0.0);
        for c in 0..=last {
            let (lo, hi) = (c * m, (c + 1) * m);
            let a = (overlap(lo, hi, s + n, s + 2 * n) - overlap(lo, hi, s, s + n)) / n as f64;
            r = phi_m * (r + prev);
            q += a * (a + 2.0 * r);
            prev = a;
        }
        total += q;
    }
    sigma * sigma * total / (2.0 * m as f64)
}

/// The hold of the multirate rule for correlation time `tc` at interval `dt` (as in the crate).
fn hold(tc: f64, dt: f64) -> u64 {
    ((HOLD_FRACTION * tc / dt).floor() as u64).max(1)
}

#[test]
fn exact_allan_variance_of_the_held_component_is_within_the_bound() {
    let (sigma, dt): (f64, f64) = (1.0, 1.0);
    // The calculation itself, with m = 1, against the closed form of the sampled process.
    for (tc, n) in [(5.0, 3u64), (50.0, 40), (300.0, 1000)] {
        let phi = (-dt / tc).exp();
        let exact = held_avar(sigma, phi, 1, n);
        let closed = cf::gauss_markov_avar_sampled(sigma, tc, n as f64 * dt, dt);
        assert!(
            (exact / closed - 1.0).abs() < 1e-9,
            "T {tc}, n {n}: {exact} vs closed form {closed}"
        );
    }
    // Correlation times from the smallest held one (m = 2) to 1e6 samples (m = 1000), averaging
    // times from one sample to 10 T.
    let mut worst: (f64, f64, u64) = (0.0, 0.0, 0);
    for tc in [2000.0, 2999.0, 10_000.0, 1e5, 1e6] {
        let m = hold(tc, dt);
        assert!(m >= 2 && m as f64 * dt <= HOLD_FRACTION * tc);
        let mut n = 1u64;
        while n as f64 <= 10.0 * tc {
            let held = held_avar(sigma, (-(m as f64) * dt / tc).exp(), m, n);
            let every = held_avar(sigma, (-dt / tc).exp(), 1, n);
            let rel = (held / every - 1.0).abs();
            assert!(
                rel < HELD_AVAR_BOUND,
                "T {tc} dt, hold {m}, tau {n} dt: held avar {held:.6e} vs {every:.6e} ({rel:.2e})"
            );
            if rel > worst.0 {
                worst = (rel, tc, n);
            }
            n = (n * 3).max(n + 1);
        }
    }
    println!(
        "held Gauss-Markov: largest relative Allan-variance change {:.2e} (T {} dt, tau {} dt)",
        worst.0, worst.1, worst.2
    );
}

#[test]
fn held_component_steps_every_m_samples_with_the_exact_increment() {
    // T = 5000 dt: m = 5. The value is constant within each hold and its coarse-grid increments have
    // variance 2 sigma^2 (1 - phi^m) (stationary AR(1) at lag m, docs/model.md §3).
    let (sigma, tc, dt): (f64, f64, f64) = (2.0, 5000.0, 1.0);
    let m = hold(tc, dt) as usize;
    assert_eq!(m, 5);
    let mut rng = stream_rng(11, 0);
    let mut bank = GaussMarkovBank::multirate(&[(tc, sigma)], dt, &mut rng);
    let y: Vec<f64> = (0..m * 200_000).map(|_| bank.next(&mut rng)).collect();
    for hold_block in y.chunks(m) {
        assert!(hold_block.iter().all(|&v| v == hold_block[0]));
    }
    let steps: Vec<f64> = y
        .chunks(m)
        .zip(y.chunks(m).skip(1))
        .map(|(a, b)| b[0] - a[0])
        .collect();
    // Adjacent increments of an AR(1) are correlated (phi^m - 1 < 1e-3 relative); use every other
    // one, which are nearly independent (correlation O(1e-3), far inside the chi-squared bound).
    let independent: Vec<f64> = steps.iter().step_by(2).copied().collect();
    let phi_m = (-(m as f64) * dt / tc).exp();
    assert_variance(
        "held increments",
        &independent,
        2.0 * sigma * sigma * (1.0 - phi_m),
    );
    // Both constructors draw the stationary initial state first, from the same stream.
    let mut a = stream_rng(11, 1);
    let mut b = stream_rng(11, 1);
    let mut every = GaussMarkovBank::new(&[(tc, sigma)], dt, &mut a);
    let mut held = GaussMarkovBank::multirate(&[(tc, sigma)], dt, &mut b);
    assert_eq!(every.next(&mut a), held.next(&mut b), "same initial state");
}
