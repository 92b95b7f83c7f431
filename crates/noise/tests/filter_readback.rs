//! The output filter read back: generated logs through each filter kind, with decimation, at 10 Hz,
//! 100 Hz and 1 kHz have the overlapping Allan variance of the exact filtered closed form
//! (`noise::filter::FilteredAllan` via `AxisModel::allan_variance_sampled`), within chi-squared
//! bounds from Greenhall's EDF at a per-comparison false-positive rate of 1e-6 (`common::ALPHA`);
//! outliers read back as white noise of variance p size^2 per sample.

mod common;

use common::*;
use noise::{
    AxisModel, BiasInstability, FilterKind, Flicker, GaussMarkov, Outliers, OutputFilter,
    OutputWhiteNoise, Resonance,
};

const RATES_HZ: [f64; 3] = [10.0, 100.0, 1000.0];
/// 2^19 samples per series.
const N: usize = 1 << 19;
const SEED: u64 = 20_261_124;
/// Short taus, where the filter shapes the curve, and long ones, where it must not.
const MS: [usize; 7] = [1, 2, 3, 5, 10, 100, 1000];

fn check(label: &str, axis: &AxisModel, alphas: &[i32]) {
    for (i, &rate) in RATES_HZ.iter().enumerate() {
        let dt = 1.0 / rate;
        let data = gyro_x_series(axis, rate, N, SEED, i as u64);
        assert_avar_matches(
            &format!("{label} at {rate} Hz"),
            &data,
            dt,
            &MS,
            alphas,
            |tau| axis.allan_variance_sampled(tau, dt),
        );
    }
}

fn filtered(kind: FilterKind, decimation: u32) -> AxisModel {
    AxisModel::default()
        .with(noise::WhiteNoise::new(1e-3).unwrap())
        .with(BiasInstability::Flicker(Flicker::with_b(2e-4).unwrap()))
        .with(GaussMarkov::new(3e-3, 0.05).unwrap())
        .with(OutputFilter::new(kind, decimation).unwrap())
}

#[test]
fn moving_average_with_decimation_reads_back() {
    check(
        "moving average 6 / 4",
        &filtered(FilterKind::MovingAverage { taps: 6 }, 4),
        &[0],
    );
}

#[test]
fn bartlett_reads_back() {
    check(
        "bartlett 9",
        &filtered(FilterKind::Bartlett { taps: 9 }, 1),
        &[0],
    );
}

#[test]
fn second_order_lowpass_with_decimation_reads_back() {
    // Cutoff at a tenth of the internal rate of each output rate.
    for (i, &rate) in RATES_HZ.iter().enumerate() {
        let axis = filtered(
            FilterKind::LowPass2 {
                cutoff_hz: 0.1 * rate * 10.0,
            },
            10,
        );
        let dt = 1.0 / rate;
        let data = gyro_x_series(&axis, rate, N, SEED + 7, i as u64);
        assert_avar_matches(
            &format!("lowpass2 at {rate} Hz"),
            &data,
            dt,
            &MS,
            &[0],
            |tau| axis.allan_variance_sampled(tau, dt),
        );
    }
}

#[test]
fn first_order_lowpass_reads_back() {
    for (i, &rate) in RATES_HZ.iter().enumerate() {
        let axis = filtered(
            FilterKind::LowPass1 {
                cutoff_hz: 0.05 * rate,
            },
            1,
        );
        let dt = 1.0 / rate;
        let data = gyro_x_series(&axis, rate, N, SEED + 11, i as u64);
        assert_avar_matches(
            &format!("lowpass1 at {rate} Hz"),
            &data,
            dt,
            &MS,
            &[0],
            |tau| axis.allan_variance_sampled(tau, dt),
        );
    }
}

/// White noise on the output register behind a strong low-pass (the shape of a phone's log: the
/// sensing element's noise filtered to a cutoff of a hundredth of the output rate, a smaller white
/// noise after the filter): the Allan variance is the filtered white noise's plus N_out^2 / tau
/// (Hou 4.36, unfiltered), which dominates at the shortest taus; and the term alone, the filter's
/// place in the chain aside, reads back as plain white noise.
#[test]
fn output_white_noise_is_added_after_the_filter() {
    for (i, &rate) in RATES_HZ.iter().enumerate() {
        let axis = AxisModel::default()
            .with(noise::WhiteNoise::new(1e-3).unwrap())
            .with(OutputWhiteNoise::new(1e-4).unwrap())
            .with(
                OutputFilter::new(
                    FilterKind::LowPass1 {
                        cutoff_hz: 0.01 * rate,
                    },
                    1,
                )
                .unwrap(),
            );
        let dt = 1.0 / rate;
        // At one sample the term is most of the variance (the filter leaves ~ N^2 pi fc of the
        // element's noise; the term adds N_out^2 / dt): the test would fail if it were filtered.
        let mut without = axis.clone();
        without.remove(noise::Effect::OutputWhiteNoise);
        assert!(axis.allan_variance_sampled(dt, dt) > 2.0 * without.allan_variance_sampled(dt, dt));
        let data = gyro_x_series(&axis, rate, N, SEED + 13, i as u64);
        assert_avar_matches(
            &format!("lowpass1 + output white noise at {rate} Hz"),
            &data,
            dt,
            &MS,
            &[0],
            |tau| axis.allan_variance_sampled(tau, dt),
        );
    }
}

/// A resonance behind a Bartlett filter with decimation (the ADIS16405 gyro's shape: a broad peak at a
/// fifth of the output rate behind the sensor's averaging) reads back with the exact filtered form
/// (`FilteredAllan::resonance`).
#[test]
fn resonance_behind_a_filter_reads_back() {
    for (i, &rate) in RATES_HZ.iter().enumerate() {
        let dt = 1.0 / rate;
        // The resonance carries 9 times the white noise's variance, so the check is of it.
        let (f0, bw) = (0.2 * rate, 0.016 * rate);
        let axis = noise::AxisModel::default()
            .with(noise::WhiteNoise::new(1e-3).unwrap())
            .with(Resonance::new(3e-3 / dt.sqrt(), f0, bw).unwrap())
            .with(OutputFilter::new(FilterKind::Bartlett { taps: 3 }, 2).unwrap());
        let data = gyro_x_series(&axis, rate, N, SEED + 3, i as u64);
        assert_avar_matches_capped(
            &format!("filtered resonance at {rate} Hz"),
            &data,
            dt,
            &MS,
            &[0, -2],
            narrowband_edf(bw, N as f64 * dt),
            |tau| axis.allan_variance_sampled(tau, dt),
        );
    }
}

#[test]
fn outliers_read_back_as_white_noise() {
    // Outliers dominate (p size^2 = 40 x the white variance). Their Allan variance fluctuates with
    // their count K ~ Binomial(N, p), relative sd 1/sqrt(N p) at m = 1 and, the overlapping blocks
    // sharing outliers, no more than sqrt(3) times that at any m (the Allan difference weighs each
    // outlier in at most 2m of the N overlapping differences, each weight 1/m); bound 6 sd (a normal
    // tail of 2e-9), plus 6 sd of the chi-squared error of a white Allan estimate, relative sd at most
    // 1.5 sqrt(2m/N) for the overlapping estimator (SP 1065 Table 5 EDF for white FM).
    let (size, rate_per_hour) = (0.2, 36_000.0);
    for (i, &rate) in RATES_HZ.iter().enumerate() {
        let dt = 1.0 / rate;
        let axis = noise::AxisModel::default()
            .with(noise::WhiteNoise::new(1e-3).unwrap())
            .with(Outliers::new(rate_per_hour, size).unwrap());
        let p = axis
            .get::<noise::Outliers>()
            .copied()
            .unwrap()
            .probability(dt);
        let data = gyro_x_series(&axis, rate, N, SEED + 13, i as u64);
        let est = oavar(&data, dt, &MS);
        for (&m, &v) in MS.iter().zip(&est) {
            let tau = m as f64 * dt;
            let truth = axis.allan_variance_sampled(tau, dt);
            let outl = p * size * size / m as f64;
            let white = 1e-6 / tau;
            let tol = 6.0
                * (3f64.sqrt() * outl / (N as f64 * p).sqrt()
                    + 1.5 * (outl + white) * (2.0 * m as f64 / N as f64).sqrt());
            assert!(
                (v - truth).abs() <= tol,
                "outliers at {rate} Hz, m {m}: {v:.4e} vs {truth:.4e} (tolerance {tol:.2e})"
            );
        }
    }
}

#[test]
fn filtered_sinusoid_is_the_filter_applied_to_the_raw_sinusoid() {
    // The generator adds a filtered sinusoid at the output rate (gain |H| and phase arg H); it must
    // equal the filter applied to the sinusoid sampled at the internal rate, sum_j h_j x(t - j dt_i).
    for (kind, d) in [
        (FilterKind::Bartlett { taps: 13 }, 8),
        (FilterKind::LowPass2 { cutoff_hz: 30.0 }, 3),
    ] {
        let f = OutputFilter::new(kind, d).unwrap();
        let (a, hz, phase) = (0.02, 7.3, 0.4);
        let axis = noise::AxisModel::default()
            .with(noise::Sinusoid::new(a, hz, Some(phase)).unwrap())
            .with(f);
        let dt = 0.01;
        let data = gyro_x_series(&axis, 100.0, 300, SEED, 0);
        let h = f.impulse_response(dt);
        let dt_i = f.internal_dt(dt);
        for (n, &v) in data.iter().enumerate() {
            let t = n as f64 * dt;
            let direct: f64 = h
                .iter()
                .enumerate()
                .map(|(j, hj)| {
                    hj * a * (std::f64::consts::TAU * hz * (t - j as f64 * dt_i) + phase).sin()
                })
                .sum();
            assert!(
                (v - direct).abs() < 1e-12,
                "{kind:?} n {n}: {v} vs {direct}"
            );
        }
    }
}

/// The ARW / VRW an Allan curve's tau^-1/2 line shows: white noise before and after the filter in
/// quadrature (3-4-5); white noise alone is its density exactly; none without either.
#[test]
fn white_noise_density_adds_the_output_white_noise_in_quadrature() {
    let both = AxisModel::default()
        .with(noise::WhiteNoise::new(3e-4).unwrap())
        .with(OutputWhiteNoise::new(4e-4).unwrap());
    assert!((both.white_noise_density().unwrap() - 5e-4).abs() < 1e-18);
    let alone = AxisModel::default().with(noise::WhiteNoise::new(3e-4).unwrap());
    assert_eq!(alone.white_noise_density(), Some(3e-4));
    assert_eq!(AxisModel::default().white_noise_density(), None);
}
