//! The sample rates a log may have.

/// Highest sample rate a log may have, Hz.
pub const MAX_LOG_RATE_HZ: f64 = 1e9;

/// Whether `rate_hz` is a sample rate a log can have (finite, above 0, at most
/// [`MAX_LOG_RATE_HZ`]): the check of the rate setting, for front ends that validate early.
pub fn valid_rate_hz(rate_hz: f64) -> bool {
    rate_hz.is_finite() && rate_hz > 0.0 && rate_hz <= MAX_LOG_RATE_HZ
}
