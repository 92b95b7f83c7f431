//! Quantisation of the integrated output (docs/model.md §2: the tau^-1 slope of the Allan deviation).

use super::term::{
    note_value_units, ErrorTerm, GenContext, Generate, Stage, TermKind, WriteContext,
};
use crate::closed_form as cf;
use crate::config::error::ConfigError;
use crate::config::read::{ReadContext, Text};
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check, ModelError};
use crate::units::{Quantity, Signal};
use crate::ImuRng;
use rand::Rng;

/// Quantisation coefficient Q of the integrated output (rad or m/s); the LSB of the integrated
/// output is Q·sqrt(12) (Hou §4.3.1: Q = LSB/sqrt(12)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quantization {
    q: f64,
}

impl Quantization {
    /// A finite value >= 0.
    pub fn new(q: f64) -> Result<Quantization, ModelError> {
        Ok(Quantization {
            q: check("quantization coefficient", q, false)?,
        })
    }

    /// Q (rad or m/s).
    pub fn coefficient(&self) -> f64 {
        self.q
    }
}

impl ErrorTerm for Quantization {
    /// No law: the error of the quantised integrated output is bounded by the LSB and depends on
    /// the dither the other terms provide; docs/model.md §4 has no closed form.
    fn law_sources(&self, _cx: &LawSourceContext) -> Vec<LawSource> {
        vec![LawSource::NoLaw(
            "quantisation: the error of the quantised integrated output is bounded by the LSB and depends on the dither from the other terms; no closed form in docs/model.md §4".into(),
        )]
    }

    /// Q, named `q` (docs/cli.md).
    fn level(&self) -> Option<(&'static str, f64)> {
        Some(("q", self.q))
    }

    /// sigma^2 = 3 Q^2 / tau^2 (Hou 4.29), sampled or not; the output filter does not act on it
    /// (quantisation is of the output register).
    fn allan_variance(&self, tau_s: f64) -> Option<f64> {
        Some(cf::quantization_avar(self.q, tau_s))
    }

    fn config_value(&self, cx: &WriteContext) -> String {
        cx.quoted(self.q, Quantity::Integrated(cx.sig))
    }
}

impl TermKind for Quantization {
    const STOCHASTIC: bool = true;
    const LONG_TERM: bool = false;
    const FREE_PARAMETERS: usize = 1;
    const SHOWS_IN_STATIC_LOG: bool = true;
    type Raw = Text;
    const EXAMPLE: Option<&'static str> = Some("quantization = \"0.001 deg\"");

    fn with_level(&self, level: f64) -> Result<Quantization, ModelError> {
        Quantization::new(level)
    }

    fn from_raw(raw: &Text, cx: &ReadContext) -> Result<Quantization, ConfigError> {
        let value = cx.value(raw, Quantity::Integrated(cx.sig), true)?;
        Quantization::new(value).map_err(|e| cx.refused(&cx.key, e))
    }

    fn note_units(value: &toml::Value, sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value)) {
        note_value_units(value, Quantity::Integrated(sig), sig, note);
    }

    type Generator = Quantizer;

    /// The quantiser's phase is the term's one draw.
    fn generator(&self, _cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> Quantizer {
        Quantizer::new(self.q, &mut rng())
    }
}

/// Quantisation of the integrated output (docs/cli.md: so its Allan signature is the tau^-1 slope):
/// the output released in a sample is a whole number of LSBs of the integral, LSB = Q sqrt(12)
/// (Hou §4.3.1, Q = LSB/sqrt(12)). `residual` is the integral not yet released.
#[derive(Clone, Copy, Debug)]
pub struct Quantizer {
    lsb: f64,
    residual: f64,
}

impl Quantizer {
    /// The quantiser's phase on the LSB grid is drawn from `rng`, so no run starts on a step.
    pub fn new<R: Rng + ?Sized>(q: f64, rng: &mut R) -> Quantizer {
        let lsb = q * 12f64.sqrt();
        Quantizer {
            lsb,
            residual: lsb * (rng.gen::<f64>() - 0.5),
        }
    }
    #[inline]
    pub fn apply(&mut self, value: f64, dt_s: f64) -> f64 {
        self.residual += value * dt_s;
        let n = (self.residual / self.lsb).round();
        self.residual -= n * self.lsb;
        n * self.lsb / dt_s
    }
}

impl Generate for Quantizer {
    fn stage(&self) -> Stage {
        Stage::Output
    }

    /// Q = 0 is a continuous output (no grid): the values pass unchanged. (Q = 0 is a valid
    /// level: `drift`'s parametric bootstrap can draw it.)
    fn output(&mut self, _k0: u64, dt_s: f64, out: &mut [f64]) {
        if self.lsb > 0.0 {
            out.iter_mut().for_each(|v| *v = self.apply(*v, dt_s));
        }
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> Quantization {
    Quantization::new(1e-3).unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quantiser of Q = 0 leaves every value as it is (it once gave 0/0 = NaN).
    #[test]
    fn zero_q_passes_values_unchanged() {
        let mut g = Quantizer::new(
            0.0,
            &mut crate::term_rng(1, 0, 0, crate::Effect::Quantization),
        );
        let mut out = [0.25, -3.0, 1e-9];
        g.output(0, 0.01, &mut out);
        assert_eq!(out, [0.25, -3.0, 1e-9]);
    }
}
