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

/// Samples with gaps, for the gap-tolerant Allan deviation (allantools `gradev`): a NaN is a
/// gap; the samples present follow [`check_samples`] (an infinite sample or one of magnitude
/// 1e100 or more is refused by its index, fewer than 2 present or all one value is refused).
pub fn check_samples_with_gaps(data: &[f64]) -> Result<()> {
    if let Some(i) = data
        .iter()
        .position(|&v| !v.is_nan() && !logio::valid_value(v))
    {
        return Err(RequestError::Sample {
            index: i,
            value: data[i],
        });
    }
    let present: Vec<f64> = data.iter().copied().filter(|v| !v.is_nan()).collect();
    check_samples(&present)
}

/// Fewest averaging times with 9 or more intervals a channel's curve must give (a slope needs
/// two).
pub const MIN_USABLE_TAUS: usize = 2;

/// Averaging factors of averaging times in seconds, as allantools' `tau_generator` makes them:
/// m = round(tau * rate) (half to even, numpy's `round`), kept when 0 < m < `n_phase` (the
/// number of phase points). A time that is not finite and > 0 is refused (allantools would give
/// NaN or drop it without a word); times whose factor the samples cannot hold are dropped, as
/// allantools does (the curve's own check then refuses a list that leaves none).
pub fn factors_of_seconds(taus_s: &[f64], rate_hz: f64, n_phase: usize) -> Result<allan::TauGrid> {
    if let Some(index) = taus_s.iter().position(|&t| !(t.is_finite() && t > 0.0)) {
        return Err(RequestError::Tau {
            index,
            value: taus_s[index],
        });
    }
    let ms = taus_s
        .iter()
        .map(|t| (t * rate_hz).round_ties_even())
        .filter(|&m| m > 0.0 && m < n_phase as f64)
        .map(|m| m as usize)
        .collect();
    Ok(allan::TauGrid::Explicit(ms))
}

/// Refuse a channel's curve with fewer than [`MIN_USABLE_TAUS`] averaging times of at least 9
/// intervals (Woodman's rule), or with a deviation whose square (the variance the fit and the
/// intervals work on) is not a normal double: 0 (the samples' variations cancel at that tau),
/// below about 1.5e-154 (samples of magnitude 1e-160 or 1e-300: their variance underflows and
/// the fit divides by it), or not finite. As `imudrift allan` does for each channel of a log and
/// `imudrift.allan` for its samples (`channel`: the log's channel, when there is one).
pub fn check_curve(
    source_name: &str,
    channel: Option<&str>,
    samples: usize,
    points: &[allan::AllanPoint],
) -> Result<()> {
    let usable = points.iter().filter(|p| p.woodman_ok()).count();
    if usable < MIN_USABLE_TAUS {
        return Err(RequestError::UnusableCurve {
            source_name: source_name.to_string(),
            channel: channel.map(str::to_string),
            samples,
            usable,
            needed: MIN_USABLE_TAUS,
            empty: points.is_empty(),
        });
    }
    if let Some(p) = points.iter().find(|p| !(p.dev * p.dev).is_normal()) {
        return Err(RequestError::DegenerateDeviation {
            source_name: source_name.to_string(),
            channel: channel.map(str::to_string),
            tau_s: p.tau_s,
            dev: p.dev,
        });
    }
    Ok(())
}

/// Refuse a deviation function's result (allantools' conventions: any point of 2 or more terms)
/// that has no point.
pub fn check_points(function: &str, samples: usize, points: &[allan::AllanPoint]) -> Result<()> {
    if points.is_empty() {
        return Err(RequestError::NoPoint {
            function: function.to_string(),
            samples,
        });
    }
    Ok(())
}
