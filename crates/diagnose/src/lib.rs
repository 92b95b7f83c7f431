//! imudrift diagnose: where a sensor model and a measured log disagree, which effect is missing, and
//! what adding it is worth (docs/diagnose.md, "The diagnose workflow").
//!
//! Units: SI throughout (rad/s for gyro channels, m/s^2 for accelerometer channels, s for tau).
//! Frames: channels are body-frame axes (forward-right-down); the drift consequence linearises a
//! static, level IMU (nav frame NED).

// Per-tau and per-channel arrays are indexed in parallel; index loops say that more plainly.
#![allow(clippy::needless_range_loop)]

pub mod candidates;
pub mod detect;
pub mod drift;
pub mod drift_check;
pub mod fit;
pub mod gap;
mod measure;
pub mod model_terms;
pub mod protocol;
pub mod report;
pub mod simulate;
pub mod spectrum;
#[cfg(test)]
mod testutil;
mod trials;
pub mod workflow;

pub use report::{DiagnoseError, Diagnosis, LogInput, Settings};
pub use workflow::{diagnose, diagnose_with_progress};
