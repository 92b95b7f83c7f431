//! The harness shared by the two hidden-effect suites (`hidden_effects.rs`, `hidden_real_effects.rs`):
//! the base model, the log-uniform parameter draw, generating a log and diagnosing it, the pass
//! rules (parameters, gap) and the trial loop.

#![allow(dead_code)] // each suite uses a part

use diagnose::simulate::{static_log, SimSetup};
use diagnose::{diagnose, Diagnosis, LogInput, Settings};
use noise::{BiasInstability, Channel, Flicker, ImuErrors, SensorModel, WhiteNoise};
use rand::Rng;
use rand_xoshiro::Xoshiro256PlusPlus;

/// Sample interval of the generated logs (100 Hz).
pub const DT_S: f64 = 0.01;
/// Seeds per band in these tests (a tenth of the default spread error is not needed here).
pub const SEEDS: usize = 12;

/// Base model: white noise, and flicker bias instability if `with_flicker`, on every axis.
/// Gyro N = 1e-4 rad/s/sqrt(Hz) (0.34 deg/sqrt(h)), B = 2e-5 rad/s (4 deg/h); accel N = 1e-3
/// m/s^2/sqrt(Hz) (100 ug/sqrt(Hz)), B = 2e-4 m/s^2 (20 ug). The flicker plateau crosses white
/// noise at N^2 / (0.44 B^2) = 57 s.
pub fn base_model(with_flicker: bool) -> SensorModel {
    let mut m = SensorModel {
        name: "base".into(),
        ..Default::default()
    };
    for ch in Channel::ALL {
        let (n, b) = if ch.is_gyro() {
            (1e-4, 2e-5)
        } else {
            (1e-3, 2e-4)
        };
        let (sensor, axis) = (ch.sensor(), ch.axis());
        let a = m.axis_mut(sensor, axis);
        a.set_term(WhiteNoise::new(n).unwrap());
        if with_flicker {
            a.set_term(BiasInstability::Flicker(Flicker::with_b(b).unwrap()));
        }
    }
    m
}

/// A draw uniform in log between `lo` and `hi`.
pub fn log_uniform(rng: &mut Xoshiro256PlusPlus, lo: f64, hi: f64) -> f64 {
    (rng.gen::<f64>() * (hi / lo).ln()).exp() * lo
}

/// A static log of `samples` generated from `model` (seed `seed`, run 0), with the model's
/// temperature column if `record_temperature`.
pub struct GeneratedLog {
    pub channels: [Vec<f64>; 6],
    pub temperature_c: Option<Vec<f64>>,
}

impl GeneratedLog {
    pub fn new(model: &SensorModel, samples: usize, seed: u64, record_temperature: bool) -> Self {
        let setup = SimSetup {
            dt_s: DT_S,
            samples,
            grid_m: vec![],
            active: noise::ImuChannels([true; 6]),
            horizons_s: vec![60.0],
            temperature_c: None,
            temp_coeff: noise::ImuChannels::default(),
            latitude_deg: diagnose::protocol::Protocol::default().latitude_deg,
            stop: None,
        };
        let channels = static_log(model, &setup, seed, 0).0;
        let temperature_c = record_temperature.then(|| {
            let errors = ImuErrors::new(model, DT_S, seed, 0);
            (0..samples as u64)
                .map(|k| errors.temperature_c(k))
                .collect()
        });
        GeneratedLog {
            channels,
            temperature_c,
        }
    }

    /// Diagnose the log with `base`, `seeds` simulated logs per band, a 60 s drift horizon.
    pub fn diagnose(&self, base: &SensorModel, seeds: usize) -> Diagnosis {
        let input = LogInput {
            dt_s: DT_S,
            channels: noise::ImuChannels(self.channels.each_ref().map(|c| Some(c.as_slice()))),
            temperature_c: self.temperature_c.as_deref(),
        };
        let settings = Settings {
            seeds,
            horizons_s: vec![60.0],
            ..Settings::default()
        };
        diagnose(&input, base, &settings).expect("diagnose runs")
    }
}

/// Runs of one sensor diagnosed together (`pooled_runs.rs`, `pooled_null.rs`): the logs as
/// inputs, and the settings with drift horizons of 60 and 300 s, the drift check on those
/// horizons (default protocol) when `drift`.
pub fn run_inputs(logs: &[GeneratedLog]) -> Vec<LogInput<'_>> {
    logs.iter()
        .map(|l| LogInput {
            dt_s: DT_S,
            channels: noise::ImuChannels(l.channels.each_ref().map(|c| Some(c.as_slice()))),
            temperature_c: None,
        })
        .collect()
}

/// See [`run_inputs`].
pub fn pooled_settings(drift: bool) -> Settings {
    Settings {
        horizons_s: vec![60.0, 300.0],
        drift_protocol: drift.then(|| diagnose::protocol::Protocol {
            horizons_s: vec![60.0, 300.0],
            ..diagnose::protocol::Protocol::default()
        }),
        ..Settings::default()
    }
}

/// Is `value` within 25 % of `truth`, or `truth` inside the stated interval [lo, hi]?
pub fn parameter_ok(truth: f64, value: f64, lo: f64, hi: f64) -> bool {
    (value / truth - 1.0).abs() <= 0.25 || (lo <= truth && truth <= hi)
}

/// Did naming the effect close the gap: a final gap at most 1.5 and at most a third of the initial
/// one, or only at most 1.5 when the effect is faint (initial gap below 4.5: a third of it would
/// then be below 1.5, the agreement level, and a correct model's gap itself scatters around 1,
/// the RMS z over the taus).
pub fn gap_closed(gap_initial: f64, gap_final: f64) -> bool {
    let faint = gap_initial < 4.5;
    gap_final <= 1.5 && (faint || gap_final <= gap_initial / 3.0)
}

/// Run `trials` trials (or `IMUDRIFT_HIDDEN_TRIALS`: a longer blind run before a release; the
/// default keeps CI short) and fail with every failed trial's problems.
pub fn run_trials(trials: u64, trial: impl Fn(u64) -> Result<(), String>) {
    let trials = std::env::var("IMUDRIFT_HIDDEN_TRIALS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(trials);
    let failures: Vec<String> = (0..trials).filter_map(|t| trial(t).err()).collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// z-scores to one decimal, for the `DIAGNOSE_DUMP=1` output of a failed trial.
pub fn format_z(z: &[f64]) -> String {
    z.iter()
        .map(|x| format!("{x:.1}"))
        .collect::<Vec<_>>()
        .join(" ")
}
