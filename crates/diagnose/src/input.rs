//! What diagnose reads: the measured log, and the checks of its shape.

use crate::error::DiagnoseError;
use noise::ImuChannels;

/// The measured log, SI, one series per channel (None: not in the log).
#[derive(Clone, Copy, Debug)]
pub struct LogInput<'a> {
    pub dt_s: f64,
    pub channels: ImuChannels<Option<&'a [f64]>>,
    pub temperature_c: Option<&'a [f64]>,
}

impl<'a> LogInput<'a> {
    /// The same log with other channel series (e.g. the detectors' corrected ones, see `detect`).
    pub fn with_channels(&self, channels: &'a ImuChannels<Option<Vec<f64>>>) -> LogInput<'a> {
        LogInput {
            dt_s: self.dt_s,
            channels: ImuChannels::from_fn(|c| channels[c].as_deref()),
            temperature_c: self.temperature_c,
        }
    }

    /// Check the log's shape; returns the number of samples.
    pub fn validate(&self) -> Result<usize, DiagnoseError> {
        if !(self.dt_s > 0.0 && self.dt_s.is_finite()) {
            return Err(DiagnoseError::BadInterval(self.dt_s));
        }
        let (first, samples) = self
            .channels
            .iter()
            .find_map(|(c, s)| s.map(|s| (c, s.len())))
            .ok_or(DiagnoseError::NoChannels)?;
        for (c, s) in self.channels.iter() {
            if let Some(s) = s {
                if s.len() != samples {
                    return Err(DiagnoseError::Length {
                        channel: c.name(),
                        got: s.len(),
                        first: first.name(),
                        expected: samples,
                    });
                }
            }
        }
        if samples < 64 {
            return Err(DiagnoseError::TooShort { samples });
        }
        if let Some(t) = self.temperature_c {
            if t.len() != samples {
                return Err(DiagnoseError::TemperatureLength {
                    got: t.len(),
                    expected: samples,
                });
            }
        }
        Ok(samples)
    }
}

/// Check several runs of one sensor (docs/diagnose.md, "Several runs"): each log's shape, one
/// rate and one set of channels; returns each run's number of samples.
pub fn validate_runs(logs: &[LogInput]) -> Result<Vec<usize>, DiagnoseError> {
    let first = logs.first().ok_or(DiagnoseError::NoRuns)?;
    let names = |l: &LogInput| {
        l.channels
            .iter()
            .filter(|(_, s)| s.is_some())
            .map(|(c, _)| c.name())
            .collect::<Vec<_>>()
            .join(" ")
    };
    let mut samples = Vec::with_capacity(logs.len());
    for (r, log) in logs.iter().enumerate() {
        samples.push(log.validate()?);
        if (log.dt_s - first.dt_s).abs() > 1e-9 * first.dt_s {
            return Err(DiagnoseError::RunRate {
                run: r + 1,
                dt_s: log.dt_s,
                first_dt_s: first.dt_s,
            });
        }
        if names(log) != names(first) {
            return Err(DiagnoseError::RunChannels {
                run: r + 1,
                channels: names(log),
                first: names(first),
            });
        }
    }
    Ok(samples)
}
