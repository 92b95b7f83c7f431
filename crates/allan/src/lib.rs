//! Allan-family deviations of sensor logs, their confidence intervals, and the IEEE 952
//! noise-term fit: the project's measuring instrument.
//!
//! Units: the deviations carry the unit of the input samples (rad/s for gyro rate, m/s^2 for
//! accelerometer specific force, seconds for clock phase data); averaging times are seconds.
//! No frames are involved: every channel is a scalar time series.
//!
//! Definitions follow NIST SP 1065 (Riley 2008) as implemented in allantools and Stable32, so
//! the results agree with the Stable32 reference tables (tested against them):
//! - non-overlapping Allan deviation, SP 1065 eq (7) = Woodman TR-696 eq (19),
//! - overlapping Allan deviation, SP 1065 eq (11),
//! - modified Allan deviation, SP 1065 eq (14),
//! - Hadamard and overlapping Hadamard deviation, SP 1065 eqs (18) and (20),
//! - total deviation, SP 1065 eq (25) (doubly reflected phase),
//! - modified total and Hadamard total deviation, SP 1065 eq (27) and §5.2.13, Theo1, SP 1065
//!   eq (30) (tau = 0.75 m tau0, even m), and TheoH, SP 1065 §5.2.14 ([`total`], which also
//!   holds the gap-tolerant Allan sum and the time-interval errors MTIE and TIE rms).
//!
//! Rate samples y_k (one per `tau0_s`) are turned into phase x_0 = 0, x_n = tau0 * sum_{k<n} (y_k - mean)
//! (docs/model.md §2.1; the mean removal is allantools' `frequency2phase`), summed with compensated
//! (TwoSum) summation so the phase carries no accumulated rounding error.
//!
//! The per-tau cost is O(N) with no allocation besides the phase array (computed in the
//! rate's own buffer by [`Series::from_rate`], in parallel over fixed blocks so the result does
//! not depend on the thread count): the overlapping estimators share one cache-blocked pass
//! for every tau up to m = 2^16 (then one pass per tau), the modified estimator uses
//! allantools' running-sum recursion, and the noise identification works on phase differences
//! (block averages): a pass for the line, a pass for the lag-1 ACF of order 0, and one for
//! the differenced orders only where order 0 does not decide. The hot kernels also exist
//! compiled for AVX2 and AVX-512, chosen at run time, with identical results.
//! Intervals: `edf` (Greenhall, SP 1065 Tables 5 and 7, lag-1 ACF noise identification) and
//! `chi2` (SP 1065 eq 45); the IEEE 952 term fit: `fit`; the spec-sheet readings, each a value
//! where the curve resolves it and a bound where not: `sheet`.
//!
//! The overlapping Allan deviation of white rate noise of standard deviation sigma sampled every
//! tau0 is sigma sqrt(tau0 / tau) (SP 1065 Table 2 for white FM):
//!
//! ```
//! use allan::{deviation, DataKind, Estimator, TauGrid};
//!
//! // Unit-variance white noise (testkit's small test generator).
//! let mut gen = testkit::SplitMix64::new(42);
//! let rate: Vec<f64> = (0..1 << 15).map(|_| gen.normal()).collect();
//! let tau0_s = 0.01;
//! let curve = deviation(&rate, DataKind::Rate, tau0_s, Estimator::Overlapping, &TauGrid::Octave);
//! assert_eq!(curve[0].m, 1);
//! for p in curve.iter().filter(|p| p.m <= 64) {
//!     let expected = (tau0_s / p.tau_s).sqrt();
//!     // Each estimate within 15 % (at m = 64 its own standard error is about 4 %), and the
//!     // one-sigma interval holds what it estimates.
//!     assert!((p.dev / expected - 1.0).abs() < 0.15, "tau {}: {} vs {expected}", p.tau_s, p.dev);
//!     assert!(p.lo < p.dev && p.dev < p.hi);
//! }
//! ```

pub mod chi2;
pub mod claims;
mod curve;
pub mod edf;
pub mod fit;
mod grid;
pub mod null;
pub mod null_table;
mod null_table_data;
pub mod plan;
pub mod sheet;

mod analysis;
mod kernels;
mod phase;
mod series;
mod sum;
pub mod total;

pub use analysis::{analyse, analyse_rate, analyse_rate_until, analyse_until, Analysis};
pub use grid::TauGrid;
pub use phase::{rate_to_phase, rate_to_phase_in_place, rate_to_phase_into};
pub use series::{deviation, deviation_with, Series};
pub use sum::compensated_sum;

use serde::{Deserialize, Serialize};

/// What the samples are.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum DataKind {
    /// Frequency-like samples: gyro rate, specific force, fractional frequency.
    Rate,
    /// Integrated samples: angle, velocity, clock phase (time error).
    Phase,
}

/// The Allan-family estimator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Estimator {
    /// Non-overlapping Allan deviation, SP 1065 eq (7), Woodman eq (19).
    NonOverlapping,
    /// Overlapping Allan deviation, SP 1065 eq (11).
    Overlapping,
    /// Modified Allan deviation, SP 1065 eq (14).
    Modified,
    /// Non-overlapping Hadamard deviation, SP 1065 eq (18): insensitive to a rate ramp.
    Hadamard,
    /// Overlapping Hadamard deviation, SP 1065 eq (20): insensitive to a rate ramp.
    OverlappingHadamard,
    /// Total deviation, SP 1065 eq (25).
    Total,
    /// Modified total deviation, SP 1065 eq (27): each 3m-point subsequence detrended and
    /// reflected (Howe & Vernotte 1999).
    ModifiedTotal,
    /// Hadamard total deviation, SP 1065 §5.2.13 (Howe et al. 2005): the modified total's
    /// reflection on frequency data; insensitive to a rate ramp.
    HadamardTotal,
    /// Theo1, SP 1065 eq (30) (Howe & Tasset 2004): even factors m, tau = 0.75 m tau0.
    Theo1,
    /// TheoH, SP 1065 §5.2.14: the overlapping Allan deviation below a tenth of the record,
    /// bias-removed Theo1 (TheoBR) beyond.
    TheoH,
}

impl Estimator {
    /// All estimators, in a fixed order.
    pub const ALL: [Estimator; 10] = [
        Estimator::NonOverlapping,
        Estimator::Overlapping,
        Estimator::Modified,
        Estimator::Hadamard,
        Estimator::OverlappingHadamard,
        Estimator::Total,
        Estimator::ModifiedTotal,
        Estimator::HadamardTotal,
        Estimator::Theo1,
        Estimator::TheoH,
    ];

    /// Short name as used on the command line and by allantools (`adev`, `oadev`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Estimator::NonOverlapping => "adev",
            Estimator::Overlapping => "oadev",
            Estimator::Modified => "mdev",
            Estimator::Hadamard => "hdev",
            Estimator::OverlappingHadamard => "ohdev",
            Estimator::Total => "totdev",
            Estimator::ModifiedTotal => "mtotdev",
            Estimator::HadamardTotal => "htotdev",
            Estimator::Theo1 => "theo1",
            Estimator::TheoH => "theoh",
        }
    }

    /// Parse a short name (`adev`, `oadev`, `mdev`, `hdev`, `ohdev`, `totdev`, `mtotdev`,
    /// `htotdev`, `theo1`, `theoh`).
    pub fn from_name(name: &str) -> Option<Estimator> {
        Estimator::ALL.into_iter().find(|e| e.name() == name)
    }

    /// Stable32's "stop ratio": the largest averaging factor is N / ratio with N the number
    /// of frequency points (Riley, "Evolution of frequency stability analysis software",
    /// Table III; quoted in allantools `tau_generator`). Checked against the last rows of
    /// the Stable32 octave and decade tables (adev to totdev; the others are the table's).
    pub fn stable32_stop_ratio(self) -> usize {
        match self {
            Estimator::NonOverlapping | Estimator::Hadamard => 5,
            Estimator::Overlapping | Estimator::Modified | Estimator::OverlappingHadamard => 4,
            Estimator::Total | Estimator::ModifiedTotal => 2,
            Estimator::HadamardTotal => 3,
            Estimator::Theo1 | Estimator::TheoH => 1,
        }
    }

    /// Order of the difference: 2 for Allan-type, 3 for Hadamard-type (Greenhall's d).
    pub fn difference_order(self) -> u32 {
        match self {
            Estimator::Hadamard | Estimator::OverlappingHadamard | Estimator::HadamardTotal => 3,
            _ => 2,
        }
    }
}

/// One point of a deviation curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AllanPoint {
    /// Averaging time tau = m * tau0, seconds.
    pub tau_s: f64,
    /// Averaging factor.
    pub m: usize,
    /// The deviation, in the unit of the rate samples.
    pub dev: f64,
    /// Number of terms in the estimator's sum (Stable32's "#" column).
    pub n_terms: usize,
    /// Equivalent degrees of freedom (`NaN` when none was computed).
    pub edf: f64,
    /// Lower bound of the confidence interval (`NaN` when none was computed).
    pub lo: f64,
    /// Upper bound of the confidence interval (`NaN` when none was computed).
    pub hi: f64,
    /// Number of non-overlapping bins of length tau in the record (Woodman §5.1).
    pub bins: usize,
    /// Power-law noise exponent alpha (rate PSD ~ f^alpha) used for the EDF.
    pub alpha: i32,
}

impl AllanPoint {
    /// Woodman's rule for eq (19): a tau is trustworthy only with at least 9 bins.
    pub fn woodman_ok(&self) -> bool {
        self.bins >= WOODMAN_MIN_BINS
    }

    /// Standard error of ln(dev) from the EDF: the estimated variance is chi-squared with
    /// `edf` degrees of freedom (SP 1065 §5.2), so Var(ln var) ~ 2/edf and
    /// Var(ln dev) ~ 1/(2 edf) (delta method). The diagnose gap z = (ln a - ln b)/s uses this.
    pub fn ln_dev_se(&self) -> f64 {
        (0.5 / self.edf).sqrt()
    }
}

/// Woodman TR-696 §5.1: split the log into at least 9 bins.
pub const WOODMAN_MIN_BINS: usize = 9;

/// One-sigma confidence level erf(1/sqrt 2), SP 1065 §5.3 / allantools `ONE_SIGMA_CI`.
pub const ONE_SIGMA_CI: f64 = 0.682_689_492_137_085_9;

/// How the confidence interval is obtained.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum EdfMethod {
    /// No EDF, no interval (fastest).
    None,
    /// Greenhall's general algorithm (Greenhall & Riley 2004), noise type by lag-1 ACF.
    Greenhall,
    /// NIST SP 1065 Table 5 simple formulas (Allan-type estimators only; others use Greenhall).
    Simple,
}

/// Options of [`deviation_with`].
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    pub edf: EdfMethod,
    /// Confidence level of the interval (default: one sigma).
    pub confidence: f64,
    /// Use this noise exponent alpha instead of identifying it per tau.
    pub alpha: Option<i32>,
    /// Cut the tau grid at Stable32's stop ratio (default true). Explicit grids are not cut.
    pub stable32_stop: bool,
    /// Divide the total variance by its flicker / random-walk FM bias (SP 1065 §5.2.11), as
    /// Stable32 does, once the noise type is known (default true).
    pub totvar_bias_correction: bool,
    /// The family-wise level at which a fitted term counts as resolved ([`null`]).
    pub claims: claims::ClaimLevel,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            edf: EdfMethod::Greenhall,
            confidence: ONE_SIGMA_CI,
            alpha: None,
            stable32_stop: true,
            totvar_bias_correction: true,
            claims: claims::ClaimLevel::default(),
        }
    }
}

#[cfg(test)]
mod tests;
