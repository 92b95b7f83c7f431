//! [`Series`]: a log prepared once (its phase) for many deviations, the normalisation of the
//! estimators' sums (SP 1065), and the confidence intervals attached to each point.

use crate::kernels::{
    blocked_diff_sums_fast, estimator_sum_fast, rate_noise_id_fast, streamed_diff_sums_fast,
    BLOCKED_MAX_M,
};
use crate::phase::{rate_to_phase, rate_to_phase_in_place};
use crate::{chi2, edf, total, AllanPoint, DataKind, EdfMethod, Estimator, Options, TauGrid};
use std::borrow::Cow;
use std::sync::atomic::{AtomicBool, Ordering};

/// Factors of the overlapping estimators' shared passes between two reads of a stop flag
/// ([`Series::raw_points_until`]): more than an octave or decade grid has (one pass), few enough
/// that an "all" grid of a long record is stopped within a fraction of a second.
pub(crate) const STOP_GROUP_FACTORS: usize = 64;

/// A noise identification differs from the shorter tau's only when its estimate lies this many
/// standard errors beyond the held type's rounding band (the normal 99.5 % point: a per-tau
/// false change of at most 0.5 % each way, 1 % in all, where the held type is right).
pub const NOISE_ID_CHANGE_Z: f64 = 2.575_829_303_548_901;

/// A time series prepared once for many deviations: the phase array (phase input is used in
/// place, rate input integrated into an array of its own), and for phase input the samples for
/// noise identification.
pub struct Series<'a> {
    phase: Cow<'a, [f64]>,
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
                phase: Cow::Owned(rate_to_phase(data, tau0_s)),
                rate_len: Some(data.len()),
                source_phase: None,
                tau0_s,
            },
            DataKind::Phase => Series {
                phase: Cow::Borrowed(data),
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
            phase: Cow::Owned(rate_to_phase_in_place(data, tau0_s)),
            rate_len: Some(rate_len),
            source_phase: None,
            tau0_s,
        }
    }

    /// Number of phase points (rate samples + 1).
    pub fn phase_len(&self) -> usize {
        self.phase.len()
    }

    /// The phase points (s, or the unit of phase input).
    pub fn phase(&self) -> &[f64] {
        &self.phase
    }

    /// Number of rate samples (for phase input, one less than the phase samples).
    pub fn rate_len(&self) -> usize {
        self.rate_len
            .unwrap_or_else(|| self.phase.len().saturating_sub(1))
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

    /// The deviation curve on `grid` with the intervals `opts` asks for ([`crate::deviation_with`]).
    pub fn deviation(&self, est: Estimator, grid: &TauGrid, opts: &Options) -> Vec<AllanPoint> {
        let ms = self.grid_m(est, grid, opts.stable32_stop);
        let mut points = self.raw_points(est, &ms);
        self.attach_intervals(est, &mut points, opts);
        points
    }

    /// The deviation at averaging factor `m` without interval (`None` if fewer than 2 terms).
    /// TheoH computes its bias factor here for this one point (see [`Series::raw_points`] for
    /// a curve, which computes it once).
    pub fn raw_point(&self, est: Estimator, m: usize) -> Option<AllanPoint> {
        match est {
            Estimator::ModifiedTotal => {
                let (sum, n) = total::total_window_sum(&self.phase, m)?;
                self.point_from_sum(est, m, sum, n)
            }
            // At m = 1 the overlapping Hadamard deviation, as Stable32 and allantools do
            // (Riley: "for best consistency, the overlapping Hadamard variance is used instead
            // of the Hadamard total variance at m = 1").
            Estimator::HadamardTotal if m == 1 => {
                let (sum, n) = estimator_sum_fast(&self.phase, Estimator::OverlappingHadamard, 1)?;
                self.point_from_sum(Estimator::OverlappingHadamard, 1, sum, n)
            }
            Estimator::HadamardTotal => {
                let (sum, n) = total::total_window_sum(&self.frequency(), m)?;
                self.point_from_sum(est, m, sum, n)
            }
            Estimator::Theo1 => {
                let (sum, n) = total::theo1_sum(&self.phase, m)?;
                self.point_from_sum(est, m, sum, n)
            }
            Estimator::TheoH => self.theoh_point(m, &|| self.theo_bias_factor()),
            _ => {
                let (sum_sq, n_terms) = estimator_sum_fast(&self.phase, est, m)?;
                self.point_from_sum(est, m, sum_sq, n_terms)
            }
        }
    }

    /// The frequency (rate) the phase integrates: (x_{k+1} - x_k) / tau0, the Hadamard total
    /// deviation's input (allantools `phase2frequency`; for rate input the rate less its mean,
    /// which the subsequences' detrending removes anyway).
    fn frequency(&self) -> Vec<f64> {
        let rate = 1.0 / self.tau0_s;
        self.phase
            .windows(2)
            .map(|w| (w[1] - w[0]) * rate)
            .collect()
    }

    /// TheoBR's bias factor (SP 1065 §5.2.14, Taylor & Howe 2010): the mean over
    /// i = 0..=n of AVAR(m = 9 + 3i) / Theo1(m = 12 + 4i), the two at the same tau
    /// ((9 + 3i) tau0 = 0.75 (12 + 4i) tau0), n = floor(0.1 N / 3) - 3 with N phase points.
    /// `None` when the record is too short for one ratio (N < 120).
    pub fn theo_bias_factor(&self) -> Option<f64> {
        let n = self.phase.len();
        let top = (0.1 * n as f64 / 3.0).floor() as i64 - 3;
        if top < 0 {
            return None;
        }
        let ratios: Vec<f64> = (0..=top as usize)
            .map(|i| {
                let avar = self
                    .raw_point(Estimator::Overlapping, 9 + 3 * i)?
                    .dev
                    .powi(2);
                let theo = self.raw_point(Estimator::Theo1, 12 + 4 * i)?.dev.powi(2);
                Some(avar / theo)
            })
            .collect::<Option<_>>()?;
        Some(ratios.iter().sum::<f64>() / ratios.len() as f64)
    }

    /// TheoH at factor m (SP 1065 §5.2.14): the overlapping Allan deviation at tau = m tau0 below a
    /// tenth of the record ([`total::theoh_uses_avar`]), else for even m from 0.75 m tau0 = a
    /// tenth of the record on, TheoBR = sqrt(kf) Theo1 with kf from `bias` (computed only when
    /// needed); `None` for the factors between the two parts, odd factors of the TheoBR part and
    /// factors beyond the record.
    fn theoh_point(&self, m: usize, bias: &dyn Fn() -> Option<f64>) -> Option<AllanPoint> {
        let n = self.phase.len();
        if total::theoh_uses_avar(m, n) {
            let mut p = self.raw_point(Estimator::Overlapping, m)?;
            p.m = m;
            return Some(p);
        }
        if !total::theoh_uses_theo(m, n) {
            return None;
        }
        let mut p = self.raw_point(Estimator::Theo1, m)?;
        p.dev *= bias()?.sqrt();
        Some(p)
    }

    /// The deviations at all `ms` without intervals, skipping factors with fewer than 2 terms.
    /// The overlapping estimators use one cache-blocked pass for all small factors (the phase
    /// array is streamed from memory once instead of once per tau); the result is identical to
    /// [`Series::raw_point`] up to the order of the floating-point additions.
    pub fn raw_points(&self, est: Estimator, ms: &[usize]) -> Vec<AllanPoint> {
        let never = AtomicBool::new(false);
        self.raw_points_until(est, ms, &never)
            .expect("deviations without a stop request run to their end")
    }

    /// [`Series::raw_points`] that gives up when `stop` is set (`None` then), read before each
    /// factor's pass and, for the overlapping estimators, before each group of
    /// `STOP_GROUP_FACTORS` factors of the shared passes (each factor's sum is its own lanes',
    /// so the grouping leaves the result bit for bit the same; an octave or decade grid is one
    /// group).
    pub fn raw_points_until(
        &self,
        est: Estimator,
        ms: &[usize],
        stop: &AtomicBool,
    ) -> Option<Vec<AllanPoint>> {
        let stopped = || stop.load(Ordering::Relaxed);
        if est == Estimator::TheoH {
            // The bias factor once for the curve, when a factor needs it.
            let kf = std::cell::OnceCell::new();
            let bias = || *kf.get_or_init(|| self.theo_bias_factor());
            let mut out = Vec::new();
            for &m in ms {
                if stopped() {
                    return None;
                }
                out.extend(self.theoh_point(m, &bias));
            }
            return Some(out);
        }
        let multi = match est {
            Estimator::Overlapping => Some(2),
            Estimator::OverlappingHadamard => Some(3),
            _ => None,
        };
        let Some(order) = multi else {
            let mut out = Vec::new();
            for &m in ms {
                if stopped() {
                    return None;
                }
                out.extend(self.raw_point(est, m));
            }
            return Some(out);
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
        // The blocked pass over the small factors and the streamed pass over the large ones run
        // side by side (each sum is computed by one thread in a fixed order: the result does not
        // depend on the threads; the large factors' sums are those of `raw_point`, bit for bit).
        let in_groups = |ms: &[usize], sums: &dyn Fn(&[usize]) -> Vec<f64>| -> Option<Vec<f64>> {
            let mut out = Vec::with_capacity(ms.len());
            for group in ms.chunks(STOP_GROUP_FACTORS) {
                if stopped() {
                    return None;
                }
                out.extend(sums(group));
            }
            Some(out)
        };
        let (sums, large_sums) = rayon::join(
            || in_groups(&small, &|g| blocked_diff_sums_fast(&self.phase, g, order)),
            || in_groups(&large, &|g| streamed_diff_sums_fast(&self.phase, g, order)),
        );
        let (sums, large_sums) = (sums?, large_sums?);
        let large_points: Vec<AllanPoint> = large
            .iter()
            .zip(large_sums)
            .filter_map(|(&m, s)| self.point_from_sum(est, m, s, n - order * m))
            .collect();
        let mut out: Vec<AllanPoint> = small
            .iter()
            .zip(sums)
            .filter_map(|(&m, s)| self.point_from_sum(est, m, s, n - order * m))
            .collect();
        out.extend(large_points);
        Some(out)
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
            // SP 1065 eq (27): Mod Tot sigma^2 = sum over the N - 3m + 1 subsequences of their
            // (1/6m) sums (the m-averages' second differences squared), / (2 tau^2 (N - 3m + 1))
            Estimator::ModifiedTotal => sum_sq / (2.0 * tau_s * tau_s * n_terms as f64),
            // SP 1065 §5.2.13 (allantools `calc_htotdev_freq`): the same on frequency data, / 6
            // (the Hadamard variance's 1/6) and the number of subsequences
            Estimator::HadamardTotal => sum_sq / (6.0 * n_terms as f64),
            // SP 1065 eq (30): Theo1 = sum / (0.75 (N - m) (m tau0)^2); n_terms = (N - m) m/2
            Estimator::Theo1 => {
                let outer = 2 * n_terms / m;
                sum_sq / (0.75 * outer as f64 * tau_s * tau_s)
            }
            // TheoH's points are those of its parts (`theoh_point`).
            Estimator::TheoH => return None,
        };
        // Theo1 reports tau = 0.75 m tau0 (SP 1065 eq (30), Stable32's "Theo1 Tau").
        let tau_s = if est == Estimator::Theo1 {
            0.75 * tau_s
        } else {
            tau_s
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
        let d = est.difference_order();
        let mut last: Option<i32> = None;
        for (p, alpha) in points.iter_mut().zip(alphas) {
            let alpha = match (*alpha, last) {
                (None, held) => held.unwrap_or(first_known),
                (Some(a), Some(held)) if a != held => {
                    let edf = |al| edf::edf_for(est, opts.edf, al, p.m, n_phase, p.n_terms);
                    self.held_noise_id(p.m, d, held, a, edf)
                }
                (Some(a), _) => a,
            };
            last = Some(alpha);
            p.alpha = alpha;
            if est == Estimator::Total && opts.totvar_bias_correction {
                p.dev /= edf::totvar_bias(alpha, p.m, n_phase - 1).sqrt();
            }
            if est == Estimator::HadamardTotal && p.m > 1 && opts.totvar_bias_correction {
                p.dev /= edf::htotvar_bias(alpha).sqrt();
            }
            p.edf = edf::edf_for(est, opts.edf, alpha, p.m, n_phase, p.n_terms);
            let (lo, hi) = chi2::confidence_interval(p.dev, p.edf, opts.confidence);
            p.lo = lo;
            p.hi = hi;
        }
    }

    /// The noise type at averaging factor m when its identification `found` differs from the
    /// shorter tau's `held` one: `found` where it departs from `held` significantly
    /// ([`edf::NoiseId::departs_from`] at [`NOISE_ID_CHANGE_Z`]); where it does not, the data
    /// cannot tell the two types apart, and the one with fewer degrees of freedom (`edf` of a
    /// type: the wider interval) is taken. With few blocks the lag-1 ACF scatters by 1/sqrt(n)
    /// (0.18 at the method's minimum of 30 points): white rate noise then reads as flicker PM
    /// (alpha = 1, r1 < -0.2) on about a quarter of the longest taus, and those points got
    /// Greenhall's EDF for alpha = 1, several times too large. A noise type persists over
    /// neighbouring taus (each power law dominates a range of tau, IEEE 952 Annex C), which is
    /// why the shorter tau's type, identified on more blocks, is the alternative; taking the
    /// smaller EDF of the two never narrows an interval below what either type gives.
    fn held_noise_id(
        &self,
        m: usize,
        d_max: u32,
        held: i32,
        found: i32,
        edf: impl Fn(i32) -> f64,
    ) -> i32 {
        match self.noise_id_detail(m, d_max) {
            Some(id) if id.departs_from(held, NOISE_ID_CHANGE_Z) => id.alpha,
            _ if edf(found) < edf(held) => found,
            _ => held,
        }
    }

    /// [`Series::noise_id`] with its evidence (computed without the vector kernels: called only
    /// where the identification changes).
    pub fn noise_id_detail(&self, m: usize, d_max: u32) -> Option<edf::NoiseId> {
        match (self.rate_len, self.source_phase) {
            (Some(_), _) => {
                let (m, blocks) = self.rate_blocks(m)?;
                let x = &self.phase;
                edf::rate_noise_id_detail_fn(blocks, |j| x[(j + 1) * m] - x[j * m], d_max)
            }
            (None, Some(x)) => edf::autocorr_noise_id_detail(x, m, DataKind::Phase, d_max),
            _ => None,
        }
    }

    /// The averaging factor (at least 1) and the number of block averages of the rate at m,
    /// `None` under the 30 the lag-1 ACF method needs (Riley 2004) or for phase input. The block
    /// averages of the rate are phase differences at stride m (x_{(j+1)m} - x_{jm} = tau0 * sum
    /// of the block, mean removed): no pass over the m samples of each block. Scale and offset
    /// do not change the ACF.
    fn rate_blocks(&self, m: usize) -> Option<(usize, usize)> {
        let m = m.max(1);
        let blocks = self.rate_len? / m;
        (blocks >= 30).then_some((m, blocks))
    }

    /// Lag-1 autocorrelation noise identification at averaging factor m (Riley 2004),
    /// on the data as given (rate or phase); `None` when too few points.
    pub fn noise_id(&self, m: usize, d_max: u32) -> Option<i32> {
        match (self.rate_len, self.source_phase) {
            (Some(_), _) => {
                let (m, blocks) = self.rate_blocks(m)?;
                rate_noise_id_fast(&self.phase, m, blocks, d_max)
            }
            (None, Some(x)) => edf::autocorr_noise_id(x, m, DataKind::Phase, d_max),
            _ => None,
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
    Series::new(data, kind, tau0_s).deviation(est, grid, opts)
}
