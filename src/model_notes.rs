//! The notes on what a sensor model lacks (`noise::model_notes`, one rule for every command and
//! the Python package), printed on stderr.

use noise::SensorModel;

pub use noise::model_notes::notes;

/// Print the notes on stderr ("note: ..."), the convention for notes (docs/cli.md).
pub fn print(model: &SensorModel, horizon_s: Option<f64>) {
    for n in notes(model, horizon_s) {
        tell!("note: {}: {n}", model.name);
    }
}
