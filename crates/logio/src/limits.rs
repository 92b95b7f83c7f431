//! The sample rates and values a log may have.

/// Highest sample rate a log may have, Hz.
pub const MAX_LOG_RATE_HZ: f64 = 1e9;

/// Lowest sample rate a log may have, Hz (one sample in about 11.6 days): below it the averaging
/// times of an analysis (up to 1e9 samples) leave the range of numbers their squares can hold.
pub const MIN_LOG_RATE_HZ: f64 = 1e-6;

pub use noise::limits::{valid_value, MAX_ABS_VALUE};

/// Whether `rate_hz` is a sample rate a log can have (finite, from [`MIN_LOG_RATE_HZ`] to
/// [`MAX_LOG_RATE_HZ`]): the check of the rate setting, for front ends that validate early.
pub fn valid_rate_hz(rate_hz: f64) -> bool {
    (MIN_LOG_RATE_HZ..=MAX_LOG_RATE_HZ).contains(&rate_hz)
}

/// Smallest spread (largest minus smallest value) a series must have for an analysis to measure
/// its noise. The Allan variance and the fits sum squares of differences of values (Allan 1966);
/// differences below 1e-100 square to below 1e-200, and those below about 1.5e-154 underflow
/// to zero or to subnormal numbers that have lost their digits (IEEE 754: the smallest normal
/// double is 2.2e-308). A series whose values all lie within 1e-100 of each other is, to an
/// analysis, constant: no sensor's noise is that small in any unit.
pub const MIN_SPREAD: f64 = 1e-100;

/// The spread of `values`: the largest minus the smallest (0 for none or one; finite for values
/// a log can hold, [`valid_value`]).
pub fn spread(values: &[f64]) -> f64 {
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    if values.is_empty() {
        0.0
    } else {
        hi - lo
    }
}

/// Whether `values` vary enough for an analysis to measure their noise: a spread of at least
/// [`MIN_SPREAD`]. A constant series (a stuck or disconnected sensor, a column of zeros) and one
/// whose differences underflow when squared are refused alike.
pub fn has_spread(values: &[f64]) -> bool {
    spread(values) >= MIN_SPREAD
}

/// At most the first 40 characters of `text` (and "..." when cut), for messages that quote a
/// bad value: a 100 MB field is not echoed whole.
pub fn quote_prefix(text: &str) -> String {
    const MAX_CHARS: usize = 40;
    match text.char_indices().nth(MAX_CHARS) {
        None => format!("{text:?}"),
        Some((at, _)) => format!("{:?}... ({} bytes)", &text[..at], text.len()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_is_the_range_and_refuses_constant_and_underflowing_series() {
        assert_eq!(spread(&[]), 0.0);
        assert_eq!(spread(&[3.0]), 0.0);
        assert_eq!(spread(&[1.0, -2.0, 0.5]), 3.0);
        assert!(!has_spread(&[-9.81; 10]));
        // Issue 46, item 2: 0 and 1e-160 alternating, or one 1e-300 among zeros, square to 0.
        assert!(!has_spread(&[0.0, 1e-160, 0.0, 1e-160]));
        assert!(!has_spread(&[0.0, 0.0, 1e-300, 0.0]));
        // A real sensor's noise, however small, in any unit.
        assert!(has_spread(&[1.0, 1.0 + f64::EPSILON]));
        assert!(has_spread(&[0.0, 1e-99]));
        assert!(has_spread(&[-1e99, 1e99]));
    }
}
