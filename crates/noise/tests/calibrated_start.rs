//! `ImuErrors::with_calibrated_start`: the flicker and Gauss-Markov bias processes referenced to
//! their value at t = 0 (b(t) - b(0)), the same draws, every other term unchanged; and
//! `ImuErrors::with_calibration_window` (referenced to the mean over a window before t = 0): the
//! window-mean moments against quadrature, a constant offset, the same draws.

use nalgebra::Vector3;
use noise::closed_form::gauss_markov_window_mean_moments;
use noise::{AxisModel, BiasInstability, Flicker, GaussMarkov, ImuErrors, SensorModel, TriadModel};

/// No calibration.
fn raw_run(e: ImuErrors) -> ImuErrors {
    e
}

/// Calibrated over a 10 s window (seed and run as in `series`).
fn window_10s(e: ImuErrors) -> ImuErrors {
    e.with_calibration_window(10.0, 7, 3)
}

fn model(axis: AxisModel) -> SensorModel {
    SensorModel {
        name: "calibrated".into(),
        gyro: TriadModel {
            axes: [axis.clone(), axis.clone(), axis.clone()],
        },
        accel: TriadModel {
            axes: [axis.clone(), axis.clone(), axis],
        },
        ..SensorModel::default()
    }
}

/// The corrupted static series of run 3 of seed 7 at 100 Hz, after `prep` (a calibration or none).
fn series(model: &SensorModel, prep: fn(ImuErrors) -> ImuErrors, n: usize) -> Vec<[f64; 6]> {
    let mut e = prep(ImuErrors::new(model, 0.01, 7, 3));
    let zero = Vector3::zeros();
    (0..n as u64)
        .map(|k| {
            let (g, a) = e.corrupt(k, &zero, &zero);
            [g.x, g.y, g.z, a.x, a.y, a.z]
        })
        .collect()
}

#[test]
fn slow_bias_processes_start_at_zero_and_keep_their_increments() {
    // Default flicker band 0.1 s .. 1e5 s at 100 Hz: the components of T >= 10 s are held
    // (multirate), so both the every-sample and the held parts are referenced.
    let slow = noise::AxisModel::default()
        .with(BiasInstability::Flicker(Flicker::with_b(1e-3).unwrap()))
        .with(GaussMarkov::new(2e-3, 5.0).unwrap());
    let n = 3000;
    let raw = series(&model(slow.clone()), raw_run, n);
    let cal = series(&model(slow), ImuErrors::with_calibrated_start, n);
    // b(0) - b(0) is exactly 0 (the offset is summed in the generator's own order).
    assert_eq!(cal[0], [0.0; 6]);
    for c in 0..6 {
        let b0 = raw[0][c];
        assert!(b0 != 0.0);
        for k in 0..n {
            // The same draws: calibrated = raw - b(0), up to rounding (each process subtracts
            // its own b(0); values ~1e-3, so 1e-16 is ~1e-13 relative, a few hundred ulps).
            assert!(
                (cal[k][c] - (raw[k][c] - b0)).abs() <= 1e-16,
                "channel {c} sample {k}"
            );
        }
    }
}

#[test]
fn other_terms_are_bit_identical() {
    // White noise and a random walk (already zero at the start): the switch changes nothing.
    let fast = noise::AxisModel::default()
        .with(noise::WhiteNoise::new(1e-3).unwrap())
        .with(noise::RateRandomWalk::new(1e-4).unwrap())
        .with(noise::TurnOnBias::new(1e-2).unwrap())
        .with(BiasInstability::RandomWalk {
            stability: 1e-3,
            period_s: 4.0,
        });
    let m = model(fast);
    assert_eq!(
        series(&m, raw_run, 500),
        series(&m, ImuErrors::with_calibrated_start, 500)
    );
}

/// Composite Simpson rule of `f` over [0, w] with `n` (even) panels.
fn simpson(f: impl Fn(f64) -> f64, w: f64, n: usize) -> f64 {
    let h = w / n as f64;
    let mut s = f(0.0) + f(w);
    for i in 1..n {
        s += f(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

#[test]
fn window_mean_moments_match_quadrature() {
    // With m = (1/W) int_{-W}^0 b and Cov(b(s), b(u)) = e^{-|s-u|/T} (sigma = 1, docs/model.md §3):
    //   Cov(m, b(0)) = (1/W) int_0^W e^{-v/T} dv,
    //   Var(m) = (2/W^2) int_0^W (W - v) e^{-v/T} dv  (the double integral folded onto v = |s - u|).
    for &(tc, w) in &[
        (1e5, 10.0),
        (1e5, 60.0),
        (600.0, 10.0),
        (2.0, 1.0),
        (2.0, 0.98),
        (2.0, 1.02),
        (1.0, 10.0),
        (0.1, 60.0),
        (10.0, 3.0),
    ] {
        let (rho, vm, cond) = gauss_markov_window_mean_moments(tc, w);
        // Step W/n = 3e-4 s at most: Simpson's error ~ (h/T)^4 < 1e-13 even for T = 0.1 s.
        let n = 200_000;
        let cov = simpson(|v| (-v / tc).exp(), w, n) / w;
        let var = 2.0 * simpson(|v| (w - v) * (-v / tc).exp(), w, n) / (w * w);
        assert!(
            (rho / cov - 1.0).abs() < 1e-10,
            "T={tc} W={w}: rho {rho} vs {cov}"
        );
        assert!(
            (vm / var - 1.0).abs() < 1e-10,
            "T={tc} W={w}: Var(m) {vm} vs {var}"
        );
        // The conditional variance, where it does not cancel (u >= 0.01), from the quadrature;
        // below that only through its leading term 2u/3 (the series' own first term).
        let u = w / tc;
        let c_q = var - cov * cov;
        if u >= 0.01 {
            assert!(
                (cond / c_q - 1.0).abs() < 1e-7,
                "T={tc} W={w}: {cond} vs {c_q}"
            );
        } else {
            assert!(
                (cond / (2.0 * u / 3.0) - 1.0).abs() < u,
                "T={tc} W={w}: {cond}"
            );
        }
        assert!(cond > 0.0 && cond < vm);
    }
    // Continuity across the series switch at u = 0.5.
    let (a, b) = (
        gauss_markov_window_mean_moments(1.0, 0.5 - 1e-12),
        gauss_markov_window_mean_moments(1.0, 0.5 + 1e-12),
    );
    assert!((a.0 / b.0 - 1.0).abs() < 1e-10 && (a.1 / b.1 - 1.0).abs() < 1e-10);
    assert!((a.2 / b.2 - 1.0).abs() < 1e-10, "{a:?} {b:?}");
}

#[test]
fn window_calibration_subtracts_a_constant_and_keeps_the_draws() {
    let slow = noise::AxisModel::default()
        .with(noise::WhiteNoise::new(1e-3).unwrap())
        .with(BiasInstability::Flicker(Flicker::with_b(1e-3).unwrap()))
        .with(GaussMarkov::new(2e-3, 5.0).unwrap());
    let m = model(slow);
    let n = 2000;
    let raw = series(&m, raw_run, n);
    let cal = series(&m, window_10s, n);
    for c in 0..6 {
        // The offset b(0) - m is not zero (a draw), and the same at every sample (to rounding).
        let off = raw[0][c] - cal[0][c];
        assert!(off != 0.0);
        for k in 0..n {
            assert!(
                ((raw[k][c] - cal[k][c]) - off).abs() <= 1e-16,
                "channel {c} sample {k}"
            );
        }
    }
    // Deterministic: the same seed and run give the same window draws.
    assert_eq!(cal, series(&m, window_10s, n));
}
