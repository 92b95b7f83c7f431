//! One rule, in every command, for the parts a sensor model lacks: a note naming what is assumed
//! perfect (a triad or an axis with no error term at all), and a note where a triad's model has
//! no long-term term (`TermKind::LONG_TERM`: bias instability, rate random walk, rate ramp,
//! Gauss-Markov, temperature) and the horizon is long enough for such terms to dominate a real
//! sensor's drift.

use crate::{Effect, Sensor, SensorModel};

/// Horizons at or beyond this are "long": white noise alone then understates a real sensor's
/// drift. On the shipped MEMS models the flicker floor overtakes white noise in the Allan
/// deviation between about 10 s and 100 s (docs/model.md §2, e.g. the ADIS16405 curve's minimum
/// region starts near 10 s), so from 100 s on a model without it is optimistic.
pub const LONG_HORIZON_S: f64 = 100.0;

fn sensor_words(s: Sensor) -> (&'static str, &'static str) {
    match s {
        Sensor::Gyro => ("gyro", "attitude does not drift from them"),
        Sensor::Accel => (
            "accelerometer",
            "position and velocity drift only through tilt from the gyros",
        ),
    }
}

/// The notes for `model` used up to `horizon_s` (the longest time the command looks at; `None`
/// where it has none).
pub fn notes(model: &SensorModel, horizon_s: Option<f64>) -> Vec<String> {
    let mut notes = Vec::new();
    for sensor in [Sensor::Gyro, Sensor::Accel] {
        let (name, consequence) = sensor_words(sensor);
        let axes = &model.triad(sensor).axes;
        let bare: Vec<&str> = axes
            .iter()
            .zip(["x", "y", "z"])
            .filter(|(a, _)| a.effects().is_empty())
            .map(|(_, n)| n)
            .collect();
        if bare.len() == 3 {
            notes.push(format!(
                "the model has no {name} error terms: perfect {name}s are assumed, so {consequence} (optimistic)"
            ));
            continue;
        }
        if !bare.is_empty() {
            notes.push(format!(
                "the model has no error terms for {name} {}: assumed perfect (optimistic)",
                bare.join(", ")
            ));
        }
        let long = axes
            .iter()
            .any(|a| Effect::ALL.iter().any(|&e| e.is_long_term() && a.has(e)));
        if let (false, Some(h)) = (long, horizon_s) {
            if h >= LONG_HORIZON_S {
                notes.push(format!(
                    "the {name} model has no long-term term (bias instability, rate random walk, ramp, Gauss-Markov, temperature): up to {} it is optimistic, since such terms dominate real sensors' drift beyond about {}",
                    crate::text::time(h),
                    crate::text::time(LONG_HORIZON_S)
                ));
            }
        }
    }
    notes
}
