//! Why a value of a model is invalid, and the one range check every validating constructor uses.

use crate::limits::valid_value;

/// Why a model value is invalid (programmatic construction; configs report through `ConfigError`).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{what}: expected {expected}, found {found}")]
pub struct ModelError {
    pub what: &'static str,
    pub expected: &'static str,
    pub found: f64,
}

/// `value` if a sane value (`crate::limits::valid_value`: finite, magnitude below 1e100) and > 0
/// (`positive`) or >= 0, else the error naming `what`.
pub(crate) fn check(what: &'static str, value: f64, positive: bool) -> Result<f64, ModelError> {
    let ok = valid_value(value) && if positive { value > 0.0 } else { value >= 0.0 };
    if ok {
        Ok(value)
    } else {
        Err(ModelError {
            what,
            expected: if positive {
                "a value > 0 and below 1e100 (SI units)"
            } else {
                "a value >= 0 and below 1e100 (SI units)"
            },
            found: value,
        })
    }
}

/// `value` if a sane value (any sign; `crate::limits::valid_value`), else the error naming `what`.
pub(crate) fn check_finite(what: &'static str, value: f64) -> Result<f64, ModelError> {
    if valid_value(value) {
        Ok(value)
    } else {
        Err(ModelError {
            what,
            expected: "a magnitude below 1e100 (SI units)",
            found: value,
        })
    }
}
