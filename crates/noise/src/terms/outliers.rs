//! Isolated outliers (spikes) on the output register.

use super::term::{
    note_value_units, ErrorTerm, GenContext, Generate, Stage, TermKind, WriteContext,
};
use crate::config::error::ConfigError;
use crate::config::read::{ReadContext, Text};
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check, ModelError};
use crate::units::{Quantity, Signal};
use crate::ImuRng;
use rand::Rng;

/// Isolated outliers: single output samples displaced by `size` (rad/s or m/s^2) with a random sign,
/// each output sample independently with probability p = `rate_per_hour` dt / 3600 (a Bernoulli
/// process: Poisson arrivals at the given rate on the sample grid). Applied to the output register,
/// after the filter and before quantisation. Their Allan variance is that of white noise of variance
/// p size^2 per sample (independent, zero mean): p size^2 / m at tau = m dt.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outliers {
    rate_per_hour: f64,
    size: f64,
}

impl Outliers {
    /// Checks the rate and the size (finite, >= 0).
    pub fn new(rate_per_hour: f64, size: f64) -> Result<Outliers, ModelError> {
        Ok(Outliers {
            rate_per_hour: check("outlier rate", rate_per_hour, false)?,
            size: check("outlier size", size, false)?,
        })
    }

    /// Mean number of outliers per hour.
    pub fn rate_per_hour(&self) -> f64 {
        self.rate_per_hour
    }

    /// The displacement of one outlier (signal units).
    pub fn size(&self) -> f64 {
        self.size
    }

    /// Probability that one output sample of interval `dt_s` is an outlier.
    pub fn probability(&self, dt_s: f64) -> f64 {
        (self.rate_per_hour * dt_s / 3600.0).min(1.0)
    }
    /// Exact Allan variance at tau = m dt of the outlier train alone.
    pub fn avar_sampled(&self, tau_s: f64, dt_s: f64) -> f64 {
        let m = (tau_s / dt_s).round().max(1.0);
        self.probability(dt_s) * self.size * self.size / m
    }
}

/// `outliers = { rate, size }` as written.
#[derive(serde::Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawOutliers {
    rate: Text,
    size: Text,
}

impl ErrorTerm for Outliers {
    /// Each output sample is an independent outlier with probability p, size +-a: white noise of
    /// variance p a^2 per sample, density a sqrt(p dt).
    fn law_sources(&self, cx: &LawSourceContext) -> Vec<LawSource> {
        vec![LawSource::White(
            self.size * (self.probability(cx.dt_s) * cx.dt_s).sqrt(),
        )]
    }

    /// White noise of variance p size^2 per output sample (no continuous form: p needs dt).
    fn allan_variance_sampled(&self, tau_s: f64, dt_s: f64) -> Option<f64> {
        Some(self.avar_sampled(tau_s, dt_s))
    }

    fn config_value(&self, cx: &WriteContext) -> String {
        format!(
            "{{ rate = \"{} /h\", size = {} }}",
            (cx.number)(self.rate_per_hour),
            cx.quoted(self.size, Quantity::Signal(cx.sig))
        )
    }
}

impl TermKind for Outliers {
    const STOCHASTIC: bool = true;
    const LONG_TERM: bool = false;
    const FREE_PARAMETERS: usize = 2;
    const SHOWS_IN_STATIC_LOG: bool = true;
    type Raw = RawOutliers;
    const EXAMPLE: Option<&'static str> =
        Some("outliers = { rate = \"60 /h\", size = \"1 deg/s\" }");

    /// `rate` in events per time (`"60 /h"`, `"2 /min"`, `"0.01 /s"`, or a plain number per hour),
    /// `size` in the signal's unit.
    fn from_raw(raw: &RawOutliers, cx: &ReadContext) -> Result<Outliers, ConfigError> {
        let rate = cx.ctx.per_hour(&cx.sub("rate"), &raw.rate)?;
        let size_key = cx.sub("size");
        let size = cx
            .ctx
            .value(&size_key, &raw.size, Quantity::Signal(cx.sig), true)?;
        Outliers::new(rate, size).map_err(|e| {
            cx.ctx
                .invalid_at(&size_key, Some(&raw.size), e.expected, e.to_string())
        })
    }

    fn note_units(value: &toml::Value, sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value)) {
        note_value_units(value, Quantity::Signal(sig), sig, note);
    }

    type Generator = OutlierState;

    /// One outlier per output sample with probability p (at the output interval).
    fn generator(&self, cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> OutlierState {
        OutlierState::new(self.probability(cx.dt_out_s), self.size, rng())
    }
}

/// Outliers: the index of the next one and the draws (geometric gaps, random sign).
#[derive(Clone, Debug)]
pub struct OutlierState {
    p: f64,
    size: f64,
    next: u64,
    rng: ImuRng,
}

impl OutlierState {
    fn new(p: f64, size: f64, mut rng: ImuRng) -> OutlierState {
        let first = Self::gap(p, &mut rng);
        OutlierState {
            p,
            size,
            next: first.saturating_sub(1),
            rng,
        }
    }

    /// Samples to the next outlier (>= 1): geometric with success probability p (a Bernoulli process).
    fn gap(p: f64, rng: &mut ImuRng) -> u64 {
        if p <= 0.0 {
            return u64::MAX;
        }
        if p >= 1.0 {
            return 1;
        }
        let u: f64 = 1.0 - rng.gen::<f64>(); // (0, 1]
        1 + (u.ln() / (-p).ln_1p()).floor().min(1e18) as u64
    }

    fn add(&mut self, k0: u64, out: &mut [f64]) {
        let end = k0 + out.len() as u64;
        while self.next < end {
            let sign = if self.rng.gen::<bool>() { 1.0 } else { -1.0 };
            out[(self.next - k0) as usize] += sign * self.size;
            self.next = self.next.saturating_add(Self::gap(self.p, &mut self.rng));
        }
    }
}

impl Generate for OutlierState {
    fn stage(&self) -> Stage {
        Stage::Output
    }

    fn output(&mut self, k0: u64, _dt_s: f64, out: &mut [f64]) {
        self.add(k0, out);
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> Outliers {
    Outliers::new(60.0, 0.1).unwrap()
}
