//! imudrift diagnose: where a sensor model and a measured log disagree, which effect is missing, and
//! what adding it is worth (docs/diagnose.md, "The diagnose workflow").
//!
//! Units: SI throughout (rad/s for gyro channels, m/s^2 for accelerometer channels, s for tau).
//! Frames: channels are body-frame axes (forward-right-down); the drift consequence linearises a
//! static, level IMU (nav frame NED).
//!
//! A small, fast step: a sensor model's log plan ([`log_plan::plan`], `imudrift plan`), how long
//! a static log must be to read each noise term off its Allan deviation to a relative
//! uncertainty. A tighter target needs a longer log, and a log ten times the required length
//! reads the term better than the target:
//!
//! ```
//! use allan::plan::PlanTerm;
//! use diagnose::log_plan::plan;
//!
//! let model = noise::SensorModel::from_toml_str(
//!     "name = \"gyro\"\n[gyro.all]\nwhite_noise = \"0.1 deg/sqrt(s)\"\n",
//!     "gyro.toml",
//! )
//! .unwrap();
//! let required = |target: f64| {
//!     let doc = plan(&model, 100.0, target, None).expect("white noise to plan for");
//!     // The three gyro axes, nothing for the accelerometers (they have no term).
//!     assert_eq!(doc.axes.len(), 3);
//!     assert!(doc.axes.iter().all(|a| a.sensor == "gyro"));
//!     doc.required_duration_s.unwrap()
//! };
//! let (loose, tight) = (required(0.10), required(0.05));
//! assert!(loose > 0.0 && tight > loose, "{loose} s, {tight} s");
//! let doc = plan(&model, 100.0, 0.10, Some(10.0 * loose)).unwrap();
//! let white = &doc.axes[0].terms[0];
//! assert_eq!(white.term, PlanTerm::WhiteNoise);
//! assert!(white.uncertainty_at_duration.unwrap() < 0.10);
//! ```

// Per-tau and per-channel arrays are indexed in parallel; index loops say that more plainly.
#![allow(clippy::needless_range_loop)]

pub mod alternatives;
pub mod bootstrap;
pub mod candidates;
pub mod detect;
pub mod document;
pub mod drift;
pub mod drift_check;
mod drift_fit;
pub mod drift_gap;
pub mod drift_joint;
pub mod effect_text;
pub mod error;
mod findings;
pub mod fit;
pub mod fitted_on;
pub mod gap;
mod held_out;
pub mod input;
pub mod log_plan;
mod measure;
pub mod model_terms;
pub mod observer;
pub mod protocol;
mod relevel;
pub mod report;
pub mod run_spread;
mod runs;
pub mod settings;
pub mod simulate;
pub mod spectrum;
mod stats;
#[cfg(test)]
mod testutil;
mod trials;
pub mod workflow;

pub use error::DiagnoseError;
pub use input::LogInput;
pub use observer::{Observer, RoundDone, Step};
pub use report::Diagnosis;
pub use settings::Settings;
pub use workflow::{diagnose, diagnose_observed, diagnose_runs, diagnose_until};
