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
//! - total deviation, SP 1065 eq (25) (doubly reflected phase).
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
//! `chi2` (SP 1065 eq 45); the IEEE 952 term fit and spec-sheet readings: `fit`.

pub mod chi2;
pub mod edf;
pub mod fit;
mod grid;
pub mod plan;
pub mod testdata;

pub use grid::TauGrid;

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
}

impl Estimator {
    /// All estimators, in a fixed order.
    pub const ALL: [Estimator; 6] = [
        Estimator::NonOverlapping,
        Estimator::Overlapping,
        Estimator::Modified,
        Estimator::Hadamard,
        Estimator::OverlappingHadamard,
        Estimator::Total,
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
        }
    }

    /// Parse a short name (`adev`, `oadev`, `mdev`, `hdev`, `ohdev`, `totdev`).
    pub fn from_name(name: &str) -> Option<Estimator> {
        Estimator::ALL.into_iter().find(|e| e.name() == name)
    }

    /// Stable32's "stop ratio": the largest averaging factor is N / ratio with N the number
    /// of frequency points (Riley, "Evolution of frequency stability analysis software",
    /// Table III; quoted in allantools `tau_generator`). Checked against the last rows of
    /// the Stable32 octave and decade tables.
    pub fn stable32_stop_ratio(self) -> usize {
        match self {
            Estimator::NonOverlapping | Estimator::Hadamard => 5,
            Estimator::Overlapping | Estimator::Modified | Estimator::OverlappingHadamard => 4,
            Estimator::Total => 2,
        }
    }

    /// Order of the difference: 2 for Allan-type, 3 for Hadamard-type (Greenhall's d).
    pub fn difference_order(self) -> u32 {
        match self {
            Estimator::Hadamard | Estimator::OverlappingHadamard => 3,
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
}

impl Default for Options {
    fn default() -> Self {
        Options {
            edf: EdfMethod::Greenhall,
            confidence: ONE_SIGMA_CI,
            alpha: None,
            stable32_stop: true,
            totvar_bias_correction: true,
        }
    }
}

/// Deviation curve with default options (Greenhall EDF, one-sigma interval, Stable32 stop ratio).
pub fn deviation(
    data: &[f64],
    kind: DataKind,
    tau0_s: f64,
    est: Estimator,
    grid: &TauGrid,
) -> Vec<AllanPoint> {
    deviation_with(data, kind, tau0_s, est, grid, &Options::default())
}

/// Deviation curve with explicit options.
pub fn deviation_with(
    data: &[f64],
    kind: DataKind,
    tau0_s: f64,
    est: Estimator,
    grid: &TauGrid,
    opts: &Options,
) -> Vec<AllanPoint> {
    let series = Series::new(data, kind, tau0_s);
    let ms = series.grid_m(est, grid, opts.stable32_stop);
    let mut points = series.raw_points(est, &ms);
    series.attach_intervals(est, &mut points, opts);
    points
}

/// A time series prepared once for many deviations: the phase array (and, for phase input,
/// the original samples for noise identification).
pub struct Series<'a> {
    phase: Vec<f64>,
    /// Number of rate samples, for rate input.
    rate_len: Option<usize>,
    source_phase: Option<&'a [f64]>,
    tau0_s: f64,
}

impl<'a> Series<'a> {
    /// Prepare `data` sampled every `tau0_s` seconds.
    pub fn new(data: &'a [f64], kind: DataKind, tau0_s: f64) -> Series<'a> {
        match kind {
            DataKind::Rate => Series {
                phase: rate_to_phase(data, tau0_s),
                rate_len: Some(data.len()),
                source_phase: None,
                tau0_s,
            },
            DataKind::Phase => Series {
                phase: data.to_vec(),
                rate_len: None,
                source_phase: Some(data),
                tau0_s,
            },
        }
    }

    /// Prepare rate samples given by value: the phase is computed in their buffer (no second
    /// array of the record's size). Same result as [`Series::new`] with [`DataKind::Rate`].
    pub fn from_rate(data: Vec<f64>, tau0_s: f64) -> Series<'static> {
        let rate_len = data.len();
        Series {
            phase: rate_to_phase_in_place(data, tau0_s),
            rate_len: Some(rate_len),
            source_phase: None,
            tau0_s,
        }
    }

    /// Number of phase points (rate samples + 1).
    pub fn phase_len(&self) -> usize {
        self.phase.len()
    }

    /// Sample interval, seconds.
    pub fn tau0_s(&self) -> f64 {
        self.tau0_s
    }

    /// The averaging factors of a grid for this series and estimator.
    pub fn grid_m(&self, est: Estimator, grid: &TauGrid, stable32_stop: bool) -> Vec<usize> {
        let n_phase = self.phase.len();
        let max_m = match grid {
            TauGrid::Explicit(_) => usize::MAX,
            _ if stable32_stop => n_phase.saturating_sub(1) / est.stable32_stop_ratio(),
            _ => usize::MAX,
        };
        grid.ms(n_phase)
            .into_iter()
            .filter(|&m| m >= 1 && m <= max_m && m < n_phase)
            .collect()
    }

    /// The deviation at averaging factor `m` without interval (`None` if fewer than 2 terms).
    pub fn raw_point(&self, est: Estimator, m: usize) -> Option<AllanPoint> {
        let (sum_sq, n_terms) = estimator_sum_fast(&self.phase, est, m)?;
        self.point_from_sum(est, m, sum_sq, n_terms)
    }

    /// The deviations at all `ms` without intervals, skipping factors with fewer than 2 terms.
    /// The overlapping estimators use one cache-blocked pass for all small factors (the phase
    /// array is streamed from memory once instead of once per tau); the result is identical to
    /// [`Series::raw_point`] up to the order of the floating-point additions.
    pub fn raw_points(&self, est: Estimator, ms: &[usize]) -> Vec<AllanPoint> {
        let multi = match est {
            Estimator::Overlapping => Some(2),
            Estimator::OverlappingHadamard => Some(3),
            _ => None,
        };
        let Some(order) = multi else {
            return ms.iter().filter_map(|&m| self.raw_point(est, m)).collect();
        };
        let n = self.phase.len();
        let valid: Vec<usize> = ms
            .iter()
            .copied()
            .filter(|&m| m >= 1 && order * m < n)
            .collect();
        // Factors whose reuse window fits in cache go through the blocked kernel together.
        let (small, large): (Vec<usize>, Vec<usize>) =
            valid.iter().partition(|&&m| m <= BLOCKED_MAX_M);
        let sums = blocked_diff_sums_fast(&self.phase, &small, order);
        let mut out: Vec<AllanPoint> = small
            .iter()
            .zip(sums)
            .filter_map(|(&m, s)| self.point_from_sum(est, m, s, n - order * m))
            .collect();
        out.extend(large.iter().filter_map(|&m| self.raw_point(est, m)));
        out
    }

    fn point_from_sum(
        &self,
        est: Estimator,
        m: usize,
        sum_sq: f64,
        n_terms: usize,
    ) -> Option<AllanPoint> {
        if n_terms < 2 {
            return None;
        }
        let tau_s = m as f64 * self.tau0_s;
        let var = match est {
            // SP 1065 eqs (7), (11): sigma^2 = sum / (2 tau^2 n)
            Estimator::NonOverlapping | Estimator::Overlapping => {
                sum_sq / (2.0 * tau_s * tau_s * n_terms as f64)
            }
            // SP 1065 eq (14): Mod sigma^2 = sum / (2 m^2 tau^2 n)
            Estimator::Modified => sum_sq / (2.0 * (m * m) as f64 * tau_s * tau_s * n_terms as f64),
            // SP 1065 eqs (18), (20): H sigma^2 = sum / (6 tau^2 n)
            Estimator::Hadamard | Estimator::OverlappingHadamard => {
                sum_sq / (6.0 * tau_s * tau_s * n_terms as f64)
            }
            // SP 1065 eq (25): Tot sigma^2 = sum / (2 tau^2 (N - 2))
            Estimator::Total => sum_sq / (2.0 * tau_s * tau_s * n_terms as f64),
        };
        Some(AllanPoint {
            tau_s,
            m,
            dev: var.sqrt(),
            n_terms,
            edf: f64::NAN,
            lo: f64::NAN,
            hi: f64::NAN,
            bins: (self.phase.len() - 1) / m,
            alpha: 0,
        })
    }

    /// Identify the noise type, compute the EDF and the chi-squared interval of each point.
    pub fn attach_intervals(&self, est: Estimator, points: &mut [AllanPoint], opts: &Options) {
        if opts.edf == EdfMethod::None {
            return;
        }
        let d = est.difference_order();
        // One tau per task, each identified by one thread: the same for any thread count.
        use rayon::prelude::*;
        let alphas: Vec<Option<i32>> = points
            .par_iter()
            .map(|p| opts.alpha.or_else(|| self.noise_id(p.m, d)))
            .collect();
        self.attach_intervals_with_alphas(est, points, &alphas, opts);
    }

    /// As [`Series::attach_intervals`] with the noise exponents already identified (callers may
    /// run [`Series::noise_id`] in parallel). Where the record is too short for the lag-1 ACF
    /// method (fewer than 30 averaged points, Riley 2004) `None` is given, and the nearest
    /// shorter tau's alpha is reused (the first identified one for leading gaps).
    pub fn attach_intervals_with_alphas(
        &self,
        est: Estimator,
        points: &mut [AllanPoint],
        alphas: &[Option<i32>],
        opts: &Options,
    ) {
        if opts.edf == EdfMethod::None {
            return;
        }
        let first_known = alphas.iter().flatten().next().copied().unwrap_or(0);
        let n_phase = self.phase.len();
        let mut last = first_known;
        for (p, alpha) in points.iter_mut().zip(alphas) {
            let alpha = alpha.unwrap_or(last);
            last = alpha;
            p.alpha = alpha;
            if est == Estimator::Total && opts.totvar_bias_correction {
                p.dev /= edf::totvar_bias(alpha, p.m, n_phase - 1).sqrt();
            }
            p.edf = edf::edf_for(est, opts.edf, alpha, p.m, n_phase, p.n_terms);
            let (lo, hi) = chi2::confidence_interval(p.dev, p.edf, opts.confidence);
            p.lo = lo;
            p.hi = hi;
        }
    }

    /// Lag-1 autocorrelation noise identification at averaging factor m (Riley 2004),
    /// on the data as given (rate or phase); `None` when too few points.
    pub fn noise_id(&self, m: usize, d_max: u32) -> Option<i32> {
        match (self.rate_len, self.source_phase) {
            (Some(rate_len), _) => {
                // The block averages of the rate are phase differences at stride m
                // (x_{(j+1)m} - x_{jm} = tau0 * sum of the block, mean removed): no pass over
                // the m samples of each block. Scale and offset do not change the ACF.
                let m = m.max(1);
                let blocks = rate_len / m;
                if blocks < 30 {
                    return None;
                }
                let x = &self.phase;
                rate_noise_id_fast(x, m, blocks, d_max)
            }
            (None, Some(x)) => edf::autocorr_noise_id(x, m, DataKind::Phase, d_max),
            _ => None,
        }
    }
}

/// Phase (integrated rate) with x_0 = 0 and x_n = tau0 * sum_{k<n} (y_k - mean(y)),
/// docs/model.md §2.1 and allantools `frequency2phase` (mean removed before the sum to keep the
/// phase small). The running sum is compensated (Knuth's TwoSum error term carried along,
/// as in Neumaier 1974), so x_n is the partial sum to within a few ulps.
pub fn rate_to_phase(rate: &[f64], tau0_s: f64) -> Vec<f64> {
    let mut buf = Vec::with_capacity(rate.len() + 1);
    buf.extend_from_slice(rate);
    rate_to_phase_in_place(buf, tau0_s)
}

/// Samples per block of the phase conversion. Fixed, not per thread: the result does not
/// depend on the thread count.
const PHASE_BLOCK: usize = 1 << 16;

/// [`rate_to_phase`] in the rate's own buffer (x_k overwrites y_k, x_n is appended), in
/// parallel over fixed blocks: the mean from per-block 8-lane sums added in block order; each
/// block's compensated sum (8 lanes of TwoSum, then the lanes in order); the running
/// (sum, error) at every block start from those, in block order; then every block runs the
/// compensated recursion from its start.
pub fn rate_to_phase_in_place(mut buf: Vec<f64>, tau0_s: f64) -> Vec<f64> {
    use rayon::prelude::*;
    let n = buf.len();
    // The mean only keeps the phase small: any rounding in it adds a linear phase trend, which
    // every estimator's differences cancel. Plain 8-lane sums are accurate enough and fast.
    let block_sums: Vec<f64> = buf
        .par_chunks(PHASE_BLOCK)
        .map(|b| {
            let mut lanes = [0.0f64; 8];
            let chunks = b.chunks_exact(8);
            let tail: f64 = chunks.remainder().iter().sum();
            for c in chunks {
                for (l, v) in lanes.iter_mut().zip(c) {
                    *l += v;
                }
            }
            pairwise_lanes(&lanes) + tail
        })
        .collect();
    let mean = block_sums.iter().sum::<f64>() / n.max(1) as f64;
    // Compensated sum of (y - mean) of every block: (sum, error).
    let block_totals: Vec<(f64, f64)> = buf
        .par_chunks(PHASE_BLOCK)
        .map(|b| {
            let (mut s, mut c) = ([0.0f64; 8], [0.0f64; 8]);
            let chunks = b.chunks_exact(8);
            let tail = chunks.remainder();
            for ch in chunks {
                for l in 0..8 {
                    two_sum_acc(&mut s[l], &mut c[l], ch[l] - mean);
                }
            }
            let (mut sum, mut comp) = (0.0f64, c.iter().sum::<f64>());
            for v in s.into_iter().chain(tail.iter().map(|y| y - mean)) {
                two_sum_acc(&mut sum, &mut comp, v);
            }
            (sum, comp)
        })
        .collect();
    let mut starts = Vec::with_capacity(block_totals.len());
    let (mut sum, mut comp) = (0.0f64, 0.0f64);
    for &(s, c) in &block_totals {
        starts.push((sum, comp));
        two_sum_acc(&mut sum, &mut comp, s);
        comp += c;
    }
    buf.par_chunks_mut(PHASE_BLOCK)
        .zip(starts.par_iter())
        .for_each(|(b, &(mut sum, mut comp))| {
            for v in b.iter_mut() {
                let y = *v - mean;
                *v = (sum + comp) * tau0_s;
                two_sum_acc(&mut sum, &mut comp, y);
            }
        });
    buf.push((sum + comp) * tau0_s);
    buf
}

/// sum += v with the exact rounding error added to comp (Knuth's TwoSum, branch-free).
#[inline(always)]
fn two_sum_acc(sum: &mut f64, comp: &mut f64, v: f64) {
    let t = *sum + v;
    let bv = t - *sum;
    *comp += (*sum - (t - bv)) + (v - bv);
    *sum = t;
}

/// `fn name(args) -> ret { body }`, compiled three times: as is, with AVX2 and with AVX-512F
/// enabled, the widest the CPU has chosen at run time (x86-64). The results are the same bit
/// for bit: the kernels' additions are written out in a fixed order (lanes), Rust does not
/// contract a*b+c into FMA, and the vector width only changes how many lanes one instruction
/// does (measured on the 4.32 M-sample benchmark, one thread: blocked kernel 30 ms SSE2,
/// 20 ms AVX2, 17.5 ms AVX-512; noise identification 19.3 -> 16.3 ms from AVX2 to AVX-512).
/// The kernels the body calls are `#[inline(always)]`, so they are compiled inside each variant.
macro_rules! wide_variant {
    ($(#[$meta:meta])* fn $name:ident($($arg:ident: $ty:ty),*) -> $ret:ty $body:block) => {
        $(#[$meta])*
        fn $name($($arg: $ty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx512f")]
                fn avx512($($arg: $ty),*) -> $ret $body
                if std::arch::is_x86_feature_detected!("avx512f") {
                    // SAFETY: the CPU supports AVX-512F (checked just above).
                    return unsafe { avx512($($arg),*) };
                }
                #[target_feature(enable = "avx2")]
                fn avx2($($arg: $ty),*) -> $ret $body
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: the CPU supports AVX2 (checked just above).
                    return unsafe { avx2($($arg),*) };
                }
            }
            $body
        }
    };
}

wide_variant! {
    /// [`blocked_diff_sums`], vectorised as wide as the CPU allows.
    fn blocked_diff_sums_fast(x: &[f64], ms: &[usize], order: usize) -> Vec<f64> {
        blocked_diff_sums(x, ms, order)
    }
}

wide_variant! {
    /// [`estimator_sum`], vectorised as wide as the CPU allows.
    fn estimator_sum_fast(x: &[f64], est: Estimator, m: usize) -> Option<(f64, usize)> {
        estimator_sum(x, est, m)
    }
}

wide_variant! {
    /// Noise identification of rate data from the phase: block sums at stride m.
    fn rate_noise_id_fast(x: &[f64], m: usize, blocks: usize, d_max: u32) -> Option<i32> {
        edf::rate_noise_id_fn(blocks, |j| x[(j + 1) * m] - x[j * m], d_max)
    }
}

/// Neumaier compensated sum.
pub fn compensated_sum(values: impl Iterator<Item = f64>) -> f64 {
    let (mut sum, mut comp) = (0.0f64, 0.0f64);
    for v in values {
        let t = sum + v;
        if sum.abs() >= v.abs() {
            comp += (sum - t) + v;
        } else {
            comp += (v - t) + sum;
        }
        sum = t;
    }
    sum + comp
}

/// Sum of squares of the estimator's differences and the number of terms, or `None` if the
/// record is too short for this m.
#[inline(always)]
fn estimator_sum(x: &[f64], est: Estimator, m: usize) -> Option<(f64, usize)> {
    let n = x.len();
    match est {
        Estimator::Overlapping => {
            let terms = n.checked_sub(2 * m)?;
            // SP 1065 eq (11): sum over n of (x_{n+2m} - 2 x_{n+m} + x_n)^2
            Some((second_diff_sum_sq(x, m, terms), terms))
        }
        Estimator::NonOverlapping => {
            let span = (n - 1).checked_sub(2 * m)?;
            let terms = span / m + 1;
            // SP 1065 eq (7) / Woodman eq (19): stride m
            let s = strided_sum(terms, |i| {
                let j = i * m;
                x[j + 2 * m] - 2.0 * x[j + m] + x[j]
            });
            Some((s, terms))
        }
        Estimator::Hadamard => {
            let span = (n - 1).checked_sub(3 * m)?;
            let terms = span / m + 1;
            // SP 1065 eq (18): third difference, stride m
            let s = strided_sum(terms, |i| {
                let j = i * m;
                x[j + 3 * m] - 3.0 * x[j + 2 * m] + 3.0 * x[j + m] - x[j]
            });
            Some((s, terms))
        }
        Estimator::OverlappingHadamard => {
            let terms = n.checked_sub(3 * m)?;
            // SP 1065 eq (20)
            Some((third_diff_sum_sq(x, m, terms), terms))
        }
        Estimator::Modified => {
            // SP 1065 eq (14), allantools `mdev` / adev_lib.c running sum:
            // v_j = sum_{i=j}^{j+m-1} (x_{i+2m} - 2 x_{i+m} + x_i), updated by
            // v_{j+1} = v_j + x_{j+3m} - 3 x_{j+2m} + 3 x_{j+m} - x_j.
            let terms = (n + 1).checked_sub(3 * m)?;
            if terms == 0 {
                return None;
            }
            let mut v = compensated_sum((0..m).map(|i| x[i + 2 * m] - 2.0 * x[i + m] + x[i]));
            let mut s = v * v;
            let mut vc = 0.0f64;
            for j in 0..terms - 1 {
                let inc = x[j + 3 * m] - 3.0 * x[j + 2 * m] + 3.0 * x[j + m] - x[j];
                let t = v + inc;
                if v.abs() >= inc.abs() {
                    vc += (v - t) + inc;
                } else {
                    vc += (inc - t) + v;
                }
                v = t;
                let w = v + vc;
                s += w * w;
            }
            Some((s, terms))
        }
        Estimator::Total => {
            // SP 1065 eq (25) with the doubly reflected series of allantools `totdev`:
            // x*_{-j} = 2 x_0 - x_j, x*_{n-1+j} = 2 x_{n-1} - x_{n-1-j}, j = 1..n-2;
            // sum over i = 1..n-2 of (x*_{i-m} - 2 x*_i + x*_{i+m})^2.
            if n < 3 || m > n - 2 {
                return None;
            }
            let last = n - 1;
            let get = |i: isize| -> f64 {
                if i < 0 {
                    2.0 * x[0] - x[(-i) as usize]
                } else if (i as usize) > last {
                    let j = i as usize - last;
                    2.0 * x[last] - x[last - j]
                } else {
                    x[i as usize]
                }
            };
            let mi = m as isize;
            let s = strided_sum(n - 2, |k| {
                let i = k as isize + 1;
                get(i - mi) - 2.0 * get(i) + get(i + mi)
            });
            Some((s, n - 2))
        }
    }
}

/// Sum of squares of `f(i)` for i in 0..terms, with four interleaved accumulators
/// (a fixed order: deterministic, and it lets the compiler pipeline the loop).
#[inline(always)]
fn strided_sum(terms: usize, f: impl Fn(usize) -> f64) -> f64 {
    let mut acc = [0.0f64; 4];
    let blocks = terms / 4;
    for b in 0..blocks {
        for (l, a) in acc.iter_mut().enumerate() {
            let v = f(4 * b + l);
            *a += v * v;
        }
    }
    for i in 4 * blocks..terms {
        let v = f(i);
        acc[0] += v * v;
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// Sum over i < terms of (x[i+2m] - 2 x[i+m] + x[i])^2, written over slices so the compiler
/// vectorises it; the lane partial sums are added in a fixed order (deterministic).
#[inline(always)]
fn second_diff_sum_sq(x: &[f64], m: usize, terms: usize) -> f64 {
    const LANES: usize = 8;
    let a = &x[..terms];
    let b = &x[m..m + terms];
    let c = &x[2 * m..2 * m + terms];
    let mut acc = [0.0f64; LANES];
    let mut ca = a.chunks_exact(LANES);
    let mut cb = b.chunks_exact(LANES);
    let mut cc = c.chunks_exact(LANES);
    for ((pa, pb), pc) in (&mut ca).zip(&mut cb).zip(&mut cc) {
        for l in 0..LANES {
            let v = pc[l] - 2.0 * pb[l] + pa[l];
            acc[l] += v * v;
        }
    }
    for ((pa, pb), pc) in ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .zip(cc.remainder())
    {
        let v = pc - 2.0 * pb + pa;
        acc[0] += v * v;
    }
    pairwise_lanes(&acc)
}

/// Sum over i < terms of (x[i+3m] - 3 x[i+2m] + 3 x[i+m] - x[i])^2.
#[inline(always)]
fn third_diff_sum_sq(x: &[f64], m: usize, terms: usize) -> f64 {
    const LANES: usize = 8;
    let a = &x[..terms];
    let b = &x[m..m + terms];
    let c = &x[2 * m..2 * m + terms];
    let d = &x[3 * m..3 * m + terms];
    let mut acc = [0.0f64; LANES];
    let full = terms / LANES * LANES;
    for i in (0..full).step_by(LANES) {
        for (l, slot) in acc.iter_mut().enumerate() {
            let k = i + l;
            let v = d[k] - 3.0 * c[k] + 3.0 * b[k] - a[k];
            *slot += v * v;
        }
    }
    for k in full..terms {
        let v = d[k] - 3.0 * c[k] + 3.0 * b[k] - a[k];
        acc[0] += v * v;
    }
    pairwise_lanes(&acc)
}

/// Largest averaging factor handled by the blocked kernel: its live window, 3 m phase values,
/// is then at most 1.5 MiB and stays in the L2/L3 cache while the block front moves on.
const BLOCKED_MAX_M: usize = 1 << 16;
/// Block length of the blocked kernel (phase values per block and factor).
const BLOCK: usize = 4096;

/// For each m (ascending), the sum over i < n - order*m of the squared `order`-th difference
/// at lag m (order 2: x[i+2m] - 2x[i+m] + x[i]; order 3: the Hadamard third difference),
/// computed block by block for all m together. Each m keeps 8 lane accumulators (lane =
/// i mod 8), so the result does not depend on the block size or on how the caller splits work.
#[inline(always)]
fn blocked_diff_sums(x: &[f64], ms: &[usize], order: usize) -> Vec<f64> {
    const LANES: usize = 8;
    let n = x.len();
    let terms: Vec<usize> = ms.iter().map(|&m| n - order * m).collect();
    let max_terms = terms.iter().copied().max().unwrap_or(0);
    let mut acc = vec![[0.0f64; LANES]; ms.len()];
    let mut start = 0;
    while start < max_terms {
        for ((&m, &t), a) in ms.iter().zip(&terms).zip(acc.iter_mut()) {
            if start >= t {
                continue;
            }
            let end = (start + BLOCK).min(t);
            if order == 2 {
                block_second(x, m, start, end, a);
            } else {
                block_third(x, m, start, end, a);
            }
        }
        start += BLOCK;
    }
    acc.iter().map(pairwise_lanes).collect()
}

/// Accumulate (x[i+2m] - 2x[i+m] + x[i])^2 for i in start..end into lanes i mod 8
/// (start is a multiple of BLOCK, hence of 8).
#[inline(always)]
fn block_second(x: &[f64], m: usize, start: usize, end: usize, acc: &mut [f64; 8]) {
    let len = end - start;
    let a = &x[start..end];
    let b = &x[start + m..end + m];
    let c = &x[start + 2 * m..end + 2 * m];
    let full = len / 8 * 8;
    for ((pa, pb), pc) in a[..full]
        .chunks_exact(8)
        .zip(b[..full].chunks_exact(8))
        .zip(c[..full].chunks_exact(8))
    {
        for l in 0..8 {
            let v = pc[l] - 2.0 * pb[l] + pa[l];
            acc[l] += v * v;
        }
    }
    for k in full..len {
        let v = c[k] - 2.0 * b[k] + a[k];
        acc[k % 8] += v * v;
    }
}

/// As `block_second` for x[i+3m] - 3x[i+2m] + 3x[i+m] - x[i].
#[inline(always)]
fn block_third(x: &[f64], m: usize, start: usize, end: usize, acc: &mut [f64; 8]) {
    let len = end - start;
    let a = &x[start..end];
    let b = &x[start + m..end + m];
    let c = &x[start + 2 * m..end + 2 * m];
    let d = &x[start + 3 * m..end + 3 * m];
    for k in 0..len {
        let v = d[k] - 3.0 * c[k] + 3.0 * b[k] - a[k];
        acc[k % 8] += v * v;
    }
}

#[inline(always)]
fn pairwise_lanes(acc: &[f64; 8]) -> f64 {
    ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic pseudo-random series (SplitMix64 mapped to [-0.5, 0.5)).
    fn series(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
                let mut z = s;
                z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
                z ^= z >> 31;
                (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect()
    }

    /// Direct textbook formulas (no phase, no running sums), O(N m) per tau.
    fn naive(y: &[f64], est: Estimator, m: usize) -> f64 {
        let n = y.len();
        let avg = |k: usize| y[k..k + m].iter().sum::<f64>() / m as f64;
        match est {
            Estimator::Overlapping | Estimator::NonOverlapping => {
                let stride = if est == Estimator::Overlapping { 1 } else { m };
                let mut s = 0.0;
                let mut c = 0;
                let mut k = 0;
                while k + 2 * m <= n {
                    let d = avg(k + m) - avg(k);
                    s += d * d;
                    c += 1;
                    k += stride;
                }
                (s / (2.0 * c as f64)).sqrt()
            }
            Estimator::Hadamard | Estimator::OverlappingHadamard => {
                let stride = if est == Estimator::OverlappingHadamard {
                    1
                } else {
                    m
                };
                let mut s = 0.0;
                let mut c = 0;
                let mut k = 0;
                while k + 3 * m <= n {
                    let d = avg(k + 2 * m) - 2.0 * avg(k + m) + avg(k);
                    s += d * d;
                    c += 1;
                    k += stride;
                }
                (s / (6.0 * c as f64)).sqrt()
            }
            Estimator::Modified => {
                // Mod sigma^2 = 1/(2 m^2 (N-3m+2)) sum_j [sum_{i=j}^{j+m-1} (ybar_{i+m} - ybar_i)]^2
                // with ybar the m-averages (SP 1065 eq (15), frequency form).
                let mut s = 0.0;
                let mut c = 0;
                let mut j = 0;
                while j + 3 * m <= n + 1 {
                    let inner: f64 = (j..j + m).map(|i| avg(i + m) - avg(i)).sum();
                    s += inner * inner;
                    c += 1;
                    j += 1;
                }
                (s / (2.0 * (m * m) as f64 * c as f64)).sqrt()
            }
            Estimator::Total => unreachable!(),
        }
    }

    #[test]
    fn fast_sums_match_textbook_formulas() {
        // Reason for 1e-11: both sides are exact formulas; the difference is rounding only.
        const REL_TOL: f64 = 1e-11;
        let y: Vec<f64> = series(3000, 7).iter().map(|v| 3.0 + v).collect();
        for est in [
            Estimator::Overlapping,
            Estimator::NonOverlapping,
            Estimator::Hadamard,
            Estimator::OverlappingHadamard,
            Estimator::Modified,
        ] {
            for m in [1usize, 2, 3, 7, 50, 333] {
                let p = deviation_with(
                    &y,
                    DataKind::Rate,
                    1.0,
                    est,
                    &TauGrid::Explicit(vec![m]),
                    &Options {
                        edf: EdfMethod::None,
                        ..Options::default()
                    },
                );
                let got = p[0].dev;
                let want = naive(&y, est, m);
                assert!(
                    ((got - want) / want).abs() < REL_TOL,
                    "{est:?} m={m}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn blocked_kernel_matches_single_tau_path() {
        // Same sums, different association of the additions: 1e-12 relative.
        let y = series(300_000, 9);
        let s = Series::new(&y, DataKind::Rate, 0.01);
        let ms: Vec<usize> = (0..17)
            .map(|k| 1usize << k)
            .chain([3, 7, 1000, 4097])
            .collect();
        let mut ms = ms;
        ms.sort_unstable();
        for est in [Estimator::Overlapping, Estimator::OverlappingHadamard] {
            let blocked = s.raw_points(est, &ms);
            let single: Vec<AllanPoint> = ms.iter().filter_map(|&m| s.raw_point(est, m)).collect();
            assert_eq!(blocked.len(), single.len());
            for (p, q) in blocked.iter().zip(&single) {
                assert_eq!((p.m, p.n_terms), (q.m, q.n_terms));
                assert!(((p.dev - q.dev) / q.dev).abs() < 1e-12, "{est:?} m={}", p.m);
            }
        }
    }

    #[test]
    fn wide_vector_variants_give_the_same_bits() {
        // The dispatched kernels (AVX-512 or AVX2 on CPUs that have them) against the same
        // code compiled for the baseline target: identical results, not merely close.
        let y = series(100_003, 11);
        let x = rate_to_phase(&y, 0.01);
        let ms: Vec<usize> = (0..14).map(|k| 1usize << k).chain([3, 4097]).collect();
        let mut ms = ms;
        ms.sort_unstable();
        for order in [2, 3] {
            let fast = blocked_diff_sums_fast(&x, &ms, order);
            let base = blocked_diff_sums(&x, &ms, order);
            assert_eq!(fast.len(), base.len());
            for (a, b) in fast.iter().zip(&base) {
                assert_eq!(a.to_bits(), b.to_bits(), "order {order}");
            }
        }
        for est in [
            Estimator::Overlapping,
            Estimator::OverlappingHadamard,
            Estimator::Modified,
            Estimator::Total,
        ] {
            for m in [1, 5, 64, 20_000] {
                let fast = estimator_sum_fast(&x, est, m).map(|(s, n)| (s.to_bits(), n));
                let base = estimator_sum(&x, est, m).map(|(s, n)| (s.to_bits(), n));
                assert_eq!(fast, base, "{est:?} m={m}");
            }
        }
        for m in [1, 2, 16, 1000] {
            let blocks = y.len() / m;
            let base = edf::rate_noise_id_fn(blocks, |j| x[(j + 1) * m] - x[j * m], 2);
            assert!(base.is_some());
            assert_eq!(rate_noise_id_fast(&x, m, blocks, 2), base, "m={m}");
        }
    }

    #[test]
    fn phase_sum_is_compensated() {
        // A large offset plus small noise over 4M samples: a naive running sum loses about
        // log10(N) digits; the compensated phase must give the m = 1 Allan deviation that the
        // direct first-difference formula gives (no summation at all) to 1e-12.
        const REL_TOL: f64 = 1e-12;
        let n = 4_000_000;
        let y: Vec<f64> = series(n, 11).iter().map(|v| 1.0e3 + 1.0e-3 * v).collect();
        let p = deviation_with(
            &y,
            DataKind::Rate,
            0.01,
            Estimator::Overlapping,
            &TauGrid::Explicit(vec![1]),
            &Options {
                edf: EdfMethod::None,
                ..Options::default()
            },
        );
        let direct: f64 = y
            .windows(2)
            .map(|w| (w[1] - w[0]) * (w[1] - w[0]))
            .sum::<f64>()
            / (2.0 * (n - 1) as f64);
        let direct = direct.sqrt();
        assert!(
            ((p[0].dev - direct) / direct).abs() < REL_TOL,
            "{} vs {}",
            p[0].dev,
            direct
        );
    }

    #[test]
    fn rate_and_phase_input_agree() {
        const REL_TOL: f64 = 1e-10;
        let y = series(2000, 3);
        let x = rate_to_phase(&y, 0.5);
        for est in Estimator::ALL {
            let a = deviation(&y, DataKind::Rate, 0.5, est, &TauGrid::Octave);
            let b = deviation(&x, DataKind::Phase, 0.5, est, &TauGrid::Octave);
            assert_eq!(a.len(), b.len());
            for (p, q) in a.iter().zip(&b) {
                assert_eq!(p.n_terms, q.n_terms);
                assert!(((p.dev - q.dev) / q.dev).abs() < REL_TOL);
            }
        }
    }

    #[test]
    fn hadamard_ignores_a_rate_ramp_allan_does_not() {
        // A rate ramp integrates to a quadratic phase, which every third difference removes
        // exactly (SP 1065 §5.2.8): HDEV of white + ramp equals HDEV of white alone up to
        // rounding (1e-9: the ramp's phase is ~1e4 times the noise's), while OADEV grows.
        let white = series(20_000, 21);
        let ramp: Vec<f64> = white
            .iter()
            .enumerate()
            .map(|(k, w)| w + 1e-3 * k as f64)
            .collect();
        for est in [Estimator::Hadamard, Estimator::OverlappingHadamard] {
            let a = deviation(&white, DataKind::Rate, 1.0, est, &TauGrid::Octave);
            let b = deviation(&ramp, DataKind::Rate, 1.0, est, &TauGrid::Octave);
            for (p, q) in a.iter().zip(&b) {
                assert!(((p.dev - q.dev) / p.dev).abs() < 1e-9, "{est:?} m={}", p.m);
            }
        }
        let a = deviation(
            &white,
            DataKind::Rate,
            1.0,
            Estimator::Overlapping,
            &TauGrid::Octave,
        );
        let b = deviation(
            &ramp,
            DataKind::Rate,
            1.0,
            Estimator::Overlapping,
            &TauGrid::Octave,
        );
        let last = a.len() - 1;
        // R^2 tau^2 / 2 dominates at long tau (docs/model.md §2): 1e-3 * tau / sqrt 2.
        let want = 1e-3 * a[last].tau_s / 2f64.sqrt();
        assert!(
            (b[last].dev / want - 1.0).abs() < 0.05,
            "{} vs {want}",
            b[last].dev
        );
    }

    #[test]
    fn short_or_degenerate_inputs_do_not_panic() {
        let grids = [
            TauGrid::Octave,
            TauGrid::Decade,
            TauGrid::All,
            TauGrid::PerDecade(3),
        ];
        for n in 0..40 {
            let y = series(n, n as u64);
            let constant = vec![1.0; n];
            for data in [&y, &constant] {
                for est in Estimator::ALL {
                    for g in &grids {
                        for kind in [DataKind::Rate, DataKind::Phase] {
                            let p = deviation(data, kind, 0.01, est, g);
                            assert!(p.iter().all(|q| q.n_terms >= 2));
                            let _ = fit::fit_ieee952(&p);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn woodman_bins_rule() {
        let y = series(1000, 5);
        let p = deviation(
            &y,
            DataKind::Rate,
            1.0,
            Estimator::NonOverlapping,
            &TauGrid::All,
        );
        for q in &p {
            assert_eq!(q.bins, 1000 / q.m);
            assert_eq!(q.n_terms, q.bins - 1);
            assert_eq!(q.woodman_ok(), q.m <= 111);
        }
    }
}
