//! Error models of inertial sensors: one gyro triad and one accelerometer triad, per axis.
//!
//! - Stochastic terms (IEEE Std 952 / 1293): quantisation, white noise (ARW / VRW), bias instability
//!   (flicker, or Woodman's bias random walk), rate random walk, rate ramp, first-order Gauss-Markov,
//!   sinusoid; each discretised exactly at the sample interval (docs/model.md §3; Gauss-Markov components
//!   with T >= 1000 dt exactly on a coarser grid and held, see [`process::GaussMarkovBank`]) and with its closed-form
//!   Allan variance and growth laws in [`closed_form`] (docs/model.md §2, §4).
//! - Deterministic and per-run terms: constant bias, turn-on bias drawn per run, scale-factor error,
//!   misalignment, temperature-dependent bias driven by a [`TemperatureProfile`].
//!
//! Units: SI inside (rad, rad/s, m/s^2, s, degC); configs take strings with explicit units
//! ([`units`]). Frames: body frame forward-right-down; a static level IMU reads specific force
//! (0, 0, -g). Randomness: the RNG is passed in or derived from (seed, run) with [`stream_rng`];
//! one named generator, [`ImuRng`] (Xoshiro256++), and one sub-stream per (run, channel, term).
//!
//! A model from sensor TOML text, and one run's readings of a static, level IMU: white rate noise
//! N = 0.1 deg/sqrt(s) sampled at 100 Hz has the per-sample standard deviation N / sqrt(dt) =
//! 1 deg/s; the accelerometers, with no term, read the ideal (0, 0, -g).
//!
//! ```
//! use noise::units::STANDARD_GRAVITY_MPS2;
//! use noise::{ImuErrors, Sensor, SensorModel, StaticLevel};
//!
//! let text = r#"
//! name = "example"
//! [gyro.all]
//! white_noise = "0.1 deg/sqrt(s)"
//! "#;
//! let model = SensorModel::from_toml_str(text, "example.toml").unwrap();
//! let (dt_s, n) = (0.01, 20_000);
//! let mut errors = ImuErrors::new(&model, dt_s, 7, 0); // seed 7, run 0
//! let level = StaticLevel::STANDARD;
//! let mut cols: [Vec<f64>; 6] = std::array::from_fn(|_| vec![0.0; n]);
//! errors.fill_static(
//!     0,
//!     &level.triad(Sensor::Gyro),
//!     &level.triad(Sensor::Accel),
//!     cols.each_mut().map(|c| c.as_mut_slice()),
//! );
//! // gx: zero mean, sd 1 deg/s (its estimate from 20 000 samples is within 0.5 %, so 3 % is
//! // six standard errors).
//! let gx = &cols[0];
//! let mean = gx.iter().sum::<f64>() / n as f64;
//! let sd = (gx.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64).sqrt();
//! assert!((sd / 1f64.to_radians() - 1.0).abs() < 0.03, "sd {sd} rad/s");
//! assert!(mean.abs() < 5.0 * sd / (n as f64).sqrt());
//! // az: gravity, untouched.
//! assert!(cols[5].iter().all(|&a| a == -STANDARD_GRAVITY_MPS2));
//! ```

mod block;
mod channel;
pub mod closed_form;
mod config;
mod discrete;
mod effect;
pub mod fft;
pub mod filter;
mod law_source;
pub mod limits;
mod model;
mod model_error;
pub mod model_notes;
pub mod noise_file;
pub mod process;
mod rng;
pub mod run_to_run;
mod static_level;
mod temperature;
pub mod terms;
pub mod text;
mod transpose4;
#[cfg(target_arch = "x86_64")]
#[doc(hidden)]
pub use transpose4::simd_blocks;
pub mod units;
mod wide;
mod ziggurat;

pub use channel::{Channel, ImuChannels, AXIS_NAMES};
pub use config::{is_noise_file_text, utf8_text, ConfigError, UnitStyle};
pub use effect::{Sensor, TermFilter, TermSelector, TermSelectorError};
pub use law_source::{LawSource, LawSourceContext};
pub use model::{AxisModel, SensorModel, TriadModel};
pub use model_error::ModelError;
pub use process::{ChannelErrors, ImuErrors};
pub use static_level::StaticLevel;
pub use temperature::TemperatureProfile;
pub use terms::bias_instability::{BiasInstability, BiasRandomWalk, Flicker};
pub use terms::constant_bias::ConstantBias;
pub use terms::gauss_markov::GaussMarkov;
pub use terms::misalignment::Misalignment;
pub use terms::outliers::Outliers;
pub use terms::output_filter::{FilterKind, OutputFilter, MAX_RESPONSE};
pub use terms::output_white_noise::OutputWhiteNoise;
pub use terms::power_law::PowerLaw;
pub use terms::quantization::Quantization;
pub use terms::rate_ramp::RateRamp;
pub use terms::rate_random_walk::RateRandomWalk;
pub use terms::resonance::Resonance;
pub use terms::scale_factor::ScaleFactor;
pub use terms::sinusoidal::Sinusoid;
pub use terms::slow_gauss_markov::SlowGaussMarkov;
pub use terms::temperature_bias::TemperatureBias;
pub use terms::turn_on_bias::TurnOnBias;
pub use terms::warmup_transient::WarmupTransient;
pub use terms::white_noise::WhiteNoise;
pub use terms::{Effect, ErrorTerm, Registered, Term, TermKind};
pub use wide::NormalStream;

use rand::SeedableRng;

pub use rng::ImuRng;

/// SplitMix64 finaliser (Steele, Lea & Flood 2014), used to hash (seed, stream) pairs.
fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn stream_key(seed: u64, stream: u64) -> u64 {
    splitmix64(splitmix64(seed) ^ splitmix64(stream.wrapping_add(0x632B_E59B_D9B4_E019)))
}

/// Independent stream for (seed, stream index) via SplitMix64 hashing; used for run i and sub-streams.
pub fn stream_rng(seed: u64, stream: u64) -> ImuRng {
    // seed_from_u64 expands the key into the 256-bit state with SplitMix64 (rand_xoshiro).
    ImuRng::seed_from_u64(stream_key(seed, stream))
}

/// A per-run stream for draws outside the sensor model (e.g. initial alignment errors), `index` chosen
/// by the caller. Disjoint from every term stream of `ImuErrors` by construction: term streams use
/// indices below 2^11 under the run's key, these use 2^32 + index.
pub fn extra_rng(seed: u64, run: u64, index: u32) -> ImuRng {
    stream_rng(stream_key(seed, run), (1u64 << 32) | u64::from(index))
}

/// The calibration-window stream of one term of one channel of one run
/// (`ImuErrors::with_calibration_window`): the term stream's index plus 2^33, so disjoint from the
/// term streams (below 2^11) and from `extra_rng` (2^32 + u32).
pub(crate) fn calibration_rng(seed: u64, run: u64, channel: u64, effect: Effect) -> ImuRng {
    stream_rng(
        stream_key(seed, run),
        (1u64 << 33) | (channel << 8) | effect.stream_index(),
    )
}

/// The run-to-run stream of one channel of one run (the draw that sets this run's levels of the
/// axis' `run_to_run` terms, `run_to_run::run_draw`): index 2^34 + channel, so disjoint from the
/// term streams (below 2^11), `extra_rng` (2^32 + u32) and the calibration streams (2^33 + ...).
/// No other stream is touched: a model without `run_to_run` gives the same values as before.
pub(crate) fn run_to_run_rng(seed: u64, run: u64, channel: u64) -> ImuRng {
    stream_rng(stream_key(seed, run), (1u64 << 34) | channel)
}

/// The block stream `component` of one term of one channel of one run (`crate::block`: the
/// draws of the term's component at the output rate behind a decimating FIR filter;
/// `Effect::OutputFilter`'s stream 0: the channel's summed remainder): 2^35 + component 2^16 +
/// the term stream's index, disjoint from the others above.
pub(crate) fn block_rng(
    seed: u64,
    run: u64,
    channel: u64,
    effect: Effect,
    component: usize,
) -> ImuRng {
    stream_rng(
        stream_key(seed, run),
        (1u64 << 35) | ((component as u64) << 16) | (channel << 8) | effect.stream_index(),
    )
}

/// The sub-stream of one term of one channel of one run.
pub(crate) fn term_rng(seed: u64, run: u64, channel: u64, effect: Effect) -> ImuRng {
    stream_rng(
        stream_key(seed, run),
        (channel << 8) | effect.stream_index(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::RngCore;

    #[test]
    fn streams_differ_and_repeat() {
        let a: Vec<u64> = (0..4).map(|_| stream_rng(1, 0).next_u64()).collect();
        assert!(a.windows(2).all(|w| w[0] == w[1]));
        let mut seen = std::collections::BTreeSet::new();
        for seed in 0..20 {
            for s in 0..20 {
                assert!(seen.insert(stream_rng(seed, s).next_u64()));
            }
        }
    }
}
