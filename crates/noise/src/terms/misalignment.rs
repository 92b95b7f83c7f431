//! Misalignment: the sensitivity of an axis to the two other axes (Woodman §3.2.5).

use super::term::{ErrorTerm, GenContext, Generate, Stage, TermKind, WriteContext};
use crate::config::error::ConfigError;
use crate::config::read::{ReadContext, Text};
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check_finite, ModelError};
use crate::units::{Quantity, Signal};
use crate::ImuRng;

/// Misalignment (rad): sensitivity of this axis to the two other axes, in axis order
/// (x: [y, z]; y: [x, z]; z: [x, y]), signed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Misalignment {
    angles_rad: [f64; 2],
}

impl Misalignment {
    /// Two finite angles.
    pub fn new(angles_rad: [f64; 2]) -> Result<Misalignment, ModelError> {
        check_finite("misalignment", angles_rad[0])?;
        check_finite("misalignment", angles_rad[1])?;
        Ok(Misalignment { angles_rad })
    }

    /// The sensitivities to the two other axes, in axis order (rad).
    pub fn angles_rad(&self) -> [f64; 2] {
        self.angles_rad
    }
}

impl ErrorTerm for Misalignment {
    /// A bias from the two other axes' readings (docs/model.md §1.5 Table 2, as the scale factor).
    fn law_sources(&self, cx: &LawSourceContext) -> Vec<LawSource> {
        let [a, b] = self.angles_rad;
        vec![LawSource::Bias(a * cx.others[0] + b * cx.others[1])]
    }

    fn config_value(&self, cx: &WriteContext) -> String {
        let [a, b] = self.angles_rad;
        format!(
            "[{}, {}]",
            cx.quoted(a, Quantity::Angle),
            cx.quoted(b, Quantity::Angle)
        )
    }
}

impl TermKind for Misalignment {
    const STOCHASTIC: bool = false;
    const LONG_TERM: bool = false;
    const FREE_PARAMETERS: usize = 2;
    const SHOWS_IN_STATIC_LOG: bool = false;
    /// Two angles, `misalignment = [a, b]`.
    type Raw = Vec<Text>;
    const EXAMPLE: Option<&'static str> = Some("misalignment = [\"0.1 deg\", \"0.1 deg\"]");

    fn from_raw(list: &Vec<Text>, cx: &ReadContext) -> Result<Misalignment, ConfigError> {
        if list.len() != 2 {
            return Err(cx.ctx.invalid_at(
                &cx.key,
                list.first(),
                "two angles: the sensitivity to the other two axes in x, y, z order",
                format!("{} values", list.len()),
            ));
        }
        let angle = |i: usize| {
            let key = format!("{}[{i}]", cx.key);
            cx.ctx.value(&key, &list[i], Quantity::Angle, false)
        };
        let angles = [angle(0)?, angle(1)?];
        Misalignment::new(angles).map_err(|e| cx.refused(&cx.key, e))
    }

    /// The unit of the first angle.
    fn note_units(value: &toml::Value, _sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value)) {
        if let Some(first) = value.as_array().and_then(|a| a.first()) {
            note(Quantity::Angle, first);
        }
    }

    type Generator = MisalignmentGenerator;

    fn generator(&self, cx: &GenContext, _rng: &dyn Fn() -> ImuRng) -> MisalignmentGenerator {
        MisalignmentGenerator {
            angles_rad: self.angles_rad,
            axis: cx.axis,
        }
    }
}

/// The sensitivities to the two other axes, in axis order.
#[derive(Clone, Copy, Debug)]
pub struct MisalignmentGenerator {
    angles_rad: [f64; 2],
    axis: usize,
}

impl Generate for MisalignmentGenerator {
    fn stage(&self) -> Stage {
        Stage::Input
    }

    fn input(&self, row: &mut [f64; 3], _bias: &mut f64) {
        let others: Vec<usize> = (0..3).filter(|&j| j != self.axis).collect();
        row[others[0]] = self.angles_rad[0];
        row[others[1]] = self.angles_rad[1];
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> Misalignment {
    Misalignment::new([5e-4, 6e-4]).unwrap()
}
