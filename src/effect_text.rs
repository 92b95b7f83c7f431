//! A `diagnose` finding as a person reads it: the parameters' text is the library's
//! (`diagnose::effect_text`, also in the corrected model's header); lengths and angles for tables.

pub use diagnose::effect_text::{evidence_text, model_text, params_text};

/// A length in metres for a table: engineering notation with 4 significant digits
/// ("22360 km", "172.3 m").
pub fn metres(v: f64) -> String {
    if v.is_finite() {
        crate::fmt::si(v, "m")
    } else {
        "-".into()
    }
}

/// An angle in radians for a table, in degrees to 4 significant digits.
pub fn degrees(v: f64) -> String {
    if v.is_finite() {
        format!("{} deg", crate::fmt::sig(v.to_degrees(), 4))
    } else {
        "-".into()
    }
}
