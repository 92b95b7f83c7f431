//! `diagnose` and `drift`: the settings of the measured-against-simulated workflow and of the
//! drift protocol, checked once with one set of defaults (`diagnose::Settings::default()`, the
//! protocol's), and diagnose's own errors told with a front end's names.

use crate::error::{RequestError, Result};
use crate::setting::{Names, Setting};
use diagnose::drift_check::{CheckError, CheckSettings};
use diagnose::protocol::{Calibration, Initialisation, Protocol, DEFAULT_LATITUDE_DEG};
use diagnose::settings::{MAX_ROUNDS, MAX_SEEDS};
use diagnose::{DiagnoseError, Settings};

/// The name a diagnosed model is written under: `<model file stem>-diagnosed.toml` (`sensor`
/// for a model without a file name).
pub fn diagnosed_model_name(model: &str) -> String {
    let stem = std::path::Path::new(model)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "sensor".into());
    format!("{stem}-diagnosed.toml")
}

/// Highest latitude a log may have been recorded at, deg (the north-east-down frame is singular
/// at the poles).
pub const MAX_LATITUDE_DEG: f64 = 89.0;

/// Where the logs were recorded: the round Earth's latitude, or Woodman's flat Earth.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum Earth {
    /// The round, rotating Earth at [`DEFAULT_LATITUDE_DEG`] (no latitude given).
    #[default]
    DefaultLatitude,
    /// The round, rotating Earth at this latitude, deg.
    Latitude(f64),
    /// Woodman's flat, non-rotating Earth.
    Flat,
}

impl Earth {
    /// The protocol's `latitude_deg` (None: flat), checked.
    pub fn latitude_deg(self) -> Result<Option<f64>> {
        match self {
            Earth::DefaultLatitude => Ok(Some(DEFAULT_LATITUDE_DEG)),
            Earth::Latitude(v) if v.is_finite() && v.abs() <= MAX_LATITUDE_DEG => Ok(Some(v)),
            Earth::Latitude(v) => Err(RequestError::Latitude(v)),
            Earth::Flat => Ok(None),
        }
    }
}

/// The drift protocol's settings (`drift`, and diagnose's drift check); `None` takes the default.
#[derive(Clone, Debug, Default)]
pub struct ProtocolRequest {
    pub calibration: Option<Calibration>,
    pub initialisation: Option<Initialisation>,
    /// Horizons, s (`None`: the command's default).
    pub horizons_s: Option<Vec<f64>>,
    pub overlapping: bool,
    pub earth: Earth,
}

impl ProtocolRequest {
    /// The protocol, with `default_horizons_s` where none are given.
    pub fn protocol(&self, default_horizons_s: &[f64]) -> Result<Protocol> {
        let horizons_s = self
            .horizons_s
            .clone()
            .unwrap_or_else(|| default_horizons_s.to_vec());
        if let Some(&h) = horizons_s.iter().find(|h| !(h.is_finite() && **h > 0.0)) {
            return Err(RequestError::Horizon(h));
        }
        Ok(Protocol {
            calibration: self.calibration.unwrap_or(Calibration::LogMean),
            initialisation: self.initialisation.unwrap_or(Initialisation::Perfect),
            horizons_s,
            overlapping: self.overlapping,
            latitude_deg: self.earth.latitude_deg()?,
        })
    }
}

/// `diagnose`'s settings; `None` takes [`Settings::default`]'s.
#[derive(Clone, Debug, Default)]
pub struct DiagnoseRequest {
    /// How many logs are diagnosed together (the drift check runs by default with several).
    pub logs: usize,
    pub seed: Option<u64>,
    pub seeds: Option<usize>,
    pub rounds: Option<usize>,
    pub min_delta_bic: Option<f64>,
    pub tau_min_s: Option<f64>,
    /// Run the drift check even with one log (implied by a calibration or initialisation).
    pub drift_check: bool,
    /// The drift check's protocol; its horizons are the diagnosis's.
    pub protocol: ProtocolRequest,
}

impl DiagnoseRequest {
    /// The workflow's settings, every one checked.
    pub fn validate(&self) -> Result<Settings> {
        let d = Settings::default();
        let seeds = self.seeds.unwrap_or(d.seeds);
        if seeds < 2 {
            return Err(RequestError::TooFewSeeds(seeds));
        }
        if seeds > MAX_SEEDS {
            return Err(RequestError::TooManySeeds(seeds));
        }
        let max_rounds = self.rounds.unwrap_or(d.max_rounds);
        if max_rounds > MAX_ROUNDS {
            return Err(RequestError::Rounds(max_rounds));
        }
        let min_delta_bic = self.min_delta_bic.unwrap_or(d.min_delta_bic);
        if !(min_delta_bic.is_finite() && min_delta_bic >= 0.0) {
            return Err(RequestError::MinDeltaBic(min_delta_bic));
        }
        let tau_min_s = self.tau_min_s.unwrap_or(d.tau_min_s);
        if !(tau_min_s.is_finite() && tau_min_s >= 0.0) {
            return Err(RequestError::TauMin(tau_min_s));
        }
        let protocol = self.protocol.protocol(&d.horizons_s)?;
        let p = &self.protocol;
        let asked = self.drift_check || p.calibration.is_some() || p.initialisation.is_some();
        Ok(Settings {
            seed: self.seed.unwrap_or(d.seed),
            seeds,
            max_rounds,
            horizons_s: protocol.horizons_s.clone(),
            min_delta_bic,
            tau_min_s,
            latitude_deg: protocol.latitude_deg,
            drift_protocol: (asked || self.logs > 1).then_some(protocol),
            ..d
        })
    }
}

/// A diagnose error, one about a setting named by `names`.
pub fn diagnose_error(e: &DiagnoseError, names: Names) -> String {
    match e {
        DiagnoseError::NoTaus { tau_min_s } => format!(
            "no Allan point at or above {} {tau_min_s} s",
            names(Setting::TauMin)
        ),
        DiagnoseError::SeedsForRuns { seeds, runs } => format!(
            "{s} {seeds} for {runs} logs: a band pooled over {runs} runs needs more simulated logs than runs (e.g. {s} {})",
            (runs + 1).max(Settings::default().seeds),
            s = names(Setting::Seeds)
        ),
        e => noise::text::error_chain(e),
    }
}

/// Refuse logs whose simulation would not fit in memory: each of `threads` workers holds a
/// simulated six-channel log of the longest run's `samples` (and its phase), 16 bytes per
/// channel sample; refused rather than killed for memory halfway.
pub fn check_simulation_memory(source_name: &str, samples: usize, threads: usize) -> Result<()> {
    let need = threads as u64 * 6 * samples as u64 * 16;
    match logio::available_memory_bytes() {
        Some(available) if need > available => Err(RequestError::SimulationMemory {
            source_name: source_name.to_string(),
            samples,
            threads,
            need,
            available,
        }),
        _ => Ok(()),
    }
}

/// `drift`'s horizons when none are given, s.
pub const DRIFT_HORIZONS_S: [f64; 4] = [10.0, 60.0, 600.0, 3600.0];
/// Simulated experiments for the model's band when none are given.
pub const DRIFT_REPLICATES: usize = 40;
/// Fewest and most simulated experiments a band may have.
pub const MIN_REPLICATES: usize = 10;
pub const MAX_REPLICATES: usize = 100_000;

/// `drift`'s settings; `None` takes the default.
#[derive(Clone, Debug, Default)]
pub struct DriftRequest {
    /// The protocol; its horizons default to [`DRIFT_HORIZONS_S`].
    pub protocol: ProtocolRequest,
    pub replicates: Option<usize>,
    pub seed: Option<u64>,
}

impl DriftRequest {
    /// The drift check's settings, every one checked.
    pub fn validate(&self) -> Result<CheckSettings> {
        let replicates = self.replicates.unwrap_or(DRIFT_REPLICATES);
        if !(MIN_REPLICATES..=MAX_REPLICATES).contains(&replicates) {
            return Err(RequestError::Replicates {
                value: replicates,
                min: MIN_REPLICATES,
                max: MAX_REPLICATES,
            });
        }
        Ok(CheckSettings {
            protocol: self.protocol.protocol(&DRIFT_HORIZONS_S)?,
            replicates,
            seed: self.seed.unwrap_or(Settings::default().seed),
        })
    }
}

/// A drift-check error, one about a setting named by `names`.
pub fn check_error(e: &CheckError, names: Names) -> String {
    match e {
        CheckError::Replicates(n) => format!(
            "{} {n}: at least {MIN_REPLICATES} simulated experiments are needed for a 95 % band",
            names(Setting::Replicates)
        ),
        e => noise::text::error_chain(e),
    }
}

/// A model to check drift against, read once: the sensor model, the data its levels were fitted
/// on (its `[fitted_on]` table, written by `diagnose`) and the structures it lists beside its own
/// (`[[alternatives]]`).
pub struct ModelUnderTest {
    pub model: noise::SensorModel,
    pub fitted_on: Option<diagnose::fitted_on::FittedOn>,
    pub alternatives: Vec<diagnose::alternatives::Alternative>,
}

impl ModelUnderTest {
    /// Read `file`: the model, and unless `exact_parameters` / `one_structure` say to take its
    /// levels as exact / its structure as certain, its fitted-on data and alternatives.
    pub fn read(
        file: &crate::files::TextFile,
        exact_parameters: bool,
        one_structure: bool,
    ) -> Result<ModelUnderTest> {
        let model = crate::files::model_of(file)?;
        let tables = |message: String| RequestError::ModelTables {
            name: file.name.clone(),
            message,
        };
        let fitted_on = diagnose::document::fitted_on_of(&file.text, &file.name, exact_parameters)
            .and_then(|f| {
                if let Some(f) = &f {
                    f.check_spreads(&model)?;
                }
                Ok(f)
            })
            .map_err(|e| tables(noise::text::error_chain(&e)))?;
        let alternatives =
            diagnose::document::alternatives_of(&file.text, &file.name, one_structure)
                .map_err(|e| tables(noise::text::error_chain(&e)))?;
        Ok(ModelUnderTest {
            model,
            fitted_on,
            alternatives,
        })
    }
}
