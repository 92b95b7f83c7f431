//! Time-domain laws over many runs: Gauss-Markov autocorrelation, random-walk variance growth, and
//! the growth of each stochastic term integrated once, twice and through tilt (docs/model.md §4),
//! each within chi-squared (or normal) bounds at a per-comparison false-positive rate of 1e-6.

mod common;

use common::*;
use noise::closed_form::{self as cf, Integration};
use noise::units::STANDARD_GRAVITY_MPS2;
use noise::{AxisModel, BiasInstability, Flicker, GaussMarkov, PowerLaw, Resonance};

const SEED: u64 = 77;
const RUNS: u64 = 4000;

/// Rectangle-rule integrals (Woodman eqs 2, 11): the k-fold integrals of each run's series at the end.
fn integrals(axis: &AxisModel, rate_hz: f64, n: usize) -> [Vec<f64>; 3] {
    let dt = 1.0 / rate_hz;
    let mut out: [Vec<f64>; 3] = Default::default();
    for run in 0..RUNS {
        let y = gyro_x_series(axis, rate_hz, n, SEED, run);
        let (mut i1, mut i2, mut i3) = (0.0, 0.0, 0.0);
        for v in y {
            i1 += v * dt;
            i2 += i1 * dt;
            i3 += i2 * dt;
        }
        out[0].push(i1);
        out[1].push(i2);
        out[2].push(i3);
    }
    out
}

fn check_growth(label: &str, axis: &AxisModel, law: impl Fn(f64, Integration) -> f64) {
    let (rate, n) = (100.0, 1000);
    let t = n as f64 / rate;
    let [once, twice, thrice] = integrals(axis, rate, n);
    assert_variance(
        &format!("{label} once"),
        &once,
        law(t, Integration::Once).powi(2),
    );
    assert_variance(
        &format!("{label} twice"),
        &twice,
        law(t, Integration::Twice).powi(2),
    );
    let tilt: Vec<f64> = thrice.iter().map(|x| STANDARD_GRAVITY_MPS2 * x).collect();
    assert_variance(
        &format!("{label} through tilt"),
        &tilt,
        law(t, Integration::Tilt).powi(2),
    );
}

#[test]
fn white_noise_grows_as_sqrt_t_t3_t5() {
    // Woodman eqs 5 and 18; g N t^{5/2}/sqrt(20) (docs/model.md §1.3). Discrete sums differ by O(1/n) = 0.15 %.
    let n = 1e-3;
    let axis = noise::AxisModel::default().with(noise::WhiteNoise::new(n).unwrap());
    check_growth("white noise", &axis, |t, how| {
        cf::white_noise_growth_std(n, t, how)
    });
}

/// White noise on the output register (after the filter) is an angle random walk of its own
/// density: the same laws as `white_noise` (its law source says so), generated at the output rate.
#[test]
fn output_white_noise_grows_as_white_noise() {
    let n = 1e-3;
    let term = noise::OutputWhiteNoise::new(n).unwrap();
    let temperature = noise::TemperatureProfile::default();
    let cx = noise::LawSourceContext {
        ideal: 0.0,
        others: [0.0; 2],
        dt_s: 0.01,
        temperature: &temperature,
        temperature_reference_c: 25.0,
    };
    assert_eq!(
        noise::ErrorTerm::law_sources(&term, &cx),
        vec![noise::LawSource::White(n)]
    );
    let axis = noise::AxisModel::default().with(term);
    check_growth("output white noise", &axis, |t, how| {
        cf::white_noise_growth_std(n, t, how)
    });
}

#[test]
fn random_walk_variance_grows_linearly_and_its_integrals_as_t3_t5_t7() {
    let k = 1e-4;
    let axis = noise::AxisModel::default().with(noise::RateRandomWalk::new(k).unwrap());
    // The walk itself: Var b_j = K^2 j dt (docs/model.md §3, b_{j+1} = b_j + K sqrt(dt) w).
    let rate = 100.0;
    for j in [10usize, 100, 999] {
        let at_j: Vec<f64> = (0..RUNS)
            .map(|run| gyro_x_series(&axis, rate, j + 1, SEED, run)[j])
            .collect();
        assert_variance(
            &format!("random walk at step {j}"),
            &at_j,
            k * k * j as f64 / rate,
        );
    }
    check_growth("rate random walk", &axis, |t, how| {
        cf::random_walk_growth_std(k, t, how)
    });
    // Woodman's bias random walk is the same law with K = BS/sqrt(T) (eq 9).
    let bs = BiasInstability::RandomWalk(noise::BiasRandomWalk::new(1e-3, 100.0).unwrap());
    let axis = noise::AxisModel::default().with(bs);
    let k = cf::woodman_bias_random_walk(1e-3, 100.0);
    check_growth("Woodman bias random walk", &axis, |t, how| {
        cf::random_walk_growth_std(k, t, how)
    });
}

#[test]
fn gauss_markov_autocorrelation_is_phi_to_the_lag() {
    let (rate, n) = (100.0, 1 << 20);
    let dt = 1.0 / rate;
    let tc = 20.0 * dt;
    let axis = noise::AxisModel::default().with(GaussMarkov::new(2e-3, tc).unwrap());
    let x = gyro_x_series(&axis, rate, n, SEED, 0);
    let phi = (-dt / tc).exp();
    let c0: f64 = x.iter().map(|v| v * v).sum::<f64>() / n as f64;
    let z = allan::chi2::normal_ppf(1.0 - ALPHA / 2.0);
    for lag in [1usize, 5, 20, 60] {
        let c: f64 = x.iter().zip(&x[lag..]).map(|(a, b)| a * b).sum::<f64>() / n as f64;
        let r = c / c0;
        let expected = phi.powi(lag as i32);
        // Bartlett's variance of the lag-j sample autocorrelation of an AR(1) process:
        // (1/n) [(1 + phi^2)(1 - phi^{2j})/(1 - phi^2) - 2 j phi^{2j}].
        let p2j = phi.powi(2 * lag as i32);
        let var = ((1.0 + phi * phi) * (1.0 - p2j) / (1.0 - phi * phi) - 2.0 * lag as f64 * p2j)
            / n as f64;
        assert!(
            (r - expected).abs() < z * var.sqrt(),
            "lag {lag}: autocorrelation {r:.5} vs phi^lag {expected:.5} (sd {:.5})",
            var.sqrt()
        );
    }
}

#[test]
fn gauss_markov_starts_stationary_and_integrates_as_its_law() {
    let (rate, sigma, tc) = (100.0, 2e-3, 2.0);
    let axis = noise::AxisModel::default().with(GaussMarkov::new(sigma, tc).unwrap());
    let first: Vec<f64> = (0..RUNS)
        .map(|run| gyro_x_series(&axis, rate, 1, SEED, run)[0])
        .collect();
    assert_variance("Gauss-Markov at t = 0", &first, sigma * sigma);
    // Once: exact 2 sigma^2 T [t - T(1 - e^{-t/T})] (docs/model.md §4); t = 10 s = 5 T; the rectangle
    // sum of samples differs from the integral by O(dt/T) = 0.5 %.
    let n = 1000;
    let [once, twice, thrice] = integrals(&axis, rate, n);
    let t = n as f64 / rate;
    let law = cf::gauss_markov_growth_std(sigma, tc, t, Integration::Once).unwrap();
    assert_variance("Gauss-Markov once", &once, law * law);
    // Twice and thrice: the exact forms (derived, closed_form::gauss_markov_kfold_variance).
    let exact = |k| cf::gauss_markov_kfold_variance(sigma, tc, t, k).unwrap();
    assert_variance("Gauss-Markov twice", &twice, exact(2));
    assert_variance("Gauss-Markov thrice", &thrice, exact(3));
}

/// A resonance (2 Hz, bandwidth 0.5 Hz) starts stationary and its k-fold rectangle sums over 10 s
/// have the variance of the exact quadratic form of the sampled process (weights c_j on sample j:
/// dt, (n - j) dt^2, (n - j)(n - j + 1)/2 dt^3), which the continuous closed form
/// (`cf::resonance_kfold_variance`) meets within the rectangle rule's O(k dt / t).
#[test]
fn resonance_starts_stationary_and_integrates_as_its_law() {
    let (rate, sigma, f0, bw) = (100.0, 2e-3, 2.0, 0.5);
    let axis = noise::AxisModel::default().with(Resonance::new(sigma, f0, bw).unwrap());
    let first: Vec<f64> = (0..RUNS)
        .map(|run| gyro_x_series(&axis, rate, 1, SEED + 5, run)[0])
        .collect();
    assert_variance("resonance at t = 0", &first, sigma * sigma);
    let n = 1000;
    let dt = 1.0 / rate;
    let t = n as f64 * dt;
    let [once, twice, thrice] = integrals(&axis, rate, n);
    let r: Vec<f64> = (0..n)
        .map(|j| cf::resonance_autocovariance(sigma, f0, bw, j as f64 * dt))
        .collect();
    let quadratic = |c: &dyn Fn(usize) -> f64| -> f64 {
        let c: Vec<f64> = (0..n).map(c).collect();
        let mut v = 0.0;
        for a in 0..n {
            for b in 0..n {
                v += c[a] * c[b] * r[a.abs_diff(b)];
            }
        }
        v
    };
    let exact = [
        quadratic(&|_| dt),
        quadratic(&|j| (n - j) as f64 * dt * dt),
        quadratic(&|j| ((n - j) * (n - j + 1)) as f64 / 2.0 * dt.powi(3)),
    ];
    for (k, (label, series)) in [("once", &once), ("twice", &twice), ("thrice", &thrice)]
        .into_iter()
        .enumerate()
    {
        assert_variance(&format!("resonance {label}"), series, exact[k]);
        let law = cf::resonance_kfold_variance(sigma, f0, bw, t, k as i32 + 1).unwrap();
        // Deterministic: the nested rectangle sums weight sample j by (n - j)(n - j + 1)/2 dt^3
        // where the integral has (t - t_j)^2 / 2, a relative difference of order k dt / t; 2 k dt / t
        // allows for it (measured 4e-5, 1.5e-3, 5.0e-3 against 2e-3, 4e-3, 6e-3).
        let allowance = 2.0 * (k + 1) as f64 * dt / t;
        assert!(
            (law / exact[k] - 1.0).abs() < allowance,
            "resonance {label}: closed form {law:.4e} vs sampled {:.4e}",
            exact[k]
        );
    }
}

#[test]
fn flicker_integrals_follow_the_component_sum() {
    // Band 1 s .. 1e4 s at 100 Hz: the sampled components differ from continuous ones by O(dt/T) <= 1 %
    // on the shortest, which carries little of the integrated variance over 10 s.
    let flicker = Flicker::new(1e-3, 1.0, 1e4, 2).unwrap();
    let axis = noise::AxisModel::default().with(BiasInstability::Flicker(flicker.clone()));
    let (rate, n) = (100.0, 1000);
    let t = n as f64 / rate;
    let [once, twice, thrice] = integrals(&axis, rate, n);
    for (k, data) in [(1, &once), (2, &twice), (3, &thrice)] {
        let law = flicker.integrated_variance(t, k).unwrap();
        assert_variance(&format!("flicker {k}-fold"), data, law);
    }
}

#[test]
fn power_law_integrals_follow_the_component_sum() {
    // As flicker's: band 1 s .. 1e4 s at 100 Hz, the growth law being the exact k-fold integrals
    // of its Gauss-Markov components (its law source), for a slope either side of flicker.
    for alpha in [-1.5, -0.5] {
        let p = PowerLaw::new(alpha, 1e-3, 1.0, 1.0, 1e4, 2).unwrap();
        let axis = noise::AxisModel::default().with(p.clone());
        let (rate, n) = (100.0, 1000);
        let t = n as f64 / rate;
        let [once, twice, thrice] = integrals(&axis, rate, n);
        for (k, data) in [(1, &once), (2, &twice), (3, &thrice)] {
            let law: f64 = p
                .components()
                .iter()
                .map(|&(tc, s)| cf::gauss_markov_kfold_variance(s, tc, t, k).unwrap())
                .sum();
            assert_variance(&format!("power law {alpha} {k}-fold"), data, law);
        }
    }
}

#[test]
fn sinusoid_integrals_follow_the_phase_average() {
    // Random phase per run; f = 0.05 Hz at 100 Hz so the rectangle rule is within ~0.2 % of the
    // integral (w dt = 3e-3); t = 10 s = half a period.
    let (a, f) = (1e-3, 0.05);
    let axis = noise::AxisModel::default().with(noise::Sinusoid::new(a, f, None).unwrap());
    check_growth("sinusoid", &axis, |t, how| {
        cf::sinusoid_growth_std(a, f, t, how)
    });
}

#[test]
fn quantization_integrals_follow_the_residual_law() {
    // Dithered by white noise of one LSB per sample of the integral; one and two samples, where the
    // quantisation part is ~15 % of the total, with 40000 runs (bounds about +-3.5 %). The white part
    // is summed exactly from the rectangle-rule weights of each sample: dt, dt^2 (n-k), dt^3 (n-k)(n-k+1)/2.
    let (rate, q): (f64, f64) = (100.0, 1e-5);
    let dt = 1.0 / rate;
    let lsb = q * 12f64.sqrt();
    let axis = noise::AxisModel::default()
        .with(noise::Quantization::new(q).unwrap())
        .with(noise::WhiteNoise::new(lsb / dt.sqrt()).unwrap());
    let sigma2 = (lsb / dt).powi(2);
    for n in [1usize, 2] {
        let (mut once, mut twice, mut thrice) = (Vec::new(), Vec::new(), Vec::new());
        for run in 0..40_000 {
            let y = gyro_x_series(&axis, rate, n, SEED, run);
            let (mut i1, mut i2, mut i3) = (0.0, 0.0, 0.0);
            for v in y {
                i1 += v * dt;
                i2 += i1 * dt;
                i3 += i2 * dt;
            }
            once.push(i1);
            twice.push(i2);
            thrice.push(i3);
        }
        let t = n as f64 * dt;
        let white = |w: &dyn Fn(f64) -> f64| {
            sigma2 * (0..n).map(|k| w((n - k) as f64).powi(2)).sum::<f64>()
        };
        let laws = [
            white(&|_| dt) + cf::quantization_growth_std(q, t, dt, Integration::Once).powi(2),
            white(&|m| dt * dt * m)
                + cf::quantization_growth_std(q, t, dt, Integration::Twice).powi(2),
            white(&|m| dt.powi(3) * m * (m + 1.0) / 2.0)
                + (cf::quantization_growth_std(q, t, dt, Integration::Tilt)
                    / STANDARD_GRAVITY_MPS2)
                    .powi(2),
        ];
        assert_variance(&format!("quantisation once, n {n}"), &once, laws[0]);
        assert_variance(&format!("quantisation twice, n {n}"), &twice, laws[1]);
        assert_variance(&format!("quantisation thrice, n {n}"), &thrice, laws[2]);
    }
}
