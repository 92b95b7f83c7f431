//! The sample rates and values a log may have.

/// Highest sample rate a log may have, Hz.
pub const MAX_LOG_RATE_HZ: f64 = 1e9;

/// Lowest sample rate a log may have, Hz (one sample in about 11.6 days): below it the averaging
/// times of an analysis (up to 1e9 samples) leave the range of numbers their squares can hold.
pub const MIN_LOG_RATE_HZ: f64 = 1e-6;

/// Largest magnitude a value of a log may have (exclusive). Analyses sum squares of values and
/// of their differences (the Allan variance, Allan 1966; least-squares fits): with |x| < 1e100
/// a sum of 1e9 such squares stays below 1e210, far from the f64 overflow at 1.8e308
/// (IEEE 754), while 1e150 and more overflow. No sensor's reading (or time stamp) comes near.
pub const MAX_ABS_VALUE: f64 = 1e100;

/// Whether `rate_hz` is a sample rate a log can have (finite, from [`MIN_LOG_RATE_HZ`] to
/// [`MAX_LOG_RATE_HZ`]): the check of the rate setting, for front ends that validate early.
pub fn valid_rate_hz(rate_hz: f64) -> bool {
    (MIN_LOG_RATE_HZ..=MAX_LOG_RATE_HZ).contains(&rate_hz)
}

/// Whether `v` is a value a log can hold: finite and of magnitude below [`MAX_ABS_VALUE`].
#[inline(always)]
pub fn valid_value(v: f64) -> bool {
    v.abs() < MAX_ABS_VALUE
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
