//! The real-sensor effects as generated: outliers (a Bernoulli process of exact size on the output),
//! the warm-up transient (fixed and per-run amplitude), the output filter (variance, correlation and
//! decimation of white noise through each kind), the step temperature profile through the bias,
//! the filter's alignment, and block-size invariance with every new term on.
//!
//! Statistical tolerances come from the sample size: stated sigmas of the normal approximation
//! (outlier counts 3 sigma, two-sided false-positive rate 2.7e-3 per comparison; transient means 4
//! sigma, 6.3e-5 per comparison) or chi-squared / normal quantiles at `common::ALPHA` = 1e-6 per
//! comparison. Seeds are fixed, so a pass is reproducible; the rates say how unlikely a failure of a
//! correct generator would be for another seed.

mod common;

use common::*;
use nalgebra::Vector3;
use noise::{
    AxisModel, FilterKind, ImuErrors, Outliers, OutputFilter, SensorModel, TemperatureProfile,
    WarmupTransient,
};

/// z such that a standard normal exceeds |z| with probability `ALPHA`.
fn z_alpha() -> f64 {
    -allan::chi2::normal_ppf(ALPHA / 2.0)
}

fn filter(kind: FilterKind, decimation: u32) -> OutputFilter {
    OutputFilter::new(kind, decimation).unwrap()
}

// --- outliers -------------------------------------------------------------------------------

/// Outliers alone: every sample is 0 or exactly +-size; the count is binomial(n, p) within 3 sigma,
/// the signs balanced within 3 sigma, and the counts in 512 blocks have the binomial dispersion
/// (index-of-dispersion chi-squared at ALPHA: independent samples, no clustering).
#[test]
fn outliers_are_a_bernoulli_process_of_exact_size() {
    let n = 1 << 20;
    for (rate_hz, per_hour, size, seed) in [
        (100.0, 3600.0, 0.02, 1u64), // p = 1e-2
        (1000.0, 7200.0, 0.5, 2),    // p = 2e-3
        (10.0, 36.0, 3e-3, 3),       // p = 1e-3
        (100.0, 360_000.0, 1e-4, 4), // p = 1: every sample
    ] {
        let dt = 1.0 / rate_hz;
        let o = Outliers::new(per_hour, size).unwrap();
        let p = o.probability(dt);
        let axis = noise::AxisModel::default().with(o);
        let y = gyro_x_series(&axis, rate_hz, n, seed, 0);
        let label = format!("{per_hour} /h at {rate_hz} Hz");
        assert!(
            y.iter().all(|&v| v == 0.0 || v == size || v == -size),
            "{label}: a value other than 0 or +-{size}"
        );
        let count = y.iter().filter(|&&v| v != 0.0).count() as f64;
        let positive = y.iter().filter(|&&v| v > 0.0).count() as f64;
        let (mean, sd) = (n as f64 * p, (n as f64 * p * (1.0 - p)).sqrt());
        assert!(
            (count - mean).abs() <= 3.0 * sd + 1e-9,
            "{label}: {count} outliers, expected {mean:.1} +- 3 x {sd:.1}"
        );
        if p < 1.0 {
            let half_sd = 0.5 * count.sqrt();
            assert!(
                (positive - 0.5 * count).abs() <= 3.0 * half_sd,
                "{label}: {positive} positive of {count}"
            );
            // Dispersion of the counts in B blocks of m samples: sum (c - m p)^2 / (m p (1 - p))
            // is chi-squared with B degrees of freedom for independent Bernoulli samples.
            let (b, m) = (512usize, n / 512);
            let var = m as f64 * p * (1.0 - p);
            let d: f64 = y
                .chunks(m)
                .map(|c| {
                    let k = c.iter().filter(|&&v| v != 0.0).count() as f64;
                    (k - m as f64 * p).powi(2) / var
                })
                .sum();
            let (lo, hi) = (
                allan::chi2::chi2_ppf(ALPHA / 2.0, b as f64),
                allan::chi2::chi2_ppf(1.0 - ALPHA / 2.0, b as f64),
            );
            assert!(
                d > lo && d < hi,
                "{label}: dispersion {d:.1} outside [{lo:.1}, {hi:.1}] ({b} blocks)"
            );
        }
    }
}

/// With white noise and a filter, outliers act on the output: the log with outliers minus the log
/// without (same seed, same streams) is 0 or +-size at each sample, not spread by the filter.
#[test]
fn outliers_are_added_after_the_filter() {
    let size = 0.05;
    let base = noise::AxisModel::default()
        .with(noise::WhiteNoise::new(1e-3).unwrap())
        .with(filter(FilterKind::Bartlett { taps: 12 }, 3));
    let with = base.clone().with(Outliers::new(360.0, size).unwrap());
    let n = 200_000;
    let a = gyro_x_series(&base, 100.0, n, 9, 2);
    let b = gyro_x_series(&with, 100.0, n, 9, 2);
    let mut hits = 0;
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        let d = y - x;
        if d != 0.0 {
            hits += 1;
            // (x + s) - x is s up to the rounding of the sum.
            assert!(
                (d.abs() - size).abs() <= 4.0 * f64::EPSILON * (x.abs() + size),
                "sample {i}: difference {d}"
            );
        }
    }
    // p = 360 / 3600 / 100 = 1e-3: 200 expected, 3 sigma = 42.4.
    assert!(
        (hits as f64 - 200.0).abs() <= 3.0 * (200.0f64 * 0.999).sqrt(),
        "{hits}"
    );
}

// --- warm-up transient ----------------------------------------------------------------------

/// A fixed amplitude: the mean over R runs at time t is A e^{-t/tau} within 4 standard errors of the
/// white noise (sigma / sqrt(R)), and each run carries exactly that curve.
#[test]
fn warmup_transient_decays_with_its_time_constant() {
    let (rate, n, runs) = (100.0f64, 301, 4000u64);
    let (amp, tau, nd) = (5e-4, 1.0, 1e-4); // white sigma = N / sqrt(dt) = 1e-3
    let sigma = nd / (1.0 / rate).sqrt();
    let noise_only = noise::AxisModel::default().with(noise::WhiteNoise::new(nd).unwrap());
    let axis = noise_only
        .clone()
        .with(WarmupTransient::new(amp, tau, false).unwrap());
    let ks = [0usize, 25, 50, 100, 200, 300];
    let mut sums = [0.0; 6];
    for run in 0..runs {
        let y = gyro_x_series(&axis, rate, n, 17, run);
        for (s, &k) in sums.iter_mut().zip(&ks) {
            *s += y[k];
        }
        if run < 20 {
            // The same run without the transient: the difference is the curve itself.
            let x = gyro_x_series(&noise_only, rate, n, 17, run);
            for k in 0..n {
                let want = amp * (-(k as f64) / rate / tau).exp();
                assert!(
                    ((y[k] - x[k]) - want).abs() <= 4.0 * f64::EPSILON * (x[k].abs() + amp),
                    "run {run} sample {k}: {} vs {want}",
                    y[k] - x[k]
                );
            }
        }
    }
    let se = sigma / (runs as f64).sqrt();
    for (s, &k) in sums.iter().zip(&ks) {
        let t = k as f64 / rate;
        let mean = s / runs as f64;
        let want = amp * (-t / tau).exp();
        assert!(
            (mean - want).abs() <= 4.0 * se,
            "t {t} s: mean {mean:.4e} vs A e^(-t/tau) {want:.4e} (4 standard errors {:.2e})",
            4.0 * se
        );
    }
}

/// `per_run`: each run's amplitude is drawn from N(0, A^2) (variance chi-squared at ALPHA over R runs)
/// and the curve keeps its shape; the other terms' draws are unchanged.
#[test]
fn per_run_warmup_amplitude_has_the_stated_variance() {
    let (rate, n, runs) = (100.0, 200, 3000u64);
    let (amp, tau) = (2e-3, 0.5);
    let noise_only = noise::AxisModel::default().with(noise::WhiteNoise::new(3e-4).unwrap());
    let axis = noise_only
        .clone()
        .with(WarmupTransient::new(amp, tau, true).unwrap());
    let mut draws = Vec::new();
    for run in 0..runs {
        let y = gyro_x_series(&axis, rate, n, 23, run);
        let x = gyro_x_series(&noise_only, rate, n, 23, run);
        let a = y[0] - x[0];
        for k in [50usize, 199] {
            let want = a * (-(k as f64) / rate / tau).exp();
            assert!(
                ((y[k] - x[k]) - want).abs()
                    <= 8.0 * f64::EPSILON * (x[0].abs() + x[k].abs() + a.abs()),
                "run {run} sample {k}"
            );
        }
        draws.push(a);
    }
    assert_variance("per-run warm-up amplitude", &draws, amp * amp);
}

// --- output filter --------------------------------------------------------------------------

/// Autocorrelation A_h(d) = sum_i h_i h_{i+d} of the impulse response.
fn acf(h: &[f64], d: usize) -> f64 {
    (0..h.len().saturating_sub(d))
        .map(|i| h[i] * h[i + d])
        .sum()
}

/// White noise of density N through each kind, with and without decimation: the output variance is
/// (N^2 / dt_i) sum h^2 (chi-squared at ALPHA with the Satterthwaite degrees of freedom
/// n / sum_k rho_k^2 of a correlated series), the lag-1 autocorrelation is A_h(D) / A_h(0) (normal at
/// ALPHA with Bartlett's standard error).
#[test]
fn white_noise_through_each_filter_has_the_exact_variance_and_correlation() {
    let rate = 100.0;
    let dt = 1.0 / rate;
    let nd = 2e-3;
    let n = 1 << 18;
    let cases = [
        filter(FilterKind::MovingAverage { taps: 8 }, 1),
        filter(FilterKind::Bartlett { taps: 9 }, 1),
        filter(FilterKind::LowPass1 { cutoff_hz: 5.0 }, 1),
        filter(FilterKind::LowPass2 { cutoff_hz: 10.0 }, 1),
        filter(FilterKind::MovingAverage { taps: 8 }, 4),
        filter(FilterKind::Bartlett { taps: 20 }, 8),
        filter(FilterKind::LowPass1 { cutoff_hz: 30.0 }, 3),
        filter(FilterKind::LowPass2 { cutoff_hz: 20.0 }, 5),
    ];
    for (i, f) in cases.iter().enumerate() {
        let h = f.impulse_response(dt);
        let d = f.decimation() as usize;
        let dt_i = f.internal_dt(dt);
        let var = nd * nd / dt_i * acf(&h, 0);
        // Output autocorrelation at lag k: A_h(kD) / A_h(0).
        let rho = |k: i64| acf(&h, k.unsigned_abs() as usize * d) / acf(&h, 0);
        let kmax = (h.len() / d) as i64 + 2;
        let axis = noise::AxisModel::default()
            .with(noise::WhiteNoise::new(nd).unwrap())
            .with(*f);
        let y = gyro_x_series(&axis, rate, n, 31, i as u64);
        let label = format!("{:?} decimation {d}", f.kind());

        // Variance (known zero mean).
        let s2: f64 = y.iter().map(|v| v * v).sum::<f64>();
        let v = s2 / n as f64;
        let sum_rho2: f64 = (-kmax..=kmax).map(|k| rho(k).powi(2)).sum();
        let edf = n as f64 / sum_rho2;
        let (lo, hi) = ratio_bounds(edf);
        let r = v / var;
        assert!(
            r > lo && r < hi,
            "{label}: variance {v:.4e} vs (N^2/dt_i) sum h^2 = {var:.4e}, ratio {r:.5} outside [{lo:.5}, {hi:.5}] (edf {edf:.0})"
        );

        // Lag-1 autocorrelation against Bartlett's formula:
        // n Var(r_1) = sum_k rho_{k+1}^2 + rho_{k-1} rho_{k+1} + 2 rho_1^2 rho_k^2 - 4 rho_1 rho_k rho_{k+1}.
        let r1 = y.windows(2).map(|w| w[0] * w[1]).sum::<f64>() / s2;
        let p1 = rho(1);
        let bartlett: f64 = (-kmax - 1..=kmax + 1)
            .map(|k| {
                rho(k + 1).powi(2) + rho(k - 1) * rho(k + 1) + 2.0 * p1 * p1 * rho(k).powi(2)
                    - 4.0 * p1 * rho(k) * rho(k + 1)
            })
            .sum();
        let se = (bartlett / n as f64).sqrt();
        assert!(
            (r1 - p1).abs() <= z_alpha() * se,
            "{label}: lag-1 autocorrelation {r1:.5} vs {p1:.5} (tolerance {:.5})",
            z_alpha() * se
        );
    }
    // The decimated moving average of 8 taps read every 4th sample overlaps its neighbour by half.
    let ma = filter(FilterKind::MovingAverage { taps: 8 }, 4);
    let h = ma.impulse_response(dt);
    assert!((acf(&h, 4) / acf(&h, 0) - 0.5).abs() < 1e-15);
}

/// The step temperature profile through `temperature_bias`, without and with a filter. The raw
/// samples behind output n are at t = n dt - j dt_i (j = 0 .. L-1): a moving average of L taps shows
/// the fraction of them at or after the step, so the step ramps over the filter's span (and, with
/// unit DC gain, the levels before and after are exact).
#[test]
fn temperature_step_drives_the_bias_through_the_filter() {
    let c = 1e-3; // rad/s per degC
    let (before, after) = (20.0, 30.0);
    let at = 5.0061; // off the 100 Hz and 400 Hz grids
    let rate = 100.0;
    let dt = 1.0 / rate;
    let model = |f: Option<OutputFilter>| SensorModel {
        temperature: TemperatureProfile::Step {
            before_c: before,
            after_c: after,
            at_s: at,
        },
        temperature_reference_c: 25.0,
        ..gyro_x_model({
            let axis = AxisModel::default().with(noise::TemperatureBias::new(c).unwrap());
            match f {
                Some(f) => axis.with(f),
                None => axis,
            }
        })
    };
    let n = 1000;
    let run = |m: &SensorModel| {
        let mut e = ImuErrors::new(m, dt, 5, 0);
        let mut out = vec![0.0; n];
        e.channels_mut()[0].fill_static(0, &Vector3::zeros(), &mut out);
        (e, out)
    };
    // No filter: the bias follows the profile sample by sample.
    let (e, y) = run(&model(None));
    let k_at = (at / dt).ceil() as usize; // first sample after the step: 501
    for (k, v) in y.iter().enumerate() {
        let t_c = if k < k_at { before } else { after };
        assert_eq!(*v, c * (t_c - 25.0), "sample {k}");
        assert_eq!(e.temperature_c(k as u64), t_c);
    }
    // Moving averages, without and with decimation.
    for (taps, d) in [(10u32, 1u32), (8, 4), (13, 3)] {
        let (_, y) = run(&model(Some(filter(FilterKind::MovingAverage { taps }, d))));
        let dt_i = dt / f64::from(d);
        let mut ramped = 0;
        for (k, v) in y.iter().enumerate() {
            let after_count = (0..taps)
                .filter(|&j| k as f64 * dt - f64::from(j) * dt_i >= at)
                .count() as f64;
            let frac = after_count / f64::from(taps);
            if frac > 0.0 && frac < 1.0 {
                ramped += 1;
            }
            let want = c * (before - 25.0) + c * (after - before) * frac;
            assert!(
                (v - want).abs() < 1e-15,
                "{taps} taps / {d}: sample {k}: {v} vs {want}"
            );
        }
        // The ramp lasts the filter's span: ceil(L / D) output samples, give or take one.
        let span = taps.div_ceil(d) as i32;
        assert!(
            (ramped - span).abs() <= 1,
            "{taps} taps / {d}: {ramped} ramped samples"
        );
    }
}

/// The ideal input is held over the raw samples of the output sample they belong to: an input
/// step at output k0 through a moving average of 8 taps read every 4th internal sample (raw samples
/// of outputs k-1 and k, four each, behind output k) shows half at k0 and all from k0 + 1 on.
#[test]
fn the_ideal_input_is_held_over_the_raw_samples_of_its_output() {
    let model = gyro_x_model(
        noise::AxisModel::default().with(filter(FilterKind::MovingAverage { taps: 8 }, 4)),
    );
    let mut e = ImuErrors::new(&model, 0.01, 1, 0);
    let k0 = 300;
    let a = Vector3::zeros();
    for k in 0..600u64 {
        let w = if k < k0 { 0.0 } else { 1.0 };
        let (g, _) = e.corrupt(k, &Vector3::new(w, 0.0, 0.0), &a);
        let want = match k.cmp(&k0) {
            std::cmp::Ordering::Less => 0.0,
            std::cmp::Ordering::Equal => 0.5,
            std::cmp::Ordering::Greater => 1.0,
        };
        assert!((g.x - want).abs() < 1e-15, "sample {k}: {} vs {want}", g.x);
    }
}

/// The filter's delay: a first-order low-pass lags a ramp by its group delay, sum i h_i dt_i
/// (`OutputFilter::delay_s`), once the transient of the start is past; a ramp keeps its slope.
#[test]
fn a_ramp_lags_by_the_group_delay() {
    let r = 1e-3; // rad/s^2
    let rate = 200.0;
    let dt = 1.0 / rate;
    for f in [
        filter(FilterKind::LowPass1 { cutoff_hz: 2.0 }, 1),
        filter(FilterKind::LowPass2 { cutoff_hz: 8.0 }, 4),
        filter(FilterKind::Bartlett { taps: 31 }, 2),
    ] {
        let axis = noise::AxisModel::default()
            .with(noise::RateRamp::new(r).unwrap())
            .with(f);
        let y = gyro_x_series(&axis, rate, 4000, 1, 0);
        let delay = f.delay_s(dt);
        for k in [0usize, 10, 1000, 3999] {
            let t = k as f64 * dt;
            // The pre-roll runs the ramp back to negative times, so the lag holds from t = 0 on
            // (to the rounding of t and of the response's 1e-15 normalisation).
            let want = r * (t - delay);
            assert!(
                (y[k] - want).abs() <= 1e-12 * r * (t + 1.0),
                "{:?}: sample {k}: {} vs r (t - delay) = {want} (delay {delay} s)",
                f.kind(),
                y[k]
            );
        }
    }
}

// --- block-size invariance ------------------------------------------------------------------

/// Every term, the three new ones included, on all six channels: filling in blocks of any size
/// (1, 7, 513, 1500 samples, mixed) gives the same bits as filling at once and as `corrupt` one
/// sample at a time; also with a decimation larger than the raw sub-block.
#[test]
fn any_block_size_gives_the_same_values_with_every_new_term() {
    let axis = |i: usize, f: OutputFilter| {
        noise::AxisModel::default()
            .with(noise::Quantization::new(1e-6).unwrap())
            .with(noise::WhiteNoise::new(1e-3).unwrap())
            .with(noise::BiasInstability::Flicker(
                noise::Flicker::with_b(1e-4).unwrap(),
            ))
            .with(noise::RateRandomWalk::new(1e-5).unwrap())
            .with(noise::GaussMarkov::new(2e-3, 0.3).unwrap())
            .with(noise::Sinusoid::new(1e-3, 1.3, None).unwrap())
            .with(noise::TemperatureBias::new(1e-4).unwrap())
            .with(noise::TurnOnBias::new(1e-2).unwrap())
            .with(Outliers::new(3600.0 * (i as f64 + 1.0), 0.1).unwrap())
            .with(WarmupTransient::new(5e-3, 2.0, i.is_multiple_of(2)).unwrap())
            .with(f)
    };
    let filters = [
        filter(FilterKind::MovingAverage { taps: 5 }, 1),
        filter(FilterKind::Bartlett { taps: 16 }, 8),
        filter(FilterKind::LowPass1 { cutoff_hz: 20.0 }, 2),
        filter(FilterKind::LowPass2 { cutoff_hz: 30.0 }, 3),
        filter(FilterKind::MovingAverage { taps: 6000 }, 4500),
        filter(FilterKind::LowPass2 { cutoff_hz: 1.0 }, 1),
    ];
    let mut model = SensorModel {
        name: "blocks".into(),
        temperature: TemperatureProfile::Step {
            before_c: 20.0,
            after_c: 35.0,
            at_s: 3.0,
        },
        ..SensorModel::default()
    };
    for (c, &f) in filters.iter().enumerate() {
        let a = axis(c, f);
        if c < 3 {
            model.gyro.axes[c] = a;
        } else {
            model.accel.axes[c - 3] = a;
        }
    }
    let dt = 0.01;
    ImuErrors::check_rate(&model, dt).unwrap();
    let n = 2000;
    let g = Vector3::new(0.0, 0.0, 0.0);
    let f = Vector3::new(0.0, 0.0, -9.80665);
    let fill = |blocks: &[usize]| {
        let mut e = ImuErrors::new(&model, dt, 77, 5);
        let mut out = vec![vec![0.0; n]; 6];
        let mut k = 0;
        let mut b = 0;
        while k < n {
            let len = blocks[b % blocks.len()].min(n - k);
            let [o0, o1, o2, o3, o4, o5] = &mut out[..] else {
                unreachable!()
            };
            e.fill_static(
                k as u64,
                &g,
                &f,
                [
                    &mut o0[k..k + len],
                    &mut o1[k..k + len],
                    &mut o2[k..k + len],
                    &mut o3[k..k + len],
                    &mut o4[k..k + len],
                    &mut o5[k..k + len],
                ],
            );
            k += len;
            b += 1;
        }
        out
    };
    let whole = fill(&[n]);
    for blocks in [&[1usize][..], &[7], &[513], &[1500, 1, 3]] {
        assert!(
            fill(blocks) == whole,
            "blocks of {blocks:?} changed the values"
        );
    }
    let mut e = ImuErrors::new(&model, dt, 77, 5);
    #[allow(clippy::needless_range_loop)] // k indexes six series at once
    for k in 0..n {
        let (gm, am) = e.corrupt(k as u64, &g, &f);
        for c in 0..3 {
            assert_eq!(
                gm[c].to_bits(),
                whole[c][k].to_bits(),
                "gyro {c} sample {k}"
            );
            assert_eq!(
                am[c].to_bits(),
                whole[c + 3][k].to_bits(),
                "accel {c} sample {k}"
            );
        }
    }
    // Every value is finite and the outliers and transients are there.
    assert!(whole.iter().flatten().all(|v| v.is_finite()));
}

// --- the rate check -------------------------------------------------------------------------

#[test]
fn a_cutoff_above_the_internal_nyquist_frequency_is_refused_by_axis() {
    let mut model = gyro_x_model(AxisModel::default());
    model.accel.axes[2].set_term(filter(FilterKind::LowPass2 { cutoff_hz: 250.0 }, 4));
    // 100 Hz x 4 = 400 Hz internal, Nyquist 200 Hz.
    let e = ImuErrors::check_rate(&model, 0.01).unwrap_err();
    assert_eq!(e.axis, "accel.z");
    let text = e.to_string();
    assert!(
        text.contains("accel.z.output_filter")
            && text.contains("400 Hz internal")
            && text.contains("Nyquist"),
        "{text}"
    );
    // At 200 Hz output (800 Hz internal) it fits.
    assert!(ImuErrors::check_rate(&model, 0.005).is_ok());
}
