//! What can go wrong in diagnose: inputs the caller has to fix, a failed simulation, or a stop. An error
//! about a setting names the `Settings` field, never a front end's option.

use crate::simulate::SimError;

/// Errors of the workflow.
#[derive(Debug, thiserror::Error)]
pub enum DiagnoseError {
    #[error("the log has no gyro or accelerometer channel (expected columns gx gy gz ax ay az)")]
    NoChannels,
    #[error("channel {channel} has {got} samples, channel {first} has {expected}: all channels must have the same length")]
    Length {
        channel: &'static str,
        got: usize,
        first: &'static str,
        expected: usize,
    },
    #[error(
        "the log is too short for an Allan analysis ({samples} samples; at least 64 are needed)"
    )]
    TooShort { samples: usize },
    #[error("sample interval must be positive and finite, got {0} s")]
    BadInterval(f64),
    #[error("the temperature column has {got} samples, the log {expected}")]
    TemperatureLength { got: usize, expected: usize },
    /// The setting `tau_min_s` leaves no Allan point.
    #[error("no Allan point at or above tau_min_s = {tau_min_s} s")]
    NoTaus { tau_min_s: f64 },
    #[error("a log checked against the diagnosis must have its rate and length (those of a diagnosed run): got {samples} samples at {dt_s} s, expected {expected_samples} at {expected_dt_s} s")]
    CheckShape {
        samples: usize,
        dt_s: f64,
        expected_samples: usize,
        expected_dt_s: f64,
    },
    #[error("run {run} is sampled every {dt_s} s, run 1 every {first_dt_s} s: runs pooled in one diagnosis must share their rate")]
    RunRate {
        run: usize,
        dt_s: f64,
        first_dt_s: f64,
    },
    #[error("run {run} has the channels {channels}, run 1 has {first}: runs pooled in one diagnosis must have the same channels")]
    RunChannels {
        run: usize,
        channels: String,
        first: String,
    },
    /// The setting `seeds` is not above the number of runs pooled.
    #[error("seeds = {seeds} simulated logs for {runs} runs: a pooled band needs more simulated logs than runs")]
    SeedsForRuns { seeds: usize, runs: usize },
    #[error("no log to diagnose")]
    NoRuns,
    /// A simulation run failed.
    #[error("simulating the model failed in seed {run}: {message}")]
    Simulation { run: u64, message: String },
    /// The front end's stop flag was set (Ctrl-C): no diagnosis.
    #[error("stopped")]
    Stopped,
}

impl From<SimError> for DiagnoseError {
    fn from(e: SimError) -> DiagnoseError {
        match e {
            SimError::Run { run, message } => DiagnoseError::Simulation { run, message },
            SimError::Stopped => DiagnoseError::Stopped,
        }
    }
}
