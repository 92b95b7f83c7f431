//! imudrift diagnose: where a sensor model and a measured log disagree, which effect is missing, and
//! what adding it is worth (docs/diagnose.md, "The diagnose workflow").
//!
//! Units: SI throughout (rad/s for gyro channels, m/s^2 for accelerometer channels, s for tau).
//! Frames: channels are body-frame axes (forward-right-down); the drift consequence linearises a
//! static, level IMU (nav frame NED).

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
