//! What diagnose reads: the measured log, and the checks of its shape.

use crate::drift::CHANNELS;
use crate::error::DiagnoseError;
use noise::ImuChannels;

/// The measured log, SI, channels in the order gx gy gz ax ay az (None: not in the log).
#[derive(Clone, Copy, Debug)]
pub struct LogInput<'a> {
    pub dt_s: f64,
    pub channels: [Option<&'a [f64]>; 6],
    pub temperature_c: Option<&'a [f64]>,
}

impl<'a> LogInput<'a> {
    /// The same log with other channel series (e.g. the detectors' corrected ones, see `detect`).
    pub fn with_channels(&self, channels: &'a ImuChannels<Option<Vec<f64>>>) -> LogInput<'a> {
        LogInput {
            dt_s: self.dt_s,
            channels: channels.0.each_ref().map(Option::as_deref),
            temperature_c: self.temperature_c,
        }
    }

    /// Check the log's shape; returns the number of samples.
    pub fn validate(&self) -> Result<usize, DiagnoseError> {
        if !(self.dt_s > 0.0 && self.dt_s.is_finite()) {
            return Err(DiagnoseError::BadInterval(self.dt_s));
        }
        let first = (0..6)
            .find(|&c| self.channels[c].is_some())
            .ok_or(DiagnoseError::NoChannels)?;
        let samples = self.channels[first].map(|c| c.len()).unwrap_or(0);
        for c in 0..6 {
            if let Some(s) = self.channels[c] {
                if s.len() != samples {
                    return Err(DiagnoseError::Length {
                        channel: CHANNELS[c],
                        got: s.len(),
                        first: CHANNELS[first],
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
        (0..6)
            .filter(|&c| l.channels[c].is_some())
            .map(|c| CHANNELS[c])
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
