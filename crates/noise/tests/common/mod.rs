//! Helpers shared by the statistical tests: generate one channel, estimate its overlapping Allan
//! variance with the allan crate, and bound estimates by chi-squared quantiles.
#![allow(dead_code)]

use allan::{DataKind, Estimator, TauGrid};
use nalgebra::Vector3;
use noise::{AxisModel, ImuErrors, SensorModel, TriadModel};

/// Per-comparison false-positive rate of every statistical check (two-sided). The tests below make
/// fewer than 200 comparisons, so the chance that any fails on a correct model is below 2e-4.
pub const ALPHA: f64 = 1e-6;

/// A sensor model file (the library parses text; reading the file is the caller's part).
pub fn read_model(path: &std::path::Path) -> SensorModel {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    SensorModel::from_text(&text, &path.display().to_string()).unwrap_or_else(|e| panic!("{e}"))
}

/// A shipped sensor config, `configs/sensors/NAME`.
pub fn shipped_model(name: &str) -> SensorModel {
    read_model(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../configs/sensors")
            .join(name),
    )
}

/// A sensor whose gyro x axis is `axis` and everything else perfect.
pub fn gyro_x_model(axis: AxisModel) -> SensorModel {
    SensorModel {
        name: "test".into(),
        gyro: TriadModel {
            axes: [axis, AxisModel::default(), AxisModel::default()],
        },
        ..SensorModel::default()
    }
}

/// `n` samples of gyro x (zero ideal rate) at `rate_hz`, run `run` of `seed`.
pub fn gyro_x_series(axis: &AxisModel, rate_hz: f64, n: usize, seed: u64, run: u64) -> Vec<f64> {
    let model = gyro_x_model(axis.clone());
    let mut errors = ImuErrors::new(&model, 1.0 / rate_hz, seed, run);
    let mut out = vec![0.0; n];
    errors.channels_mut()[0].fill_static(0, &Vector3::zeros(), &mut out);
    out
}

/// Overlapping Allan variance (NIST SP 1065 eq 11, allan crate) at averaging factors `ms`.
pub fn oavar(data: &[f64], dt_s: f64, ms: &[usize]) -> Vec<f64> {
    let opts = allan::Options {
        edf: allan::EdfMethod::None,
        ..allan::Options::default()
    };
    let points = allan::deviation_with(
        data,
        DataKind::Rate,
        dt_s,
        Estimator::Overlapping,
        &TauGrid::Explicit(ms.to_vec()),
        &opts,
    );
    assert_eq!(points.len(), ms.len(), "allan crate dropped a tau");
    points.iter().map(|p| p.dev * p.dev).collect()
}

/// Smallest Greenhall EDF of the overlapping Allan variance over the noise types `alphas`
/// (the conservative choice for a term that is not a single power law).
pub fn edf(alphas: &[i32], m: usize, n_rate: usize) -> f64 {
    alphas
        .iter()
        .map(|&a| {
            allan::edf::edf_for(
                Estimator::Overlapping,
                allan::EdfMethod::Greenhall,
                a,
                m,
                n_rate + 1,
                0,
            )
        })
        .fold(f64::INFINITY, f64::min)
}

/// Two-sided chi-squared acceptance interval of estimate/truth for `edf` degrees of freedom at
/// false-positive rate `ALPHA`: the estimated variance is truth·chi2(edf)/edf (SP 1065 §5.3).
pub fn ratio_bounds(edf: f64) -> (f64, f64) {
    (
        allan::chi2::chi2_ppf(ALPHA / 2.0, edf) / edf,
        allan::chi2::chi2_ppf(1.0 - ALPHA / 2.0, edf) / edf,
    )
}

/// Check the overlapping Allan variance of `data` against `truth(tau)` at each m.
pub fn assert_avar_matches(
    label: &str,
    data: &[f64],
    dt_s: f64,
    ms: &[usize],
    alphas: &[i32],
    truth: impl Fn(f64) -> f64,
) {
    assert_avar_matches_capped(label, data, dt_s, ms, alphas, f64::INFINITY, truth);
}

/// Time-bandwidth EDF of a narrow-band process (a resonance of half-power bandwidth `bw_hz`) over
/// `duration_s`: 2 B_s T with the statistical bandwidth of a single mode B_s = (pi/2) bw (Bendat &
/// Piersol, Random Data, 4th ed., §8.2.1 and eq. 8.52). Its differences stay correlated over 1/B_s,
/// which the power-law EDF does not know, so a resonance's estimates have at most this many.
pub fn narrowband_edf(bw_hz: f64, duration_s: f64) -> f64 {
    std::f64::consts::PI * bw_hz * duration_s
}

/// [`assert_avar_matches`] with the EDF at most `edf_cap` (see [`narrowband_edf`]).
pub fn assert_avar_matches_capped(
    label: &str,
    data: &[f64],
    dt_s: f64,
    ms: &[usize],
    alphas: &[i32],
    edf_cap: f64,
    truth: impl Fn(f64) -> f64,
) {
    let est = oavar(data, dt_s, ms);
    for (&m, &v) in ms.iter().zip(&est) {
        let tau = m as f64 * dt_s;
        let t = truth(tau);
        let e = edf(alphas, m, data.len()).min(edf_cap);
        let (lo, hi) = ratio_bounds(e);
        let r = v / t;
        assert!(
            r > lo && r < hi,
            "{label}: tau {tau} s (m {m}): avar {v:.4e} vs closed form {t:.4e}, ratio {r:.4} outside [{lo:.4}, {hi:.4}] (edf {e:.1})"
        );
    }
}

/// Variance check with known zero mean: sum(x^2)/R ~ sigma^2 chi2(R)/R.
pub fn assert_variance(label: &str, samples: &[f64], truth: f64) {
    let r = samples.len() as f64;
    let v = samples.iter().map(|x| x * x).sum::<f64>() / r;
    let (lo, hi) = ratio_bounds(r);
    let ratio = v / truth;
    assert!(
        ratio > lo && ratio < hi,
        "{label}: variance {v:.4e} vs law {truth:.4e}, ratio {ratio:.4} outside [{lo:.4}, {hi:.4}] ({r} runs)"
    );
}
