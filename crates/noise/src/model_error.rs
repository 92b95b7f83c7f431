//! Why a value of a model is invalid, and the one range check every validating constructor uses.

/// Why a model value is invalid (programmatic construction; configs report through `ConfigError`).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{what}: expected {expected}, found {found}")]
pub struct ModelError {
    pub what: &'static str,
    pub expected: &'static str,
    pub found: f64,
}

/// `value` if finite and > 0 (`positive`) or >= 0, else the error naming `what`.
pub(crate) fn check(what: &'static str, value: f64, positive: bool) -> Result<f64, ModelError> {
    let ok = value.is_finite() && if positive { value > 0.0 } else { value >= 0.0 };
    if ok {
        Ok(value)
    } else {
        Err(ModelError {
            what,
            expected: if positive {
                "a finite value > 0"
            } else {
                "a finite value >= 0"
            },
            found: value,
        })
    }
}

/// `value` if finite (any sign), else the error naming `what`.
pub(crate) fn check_finite(what: &'static str, value: f64) -> Result<f64, ModelError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ModelError {
            what,
            expected: "a finite value",
            found: value,
        })
    }
}
