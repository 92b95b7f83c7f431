//! Misalignment: the sensitivity of an axis to the two other axes (Woodman §3.2.5).

use super::term::{ErrorTerm, GenContext, Generate, Stage, TermKind};
use crate::model_error::{check_finite, ModelError};
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

impl ErrorTerm for Misalignment {}

impl TermKind for Misalignment {
    const STOCHASTIC: bool = false;
    const SHOWS_IN_STATIC_LOG: bool = false;
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
