//! White-noise logs of known N for the reading tests (readings_white.rs, null_terms.rs).
//!
//! Generator: the noise crate's white rate noise N/sqrt(dt) w_k (docs/model.md §3, exact at the
//! sample interval). N = 0.5833 deg/sqrt(h), the level of issue 24's log.

use allan::{analyse_rate, Analysis, Estimator, Options, TauGrid};
use noise::process::WhiteNoiseSampler;
use rand::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;

/// 0.5833 deg/sqrt(h) in rad/sqrt(s).
pub fn n_true() -> f64 {
    (0.5833f64 / 60.0).to_radians()
}

/// `len` samples of white rate noise of N = [`n_true`] every `dt` seconds from `seed`.
pub fn white_log(dt: f64, len: usize, seed: u64) -> Vec<f64> {
    let white = WhiteNoiseSampler::new(n_true(), dt);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    (0..len).map(|_| white.sample(&mut rng)).collect()
}

/// The command's analysis (overlapping deviation, octave grid) of a white-noise log of
/// `duration_s` at `rate_hz` from `seed`.
pub fn white_analysis(rate_hz: f64, duration_s: f64, seed: u64, opts: &Options) -> Analysis {
    let dt = 1.0 / rate_hz;
    let len = (duration_s * rate_hz).round() as usize;
    let data = white_log(dt, len, seed);
    analyse_rate(
        data,
        dt,
        Estimator::Overlapping,
        &TauGrid::Octave,
        opts,
        &|_| {},
    )
}
