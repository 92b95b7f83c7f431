//! The IEEE 952 fit recovers the parameters of generated logs within its stated uncertainty.
//!
//! Generators: the noise crate's discrete processes (docs/model.md §3, exact at the sample interval
//! dt): white rate noise N/sqrt(dt) w_k; rate random walk b_{k+1} = b_k + K sqrt(dt) w_k; flicker
//! (bias instability B) as a bank of Gauss–Markov processes with log-spaced correlation times and
//! variance B^2 ln(rho)/pi each; quantisation of the integrated output to the LSB Q sqrt(12);
//! plus a rate ramp R t_k.
//!
//! Tolerance: each recovered parameter must lie within 3.5 of its stated standard errors of the
//! truth (two-sided normal false-positive rate 4.7e-4 per parameter, about 3e-3 per test run
//! for the 6 parameters checked; the seeds are fixed, so a run is reproducible). The ignored
//! test `calibration_many_seeds` checks over 20 seeds that the RMS of (estimate - truth)/sigma
//! is within the chi-square band of a calibration to 25 % (run with --ignored; ~15 s).

use allan::fit::{fit_ieee952_terms, FitTerms};
use allan::{deviation, DataKind, Estimator, TauGrid};
use noise::process::{GaussMarkovBank, Quantizer, RandomWalk, WhiteNoiseSampler};
use rand::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;

const SIGMAS: f64 = 3.5;
const TRUTH_QNBK: Truth = Truth {
    q: 8.660_254_037_844_386e-6,
    n: 3e-4,
    b: 1e-4,
    k: 6e-6,
    r: 0.0,
};
const GOLDEN: f64 = 0.618_033_988_749_894_9;

struct Truth {
    q: f64,
    n: f64,
    b: f64,
    k: f64,
    r: f64,
}

fn generate(t: &Truth, dt: f64, len: usize, seed: u64) -> Vec<f64> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    // Flicker band 0.05 s .. 5e4 s, two Gauss-Markov processes per decade, each with variance
    // B^2 ln(rho) / pi (docs/model.md §3).
    let rho: f64 = 10f64.sqrt();
    let sd_each = (t.b * t.b * rho.ln() / std::f64::consts::PI).sqrt();
    let components: Vec<(f64, f64)> = (0..13).map(|i| (0.05 * rho.powi(i), sd_each)).collect();
    let mut flicker = GaussMarkovBank::new(&components, dt, &mut rng);
    let white = WhiteNoiseSampler::new(t.n, dt);
    let mut walk = RandomWalk::new(t.k, dt);
    let mut quantizer = (t.q > 0.0).then(|| Quantizer::new(t.q, &mut rng));
    let lsb = t.q * 12f64.sqrt();
    // The rounding error is white (the condition for the 3 Q^2/tau^2 law) only if the integral
    // moves about an LSB or more per sample between roundings: the white noise does that when
    // LSB ~ N sqrt(dt); a constant rate of (7 + golden ratio) LSB per sample breaks any
    // periodicity (the Allan variance ignores the constant).
    let sweep = (7.0 + GOLDEN) * lsb / dt;
    (0..len)
        .map(|k| {
            let rate = sweep
                + white.sample(&mut rng)
                + walk.next(&mut rng)
                + flicker.next(&mut rng)
                + t.r * (k as f64 * dt);
            match quantizer.as_mut() {
                Some(q) => q.apply(rate, dt),
                None => rate,
            }
        })
        .collect()
}

fn check(truth: &Truth, allowed: [bool; 5], dt: f64, len: usize, seed: u64) {
    let y = generate(truth, dt, len, seed);
    let pts = deviation(
        &y,
        DataKind::Rate,
        dt,
        Estimator::Overlapping,
        &TauGrid::Octave,
    );
    let fit = fit_ieee952_terms(&pts, FitTerms(allowed));
    let want = [truth.q, truth.n, truth.b, truth.k, truth.r];
    for (j, name) in allan::fit::TERM_NAMES.iter().enumerate() {
        if want[j] == 0.0 {
            continue;
        }
        let t = fit.terms()[j].unwrap_or_else(|| panic!("{name} not fitted: {fit:?}"));
        let z = (t.value - want[j]) / t.sigma;
        eprintln!(
            "{name}: {:.4e} +- {:.2e} (truth {:.4e}, z = {z:.2})",
            t.value, t.sigma, want[j]
        );
        assert!(
            z.abs() < SIGMAS,
            "{name}: {} +- {} vs {} (z = {z})",
            t.value,
            t.sigma,
            want[j]
        );
    }
}

#[test]
fn recovers_q_n_b_k() {
    // Each term dominates a range of the octave curve (100 Hz, 2^21 samples, tau 0.01..5243 s):
    // white up to ~20 s, flicker 20..370 s, random walk above; LSB = N sqrt(dt) = 3e-5 rad, so
    // Q = 3e-5/sqrt(12) adds 25 % to the variance at tau = dt.
    let truth = TRUTH_QNBK;
    check(&truth, [true, true, true, true, false], 0.01, 1 << 21, 1);
}

#[test]
fn recovers_n_and_ramp() {
    let truth = Truth {
        q: 0.0,
        n: 1e-3,
        b: 0.0,
        k: 0.0,
        r: 2e-7,
    };
    check(&truth, [false, true, false, false, true], 0.01, 1 << 20, 2);
}

/// Over 20 seeds the stated sigmas are calibrated to within 25 % (the RMS of (estimate -
/// truth)/sigma is 1.21 on this configuration, see `correlation_inflation` in fit.rs), and no term
/// goes missing. The 4 z of one seed are correlated; counting only the 20 seeds as independent
/// (the worst case), RMS^2 / s^2 follows chi2(20)/20, so with s in [0.8, 1.25] the RMS lies in
/// [0.8 sqrt(chi2_0.0005(20)/20), 1.25 sqrt(chi2_0.9995(20)/20)] except with probability 1e-3
/// per grid (two-sided false-positive rate).
#[test]
#[ignore = "long (~15 s): the calibration of the fit's sigmas over 20 seeds"]
fn calibration_many_seeds() {
    let truth = TRUTH_QNBK;
    let seeds = 10..30u64;
    let dof = seeds.clone().count() as f64;
    let lo = 0.8 * (allan::chi2::chi2_ppf(0.0005, dof) / dof).sqrt();
    let hi = 1.25 * (allan::chi2::chi2_ppf(0.9995, dof) / dof).sqrt();
    for grid in [TauGrid::Octave, TauGrid::PerDecade(5)] {
        let mut zz = Vec::new();
        let mut none = 0;
        for seed in seeds.clone() {
            let y = generate(&truth, 0.01, 1 << 21, seed);
            let pts = deviation(&y, DataKind::Rate, 0.01, Estimator::Overlapping, &grid);
            let fit = fit_ieee952_terms(&pts, FitTerms([true, true, true, true, false]));
            let want = [truth.q, truth.n, truth.b, truth.k];
            for (term, w) in fit.terms().iter().zip(want) {
                match term {
                    Some(t) => zz.push((t.value - w) / t.sigma),
                    None => none += 1,
                }
            }
        }
        let rms = stats::rms(&zz);
        assert_eq!(none, 0, "{grid:?}: {none} terms missing");
        assert!(
            (lo..=hi).contains(&rms),
            "{grid:?}: z rms {rms:.2} outside [{lo:.2}, {hi:.2}]"
        );
    }
}
