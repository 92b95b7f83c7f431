//! `allan`: the rules a front end applies before an Allan analysis of samples it holds (the CLI
//! reads its log through `logio`, whose reader applies the same bounds to a file's rate and
//! values): the sample rate, the confidence level, and samples an analysis can use.

use crate::error::{RequestError, Result};

/// A sample rate a log can have (`logio::valid_rate_hz`: finite, 1e-6 Hz to 1e9 Hz).
pub fn check_rate(rate_hz: f64) -> Result<f64> {
    if logio::valid_rate_hz(rate_hz) {
        Ok(rate_hz)
    } else {
        Err(RequestError::LogRate(rate_hz))
    }
}

/// A confidence level strictly between 0 and 1.
pub fn check_confidence(level: f64) -> Result<f64> {
    if level > 0.0 && level < 1.0 {
        Ok(level)
    } else {
        Err(RequestError::Confidence(level))
    }
}

/// A confidence level from its text: `1sigma` (erf(1/sqrt 2) = 0.6827, SP 1065 §5.3), a fraction
/// (`0.95`) or a percentage (`95%`), checked with [`check_confidence`].
pub fn parse_confidence(text: &str) -> Result<f64> {
    let t = text.trim();
    let bad = || RequestError::ConfidenceText(t.to_string());
    let level = if matches!(t, "1sigma" | "1-sigma") {
        allan::ONE_SIGMA_CI
    } else if let Some(pct) = t.strip_suffix('%') {
        pct.trim().parse::<f64>().map_err(|_| bad())? / 100.0
    } else {
        t.parse::<f64>().map_err(|_| bad())?
    };
    check_confidence(level)
}

/// Samples an analysis can use: at least two, each a value a log can hold (finite, magnitude
/// below `logio::MAX_ABS_VALUE`), and not all one value (nor within `logio::MIN_SPREAD` of one: a constant channel has no
/// noise to analyse: the CLI refuses such a column with the same words).
pub fn check_samples(data: &[f64]) -> Result<()> {
    if data.len() < 2 {
        return Err(RequestError::TooFewSamples(data.len()));
    }
    if let Some(i) = data.iter().position(|&v| !logio::valid_value(v)) {
        return Err(RequestError::Sample {
            index: i,
            value: data[i],
        });
    }
    if !logio::has_spread(data) {
        return Err(RequestError::ConstantSamples {
            value: data[0],
            spread: logio::spread(data),
        });
    }
    Ok(())
}
