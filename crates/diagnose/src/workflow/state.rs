//! What the workflow's steps share: the [`Context`] every step reads and none changes (the
//! measurement, the simulation's setup, the original model's simulation, the settings, the
//! observer and the stop flag), the state the loop carries and its steps change ([`LoopState`]:
//! the two models, the current bands, each channel's findings, the rounds kept) and the current
//! model's drift ([`Drift`]), which a step returns when it simulated it afresh.

use crate::detect::Preprocessed;
use crate::drift::SegmentDrift;
use crate::drift_gap::DriftGap;
use crate::error::DiagnoseError;
use crate::fit::predicted_ln_adev;
use crate::gap::{gap, Band, Gap};
use crate::input::LogInput;
use crate::measure::{restrict, Measured};
use crate::model_terms::restore_term;
use crate::observer::Observer;
use crate::protocol::SegmentErrors;
use crate::report::{CandidateRecord, FoundEffect};
use crate::settings::Settings;
use crate::simulate::{simulate_runs, RunPlan, SimResult, SimSetup};
use crate::spectrum::SpectralPeak;
use noise::{Channel, Effect, ImuChannels, SensorModel, Term};
use std::sync::atomic::{AtomicBool, Ordering};

/// What every step reads: fixed once steps 0-2 are done.
pub(super) struct Context<'a> {
    pub(super) settings: &'a Settings,
    pub(super) observer: &'a dyn Observer,
    /// The front end's stop flag (Ctrl-C), checked between steps and by every simulation.
    pub(super) stop: &'a AtomicBool,
    /// The corrected logs (runs) the Allan steps see, and step 0's findings on each.
    pub(super) logs: Vec<LogInput<'a>>,
    pub(super) pre: &'a [Preprocessed],
    pub(super) samples: Vec<usize>,
    /// Averaging factors of the common tau grid, and each channel's measurement on it (pooled).
    pub(super) grid_m: Vec<usize>,
    pub(super) measured: ImuChannels<Option<Measured>>,
    /// Each run's own measurement, corrected and raw (several runs only).
    pub(super) run_measured: Vec<ImuChannels<Option<Measured>>>,
    pub(super) run_raw: Vec<ImuChannels<Option<Measured>>>,
    /// Least-squares slope of each corrected channel against time (the rate-ramp level, see `trials`).
    pub(super) ramp_slope: ImuChannels<f64>,
    /// The broad spectral peak and the spectral lines of each channel (over all runs' segments).
    pub(super) peaks: ImuChannels<Option<SpectralPeak>>,
    pub(super) lines: ImuChannels<Vec<f64>>,
    pub(super) setup: SimSetup<'a>,
    pub(super) plan: RunPlan,
    /// The original model's simulation (its bands and drift).
    pub(super) sim0: SimResult,
    /// The runs' segment errors under the drift protocol (empty without one).
    pub(super) drift_measured: Vec<SegmentErrors>,
}

/// What the loop carries from step to step.
pub(super) struct LoopState {
    pub(super) models: Models,
    /// The current model's band per channel.
    pub(super) bands: Bands,
    pub(super) channels: ImuChannels<ChannelState>,
    /// The last round kept.
    pub(super) rounds: usize,
}

/// The model simulated (step 0's terms left out: their effects are removed from the log) and the
/// corrected model reported (with them).
pub(super) struct Models {
    pub(super) sim: SensorModel,
    pub(super) out: SensorModel,
}

/// A model's band per channel: pooled over the runs, and of one log at each run length.
pub(super) struct Bands {
    pub(super) pooled: ImuChannels<Option<Band>>,
    pub(super) per_length: Vec<(usize, ImuChannels<Option<Band>>)>,
}

/// A model's drift: the segment drifts per horizon, and the simulated logs' segment errors under
/// the drift protocol (`SimResult::protocol_errors`).
pub(super) struct Drift {
    pub(super) segments: Vec<SegmentDrift>,
    pub(super) protocol: Vec<Vec<Vec<SegmentErrors>>>,
}

impl Drift {
    /// The drift of a simulation.
    pub(super) fn of(sim: SimResult) -> Drift {
        Drift {
            segments: sim.drift,
            protocol: sim.protocol_errors,
        }
    }
}

/// What the workflow knows about one channel so far.
#[derive(Default)]
pub(super) struct ChannelState {
    /// The gap of the raw log (before step 0's corrections) against the original model's band.
    pub(super) initial: Option<(Band, Gap)>,
    /// The effects named so far, in the order found.
    pub(super) effects: Vec<FoundEffect>,
    /// Every candidate weighed, every round.
    pub(super) records: Vec<CandidateRecord>,
    /// Nothing more to name: no disagreement left, no candidate good enough, or a round rejected.
    pub(super) done: bool,
    /// The structures the drift loop's last weighing of this channel could not tell from the one
    /// kept (`alternatives`).
    pub(super) alternatives: Vec<crate::alternatives::Alternative>,
}

impl ChannelState {
    /// Where the effects named in `round` begin (they are the last ones found).
    pub(super) fn first_in(&self, round: usize) -> usize {
        self.effects
            .iter()
            .position(|e| e.round == round)
            .unwrap_or(self.effects.len())
    }

    /// Undo the effects named in `round` from position `first` on: each becomes a record of a
    /// candidate rejected in that round.
    pub(super) fn reject_from(&mut self, round: usize, first: usize) {
        let rejected: Vec<CandidateRecord> = self
            .effects
            .drain(first..)
            .map(|e| crate::findings::rejected_record(round, e))
            .collect();
        self.records.extend(rejected);
    }
}

impl Models {
    /// Set channel `c`'s `effect` to `previous` in both models (None: remove it), e.g. to undo a change.
    pub(super) fn restore(&mut self, c: Channel, effect: Effect, previous: Option<Term>) {
        for model in [&mut self.sim, &mut self.out] {
            restore_term(model, c, effect, previous.clone());
        }
    }
}

impl Context<'_> {
    /// [`DiagnoseError::Stopped`] once the front end has set the stop flag.
    pub(super) fn check_stop(&self) -> Result<(), DiagnoseError> {
        if self.stop.load(Ordering::Relaxed) {
            Err(DiagnoseError::Stopped)
        } else {
            Ok(())
        }
    }

    /// Step 3 for channel `c` against `bands`.
    pub(super) fn gap(&self, c: Channel, bands: &ImuChannels<Option<Band>>) -> Option<(Band, Gap)> {
        gap_of(self.measured[c].as_ref(), bands[c].as_ref())
    }

    /// `model` simulated on the whole plan (every run's length), as the band is.
    pub(super) fn simulate_whole(&self, model: &SensorModel) -> Result<SimResult, DiagnoseError> {
        let s = self.settings;
        Ok(simulate_runs(
            model,
            &self.setup,
            &self.plan,
            s.seed,
            s.seeds,
        )?)
    }

    /// The drift gap of a model whose simulated logs have the segment errors `protocol` under the
    /// drift protocol (None without one).
    pub(super) fn drift_gap(&self, protocol: &[Vec<Vec<SegmentErrors>>]) -> Option<DriftGap> {
        self.plan.protocol.as_ref()?;
        let (_, of_run) = self.plan.lengths();
        Some(crate::drift_gap::drift_gap(
            &self.drift_measured,
            protocol,
            &of_run,
            &self.setup.active,
        ))
    }

    /// The sample interval of the logs.
    pub(super) fn dt_s(&self) -> f64 {
        self.logs[0].dt_s
    }

    /// Each run's length, hours.
    pub(super) fn hours(&self) -> Vec<f64> {
        self.samples
            .iter()
            .map(|&n| n as f64 * self.dt_s() / 3600.0)
            .collect()
    }

    /// Channel `c` of every corrected run (empty when not measured).
    pub(super) fn series(&self, c: Channel) -> Vec<&[f64]> {
        self.logs.iter().filter_map(|l| l.channels[c]).collect()
    }
}

/// Step 3: the gap of a measurement against a band on the measurement's own taus.
pub(super) fn gap_of(measured: Option<&Measured>, band: Option<&Band>) -> Option<(Band, Gap)> {
    let m = measured?;
    let b = restrict(band?, &m.idx);
    let g = gap(&m.curve, &b);
    Some((b, g))
}

/// The band with `delta_avar` added to its mean Allan variance, ln adev moved accordingly (the spread is
/// kept: it is re-estimated when the changed model is simulated).
pub(super) fn shifted_band(band: &Band, delta_avar: &[f64]) -> Band {
    let mut out = band.clone();
    for i in 0..out.avar_mean.len() {
        let ln = predicted_ln_adev(band.ln_mean[i], band.avar_mean[i], delta_avar[i]);
        let factor = (ln - band.ln_mean[i]).exp();
        out.ln_mean[i] = ln;
        out.avar_mean[i] = (2.0 * ln)
            .exp()
            .max(band.avar_mean[i] + delta_avar[i])
            .max(0.0);
        out.adev_lo[i] = band.adev_lo[i] * factor;
        out.adev_hi[i] = band.adev_hi[i] * factor;
    }
    out
}
