//! Temperature-dependent bias: a coefficient times the excursion of the temperature profile from
//! its reference (Woodman §3.2.4).

use super::term::{
    note_value_units, ErrorTerm, GenContext, Generate, RawClock, Stage, TermKind, WriteContext,
};
use crate::config::error::ConfigError;
use crate::config::read::{ReadContext, Text};
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check_finite, ModelError};
use crate::temperature::TemperatureProfile;
use crate::units::{Quantity, Signal};
use crate::ImuRng;

/// Bias per degC away from the reference temperature (rad/s/degC, m/s^2/degC), signed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemperatureBias {
    per_degree: f64,
}

impl TemperatureBias {
    /// Any finite value.
    pub fn new(per_degree: f64) -> Result<TemperatureBias, ModelError> {
        Ok(TemperatureBias {
            per_degree: check_finite("temperature bias coefficient", per_degree)?,
        })
    }

    /// The coefficient, per degC.
    pub fn per_degree(&self) -> f64 {
        self.per_degree
    }
}

impl ErrorTerm for TemperatureBias {
    /// A constant temperature: a constant bias c (T - Tref) (docs/model.md §1.5 Table 2: a
    /// residual temperature bias integrates like a constant bias). A steady ramp: a rate ramp c r
    /// and a bias c (T0 - Tref) (the k-fold integrals of c (T0 - Tref) and of c r t, docs/model.md
    /// §4 bias row), in that order. Any other profile: no law.
    fn law_sources(&self, cx: &LawSourceContext) -> Vec<LawSource> {
        let (c, reference) = (self.per_degree, cx.temperature_reference_c);
        match *cx.temperature {
            TemperatureProfile::Constant { temp_c } => {
                vec![LawSource::Bias(c * (temp_c - reference))]
            }
            TemperatureProfile::Ramp {
                start_c,
                rate_c_per_s,
                end_c: None,
            } => vec![
                LawSource::Ramp(c * rate_c_per_s),
                LawSource::Bias(c * (start_c - reference)),
            ],
            _ => vec![LawSource::NoLaw(
                "temperature bias under a varying temperature profile".into(),
            )],
        }
    }

    /// The coefficient (signed), named `coefficient` (docs/cli.md).
    fn level(&self) -> Option<(&'static str, f64)> {
        Some(("coefficient", self.per_degree))
    }

    fn config_value(&self, cx: &WriteContext) -> String {
        cx.quoted(self.per_degree, Quantity::PerDegree(cx.sig))
    }
}

impl TermKind for TemperatureBias {
    const STOCHASTIC: bool = false;
    const LONG_TERM: bool = true;
    const FREE_PARAMETERS: usize = 1;
    const SHOWS_IN_STATIC_LOG: bool = false;
    type Raw = Text;
    const EXAMPLE: Option<&'static str> = Some("temperature_bias = \"0.01 deg/s/degC\"");

    fn with_level(&self, level: f64) -> Result<TemperatureBias, ModelError> {
        TemperatureBias::new(level)
    }

    fn from_raw(raw: &Text, cx: &ReadContext) -> Result<TemperatureBias, ConfigError> {
        let value = cx.value(raw, Quantity::PerDegree(cx.sig), false)?;
        TemperatureBias::new(value).map_err(|e| cx.refused(&cx.key, e))
    }

    fn note_units(value: &toml::Value, sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value)) {
        note_value_units(value, Quantity::PerDegree(sig), sig, note);
    }

    type Generator = TemperatureBiasGenerator;

    fn generator(&self, cx: &GenContext, _rng: &dyn Fn() -> ImuRng) -> TemperatureBiasGenerator {
        TemperatureBiasGenerator {
            per_degree: self.per_degree,
            profile: cx.temperature.clone(),
            reference_c: cx.temperature_reference_c,
        }
    }
}

/// c (T(t) - T_ref).
#[derive(Clone, Debug)]
pub struct TemperatureBiasGenerator {
    per_degree: f64,
    profile: TemperatureProfile,
    reference_c: f64,
}

impl Generate for TemperatureBiasGenerator {
    fn stage(&self) -> Stage {
        Stage::Raw
    }

    #[inline]
    fn add_raw(&mut self, clock: RawClock, out: &mut [f64], _scratch: &mut Vec<f64>) {
        let (c, reference) = (self.per_degree, self.reference_c);
        out.iter_mut()
            .enumerate()
            .for_each(|(i, v)| *v += c * (self.profile.at(clock.t(i)) - reference));
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> TemperatureBias {
    TemperatureBias::new(1e-5).unwrap()
}
