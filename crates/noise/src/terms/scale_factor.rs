//! Scale-factor error (Woodman §3.2.5: drift proportional to the rate and duration of motion).

use super::term::{
    note_value_units, ErrorTerm, GenContext, Generate, Stage, TermKind, WriteContext,
};
use crate::config::error::ConfigError;
use crate::config::read::{ReadContext, Text};
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check_finite, ModelError};
use crate::units::{Quantity, Signal};
use crate::ImuRng;

/// Scale-factor error (dimensionless: 300 ppm = 3e-4), signed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScaleFactor {
    ratio: f64,
}

impl ScaleFactor {
    /// Any finite value.
    pub fn new(ratio: f64) -> Result<ScaleFactor, ModelError> {
        Ok(ScaleFactor {
            ratio: check_finite("scale factor", ratio)?,
        })
    }

    /// The error as a ratio.
    pub fn ratio(&self) -> f64 {
        self.ratio
    }
}

impl ErrorTerm for ScaleFactor {
    /// A bias proportional to the reading (docs/model.md §1.5 Table 2: "drift proportional to
    /// rate and duration of motion").
    fn law_sources(&self, cx: &LawSourceContext) -> Vec<LawSource> {
        vec![LawSource::Bias(self.ratio * cx.ideal)]
    }

    fn config_value(&self, cx: &WriteContext) -> String {
        cx.quoted(self.ratio, Quantity::Ratio)
    }
}

impl TermKind for ScaleFactor {
    const STOCHASTIC: bool = false;
    const LONG_TERM: bool = false;
    const FREE_PARAMETERS: usize = 1;
    const SHOWS_IN_STATIC_LOG: bool = false;
    type Raw = Text;
    const EXAMPLE: Option<&'static str> = Some("scale_factor = \"0.1 %\"");

    fn from_raw(raw: &Text, cx: &ReadContext) -> Result<ScaleFactor, ConfigError> {
        let value = cx.value(raw, Quantity::Ratio, false)?;
        ScaleFactor::new(value).map_err(|e| cx.refused(&cx.key, e))
    }

    fn note_units(value: &toml::Value, sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value)) {
        note_value_units(value, Quantity::Ratio, sig, note);
    }

    type Generator = ScaleFactorGenerator;

    fn generator(&self, cx: &GenContext, _rng: &dyn Fn() -> ImuRng) -> ScaleFactorGenerator {
        ScaleFactorGenerator {
            ratio: self.ratio,
            axis: cx.axis,
        }
    }
}

/// The axis' own sensitivity, 1 + ratio.
#[derive(Clone, Copy, Debug)]
pub struct ScaleFactorGenerator {
    ratio: f64,
    axis: usize,
}

impl Generate for ScaleFactorGenerator {
    fn stage(&self) -> Stage {
        Stage::Input
    }

    fn input(&self, row: &mut [f64; 3], _bias: &mut f64) {
        row[self.axis] += self.ratio;
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> ScaleFactor {
    ScaleFactor::new(4e-4).unwrap()
}
