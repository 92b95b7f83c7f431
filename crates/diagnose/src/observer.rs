//! What diagnose and the drift check tell their caller as they go (for a progress display): a
//! small trait whose methods do nothing unless a caller implements them.

use noise::{Channel, Effect};
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

/// What a round of the workflow did, told once its re-simulation has decided it.
#[derive(Clone, Debug, PartialEq)]
pub struct RoundDone {
    pub round: usize,
    /// A round of the drift loop (else of the Allan loop).
    pub drift: bool,
    /// The channels whose changes were kept, each with the effects named on it this round.
    pub kept: Vec<(Channel, Vec<Effect>)>,
    /// The channels whose changes were undone (the re-simulated model was no closer).
    pub undone: Vec<Channel>,
}

impl fmt::Display for RoundDone {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let kind = if self.drift { "drift round" } else { "round" };
        write!(f, "{kind} {}:", self.round)?;
        if self.kept.is_empty() {
            f.write_str(" nothing kept")?;
        }
        for (c, effects) in &self.kept {
            let names: Vec<&str> = effects.iter().map(|e| e.name()).collect();
            write!(f, " {} named {};", c.name(), names.join(", "))?;
        }
        if !self.undone.is_empty() {
            let names: Vec<&str> = self.undone.iter().map(|c| c.name()).collect();
            write!(f, " undone on {}", names.join(", "))?;
        }
        Ok(())
    }
}

/// Told of progress by `diagnose_observed` and `drift_check::check_drift`. `()` observes
/// nothing.
pub trait Observer: Sync {
    /// diagnose is about to run `step` (called on the caller's thread).
    fn step(&self, _step: Step) {}
    /// A round of diagnose has been decided: what it named and kept (called on the caller's
    /// thread).
    fn round_done(&self, _done: &RoundDone) {}
    /// A drift check has simulated `done` of its `total` logs (called from worker threads).
    fn simulated(&self, _done: usize, _total: usize) {}
}

impl Observer for () {}
