//! What diagnose and the drift check tell their caller as they go (for a progress display): a
//! small trait whose methods do nothing unless a caller implements them.

use std::fmt;

/// A long step of the diagnose workflow (docs/diagnose.md, "The diagnose workflow").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// Step 0: the time-domain detectors (outliers, temperature, warm-up transient).
    Detect,
    /// Step 1: the measured Allan deviations.
    Measure,
    /// Step 2: the model's band, simulated.
    Band,
    /// Step 5: the corrected model re-simulated after a round of named effects.
    Resimulate { round: usize },
}

impl fmt::Display for Step {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Step::Detect => {
                f.write_str("looking for outliers, temperature effects and a warm-up transient")
            }
            Step::Measure => f.write_str("measuring the log's Allan deviations"),
            Step::Band => f.write_str("simulating the model's band"),
            Step::Resimulate { round } => {
                write!(f, "round {round}: re-simulating the corrected model")
            }
        }
    }
}

/// Told of progress by `diagnose_observed` and `drift_check::check_drift`. `()` observes
/// nothing.
pub trait Observer: Sync {
    /// diagnose is about to run `step` (called on the caller's thread).
    fn step(&self, _step: Step) {}
    /// A drift check has simulated `done` of its `total` logs (called from worker threads).
    fn simulated(&self, _done: usize, _total: usize) {}
}

impl Observer for () {}
