//! `generate`: a synthetic static, level IMU log from a sensor model. The request and its checks
//! (rate, length, work, the output filter against the rate); front ends generate from the plan
//! (the CLI in blocks into a file, Python into arrays).

use crate::error::{Remedy, RequestError, Result};
use crate::files::SensorSource;
use noise::{ImuErrors, SensorModel, TermFilter, TermSelector};

/// Highest sample rate a generated log may have, Hz.
pub const MAX_RATE_HZ: f64 = 1e6;
/// Most samples a generated log may have.
pub const MAX_SAMPLES: f64 = 1e12;
/// The seed and run when none is given.
pub const DEFAULT_SEED: u64 = 1;
pub const DEFAULT_RUN: u64 = 0;

/// `generate`'s settings.
#[derive(Clone, Debug)]
pub struct GenerateRequest {
    pub sensor: SensorSource,
    pub duration_s: f64,
    pub rate_hz: f64,
    /// Master seed ([`DEFAULT_SEED`]).
    pub seed: u64,
    /// Which run's per-run draws (turn-on bias, initial states) to use ([`DEFAULT_RUN`]).
    pub run: u64,
    pub only: Option<Vec<TermSelector>>,
    pub without: Vec<TermSelector>,
    /// Where the log goes (named in messages), if a file.
    pub output: Option<String>,
}

impl Default for GenerateRequest {
    fn default() -> Self {
        GenerateRequest {
            sensor: SensorSource::default(),
            duration_s: 0.0,
            rate_hz: 0.0,
            seed: DEFAULT_SEED,
            run: DEFAULT_RUN,
            only: None,
            without: Vec::new(),
            output: None,
        }
    }
}

/// A checked `generate` request.
#[derive(Debug)]
pub struct GeneratePlan {
    /// The model with the request's term filter applied.
    pub model: SensorModel,
    pub filter: TermFilter,
    pub rate_hz: f64,
    pub samples: u64,
    pub seed: u64,
    pub run: u64,
    /// The sensor as named (its file or source name).
    pub source: String,
    /// None of the `only` terms is in the model: the log is an ideal IMU (allowed, and worth a
    /// note).
    pub only_keeps_nothing: bool,
}

impl GenerateRequest {
    /// Read the model and check every setting before any sample is generated.
    pub fn validate(&self) -> Result<GeneratePlan> {
        let file = self.sensor.read()?;
        let model = crate::files::model_of(&file)?;
        let filter = TermFilter::new(self.only.as_deref(), &self.without);
        let rate_hz = crate::simulate::check_rate(self.rate_hz)?;
        let samples = (self.duration_s * rate_hz).round();
        if !(1.0..=MAX_SAMPLES).contains(&samples) {
            return Err(RequestError::Samples {
                duration_s: self.duration_s,
                rate_hz,
                samples,
            });
        }
        if rate_hz > MAX_RATE_HZ {
            return Err(RequestError::RateTooHigh {
                rate_hz,
                max_hz: MAX_RATE_HZ,
            });
        }
        let what = match &self.output {
            Some(o) => format!("-o {o}"),
            None => file.name.clone(),
        };
        crate::simulate::check_work(&model, 1.0, samples, &what, Remedy::Generate)?;
        // An output filter must fit the rate (a low-pass cutoff below the internal Nyquist
        // frequency).
        let only_keeps_nothing = filter.only_terms().is_some_and(|only| {
            !only
                .iter()
                .any(|&(sensor, effect)| model.has(sensor, effect))
        });
        let model = model.filtered(&filter);
        ImuErrors::check_rate(&model, 1.0 / rate_hz).map_err(|e| RequestError::FilterRate {
            source_name: file.name.clone(),
            message: e.to_string(),
        })?;
        Ok(GeneratePlan {
            model,
            filter,
            rate_hz,
            samples: samples as u64,
            seed: self.seed,
            run: self.run,
            source: file.name,
            only_keeps_nothing,
        })
    }
}

impl GeneratePlan {
    /// The first value that is not one a sample may have (`noise::limits::valid_value`: finite,
    /// magnitude below 1e100, the bound every log reader holds) among generated `channels` (its
    /// channel, the sample index `k0 + i`) as the error that names it: what `generate` writes,
    /// `allan` and the other readers read back.
    pub fn check_values<'a>(
        k0: u64,
        channels: impl IntoIterator<Item = (noise::Channel, &'a [f64])>,
    ) -> Result<()> {
        for (c, values) in channels {
            if let Some(i) = values.iter().position(|&v| !noise::limits::valid_value(v)) {
                return Err(RequestError::Overflow {
                    channel: c.name(),
                    value: values[i],
                    k: (k0 + i as u64) as usize,
                });
            }
        }
        Ok(())
    }
}
