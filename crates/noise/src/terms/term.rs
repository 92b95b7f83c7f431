//! What every error effect provides, implemented by each effect's parameter type in its own file
//! under `terms/`: [`ErrorTerm`], what a value of it does (callable through a `Term`), and
//! [`TermKind`], what the type is. The registry (`terms/mod.rs`) ties each type to its effect.

use crate::filter::FilteredAllan;
use std::fmt;

/// What one error effect's validated parameters (SI) do. Every method has a default for an
/// effect it does not apply to, so a file states only what its effect does.
pub trait ErrorTerm: fmt::Debug {
    /// Allan variance of a continuous record at averaging time `tau_s` (docs/model.md §2), `None`
    /// when the term adds nothing (or, like outliers, needs the sample interval).
    fn allan_variance(&self, _tau_s: f64) -> Option<f64> {
        None
    }

    /// Exact Allan variance of the generated series at sample interval `dt_s` (`tau_s` a multiple
    /// of it); by default the continuous form, where sampling does not change it.
    fn allan_variance_sampled(&self, tau_s: f64, _dt_s: f64) -> Option<f64> {
        self.allan_variance(tau_s)
    }

    /// Exact Allan variance at output interval `dt_s` behind the output filter `fa`; by default
    /// the sampled form, for terms the filter does not touch (quantisation and outliers act on the
    /// output register, and unit DC gain keeps a ramp a ramp).
    fn allan_variance_filtered(&self, tau_s: f64, dt_s: f64, _fa: &FilteredAllan) -> Option<f64> {
        self.allan_variance_sampled(tau_s, dt_s)
    }
}

/// What an error effect is, beside what its values do.
pub trait TermKind: ErrorTerm + Sized {
    /// A stochastic term with an Allan signature; the others are deterministic or drawn once per
    /// run.
    const STOCHASTIC: bool;
    /// Does a static log's Allan deviation show it (the terms `AxisModel::stochastic_only`
    /// keeps: the stochastic ones, the rate ramp, the sinusoid and the output filter)?
    const SHOWS_IN_STATIC_LOG: bool;
}
