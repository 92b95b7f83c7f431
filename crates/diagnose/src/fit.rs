//! Fitting candidate effects to the gap (docs/diagnose.md, diagnose step 4).
//!
//! Every candidate effect adds (or changes) one independent noise term, so it changes the model's Allan
//! variance additively (IEEE 952 Annex C, docs/model.md §2: "summing the terms assumes the processes are
//! independent"). A candidate is its Allan-variance signature per unit squared parameter, `f(tau)`,
//! evaluated on the tau grid, optionally as a family over one shape parameter (the Gauss-Markov
//! correlation time, the sinusoid frequency). The fitted squared parameter `c >= 0` replaces the level
//! `c0` the model already has for that term (0 when the term is absent), so the predicted variance is
//! `avar_band + (c - c0) f(tau)` and the prediction in ln adev is
//! `ln_band + ln((avar_band + (c - c0) f) / avar_band) / 2`.
//!
//! The fit minimises chi2 = sum z^2 over all taus (not only inside the disagreeing range: a term that
//! closes one range but opens another must pay for it), the information criterion is BIC = chi2 + k ln M
//! (Schwarz 1978) with k free parameters and M taus, and parameter intervals are profile-likelihood 95 %
//! intervals (chi2 - chi2_min <= 3.84, the chi2_1 0.95 quantile; Wilks 1938), widened by the reduced chi2
//! when the fit is worse than its error bars (Birge ratio; PDG "Statistics" review, scale factor S).

use serde::Serialize;

/// chi2_1 quantile at 0.95: profile-likelihood 95 % interval threshold.
pub const CHI2_1_95: f64 = 3.841_458_820_694_124;
/// 95 % quantile of chi-squared with 2 degrees of freedom (-2 ln 0.05): a joint interval for two shape parameters.
pub const CHI2_2_95: f64 = 5.991_464_547_107_979;

/// Smallest ratio (model variance after the change) / (band variance) allowed: a candidate that would take
/// the variance to zero or below at some tau is clamped there (and pays the misfit).
const MIN_VARIANCE_RATIO: f64 = 1e-6;

/// ln adev of a band whose mean Allan variance `avar_band` (ln adev centre `ln_band`) changes by `delta`.
/// A band with no variance at all (a channel the model has no term for) takes the change as its variance.
pub fn predicted_ln_adev(ln_band: f64, avar_band: f64, delta: f64) -> f64 {
    ln_adev_from(ln_band, avar_band, ln_argument(avar_band, delta).ln())
}

/// What [`predicted_ln_adev`] takes the logarithm of: the variance ratio, or on an empty band the
/// change itself.
#[inline(always)]
fn ln_argument(avar_band: f64, delta: f64) -> f64 {
    // Both computed, one chosen: no branch, so a loop of these vectorises.
    let ratio = ((avar_band + delta) / avar_band).max(MIN_VARIANCE_RATIO);
    let change = delta.max(f64::MIN_POSITIVE);
    if avar_band > 0.0 {
        ratio
    } else {
        change
    }
}

/// [`predicted_ln_adev`] from the logarithm `ln_arg` of its [`ln_argument`].
#[inline(always)]
fn ln_adev_from(ln_band: f64, avar_band: f64, ln_arg: f64) -> f64 {
    let (shifted, alone) = (ln_band + 0.5 * ln_arg, 0.5 * ln_arg);
    if avar_band > 0.0 {
        shifted
    } else {
        alone
    }
}

/// Taus per pass of [`FitData::chi2`] (on the stack).
const CHI2_CHUNK: usize = 32;

/// What the fit sees of one channel: the measurement and the current model's band, on one tau grid.
#[derive(Clone, Debug)]
pub struct FitData<'a> {
    /// ln adev measured.
    pub ln_meas: &'a [f64],
    /// ln adev band centre (current model).
    pub ln_band: &'a [f64],
    /// Allan variance band mean (current model).
    pub avar_band: &'a [f64],
    /// Standard error of the difference at each tau.
    pub s: &'a [f64],
}

impl FitData<'_> {
    fn m(&self) -> usize {
        self.ln_meas.len()
    }

    /// chi2 of the model changed by `dc * f` (dc = c - c0): the sum over taus, in tau order, of
    /// z^2 with the prediction of [`predicted_ln_adev`]. The fits evaluate it hundreds of times, so
    /// it runs in passes over chunks of taus: the logarithms' arguments (the divisions vectorised),
    /// the logarithms, the z^2 (vectorised), then the sum in order; each value is computed by the
    /// same operations as one tau at a time, so the bits are the same.
    pub fn chi2(&self, f: &[f64], dc: f64) -> f64 {
        let mut sum = 0.0;
        let mut buf = [0.0; CHI2_CHUNK];
        for start in (0..self.m()).step_by(CHI2_CHUNK) {
            let end = (start + CHI2_CHUNK).min(self.m());
            let v = &mut buf[..end - start];
            let (ln_meas, ln_band) = (&self.ln_meas[start..end], &self.ln_band[start..end]);
            let (avar, s, f) = (
                &self.avar_band[start..end],
                &self.s[start..end],
                &f[start..end],
            );
            for ((x, &a), &fi) in v.iter_mut().zip(avar).zip(f) {
                *x = ln_argument(a, dc * fi);
            }
            for x in v.iter_mut() {
                *x = x.ln();
            }
            for (i, x) in v.iter_mut().enumerate() {
                let z = (ln_meas[i] - ln_adev_from(ln_band[i], avar[i], *x)) / s[i];
                *x = z * z;
            }
            for z2 in v.iter() {
                sum += z2;
            }
        }
        sum
    }

    /// chi2 of the unchanged model.
    pub fn chi2_base(&self) -> f64 {
        (0..self.m())
            .map(|i| ((self.ln_meas[i] - self.ln_band[i]) / self.s[i]).powi(2))
            .sum()
    }
}

/// Best squared parameter c >= 0 for one signature, with its chi2. Its profile interval is
/// [`linear_interval`]'s, computed only where wanted: most fits are compared by chi2 alone, and the
/// interval's bisections cost as many chi2 evaluations as the fit itself.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct LinearFit {
    pub c: f64,
    pub chi2: f64,
}

/// Range of c worth searching: the levels at which the term alone would explain the measured variance at
/// one of the taus, widened by a decade on either side.
fn c_range(data: &FitData, f: &[f64], c0: f64) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi: f64 = 0.0;
    for i in 0..data.m() {
        if f[i] > 0.0 {
            let c_i = (2.0 * data.ln_meas[i]).exp() / f[i];
            lo = lo.min(c_i);
            hi = hi.max(c_i);
        }
    }
    if c0 > 0.0 {
        lo = lo.min(c0);
        hi = hi.max(c0);
    }
    if !lo.is_finite() || hi <= 0.0 {
        return (0.0, 0.0);
    }
    (lo * 1e-4, hi * 10.0)
}

/// Minimise chi2(c) over c in {0} and a log grid of [lo, hi], then refine by golden-section search
/// in ln c between the grid neighbours of the best point.
pub fn fit_linear(data: &FitData, f: &[f64], c0: f64) -> LinearFit {
    let chi = |c: f64| data.chi2(f, c - c0);
    let (lo, hi) = c_range(data, f, c0);
    let mut best_c = 0.0;
    let mut best = chi(0.0);
    if c0 > 0.0 && chi(c0) < best {
        best = chi(c0);
        best_c = c0;
    }
    if hi > 0.0 {
        const GRID: usize = 80;
        let (ln_lo, ln_hi) = (lo.ln(), hi.ln());
        let step = (ln_hi - ln_lo) / (GRID - 1) as f64;
        let mut best_j = None;
        for j in 0..GRID {
            let c = (ln_lo + step * j as f64).exp();
            let v = chi(c);
            if v < best {
                best = v;
                best_c = c;
                best_j = Some(j);
            }
        }
        if let Some(j) = best_j {
            // Golden section on ln c over [j-1, j+1].
            let (mut a, mut b) = (
                ln_lo + step * (j as f64 - 1.0),
                ln_lo + step * (j as f64 + 1.0),
            );
            let g = 0.5 * (5f64.sqrt() - 1.0);
            let (mut x1, mut x2) = (b - g * (b - a), a + g * (b - a));
            let (mut f1, mut f2) = (chi(x1.exp()), chi(x2.exp()));
            for _ in 0..60 {
                if f1 < f2 {
                    b = x2;
                    x2 = x1;
                    f2 = f1;
                    x1 = b - g * (b - a);
                    f1 = chi(x1.exp());
                } else {
                    a = x1;
                    x1 = x2;
                    f1 = f2;
                    x2 = a + g * (b - a);
                    f2 = chi(x2.exp());
                }
            }
            let (x, v) = if f1 < f2 { (x1, f1) } else { (x2, f2) };
            if v < best {
                best = v;
                best_c = x.exp();
            }
        }
    }
    LinearFit {
        c: best_c,
        chi2: best,
    }
}

/// Profile interval {c >= 0 : chi2(c) <= chi2_min + delta}, by bisection on either side of c_best.
fn profile_interval(
    chi: &dyn Fn(f64) -> f64,
    c_best: f64,
    chi_min: f64,
    delta: f64,
    c_max: f64,
) -> (f64, f64) {
    let level = chi_min + delta;
    // Lower side.
    let c_lo = if c_best <= 0.0 || chi(0.0) <= level {
        0.0
    } else {
        bisect(chi, level, c_best, 0.0) // chi(0) > level >= chi(c_best)
    };
    // Upper side: expand until above the level.
    let mut top = if c_best > 0.0 {
        c_best * 2.0
    } else {
        c_max.max(f64::MIN_POSITIVE) * 1e-6
    };
    let mut expansions = 0;
    let mut chi_top = chi(top);
    while chi_top <= level && expansions < 200 {
        top *= 2.0;
        chi_top = chi(top);
        expansions += 1;
    }
    if chi_top <= level {
        return (c_lo, f64::INFINITY);
    }
    (c_lo, bisect(chi, level, c_best, top)) // chi(c_best) <= level < chi(top)
}

/// The bound between `inside` (chi <= level) and `outside` (chi > level) after 80 halvings: the
/// last point inside. It stops early once a halving leaves both ends as they were, a fixed point
/// (the next halving would take the same midpoint to the same side), so the bits are those of all 80.
fn bisect(chi: &dyn Fn(f64) -> f64, level: f64, mut inside: f64, mut outside: f64) -> f64 {
    for _ in 0..80 {
        let before = (inside.to_bits(), outside.to_bits());
        let mid = 0.5 * (inside + outside);
        if chi(mid) > level {
            outside = mid;
        } else {
            inside = mid;
        }
        if (inside.to_bits(), outside.to_bits()) == before {
            break;
        }
    }
    inside
}

/// Fit of a signature family over one shape parameter (Gauss-Markov time, sinusoid frequency): the
/// linear fit at each grid value and the best overall.
#[derive(Clone, Debug, Serialize)]
pub struct FamilyFit {
    pub shape: f64,
    pub fit: LinearFit,
    /// The shape grid and the profiled chi2 (minimised over the level) at each grid value.
    pub shapes: Vec<f64>,
    pub chi2_by_shape: Vec<f64>,
}

impl FamilyFit {
    /// Profile interval of the shape parameter: the grid values whose profiled chi2 is within `delta` of
    /// the minimum, widened to the neighbouring grid values outside (the true bound lies between them).
    pub fn shape_interval(&self, delta: f64) -> (f64, f64) {
        let level = self.fit.chi2 + delta;
        let inside: Vec<usize> = (0..self.shapes.len())
            .filter(|&j| self.chi2_by_shape[j] <= level)
            .collect();
        let (Some(&first), Some(&last)) = (inside.first(), inside.last()) else {
            return (self.shape, self.shape);
        };
        let lo = self.shapes[first.saturating_sub(1)];
        let hi = self.shapes[(last + 1).min(self.shapes.len() - 1)];
        (lo, hi)
    }
}

pub fn fit_family(
    data: &FitData,
    shapes: &[f64],
    signatures: &[Vec<f64>],
    c0_of: &dyn Fn(usize) -> f64,
) -> Option<FamilyFit> {
    let fits: Vec<LinearFit> = signatures
        .iter()
        .enumerate()
        .map(|(j, f)| fit_linear(data, f, c0_of(j)))
        .collect();
    let (jb, best) = fits
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.chi2.total_cmp(&b.1.chi2))?;
    Some(FamilyFit {
        shape: shapes[jb],
        fit: *best,
        shapes: shapes.to_vec(),
        chi2_by_shape: fits.iter().map(|f| f.chi2).collect(),
    })
}

/// How much the errors' correlation across taus widens a searched shape's interval: the ratio
/// kappa of the shape estimate's variance under correlated errors to the variance the profile
/// chi2 (a sum of independent z^2) assumes, by the sandwich form of a least-squares estimate
/// (Huber 1967; White 1980, Econometrica 48, 817-838): Var = H^-1 (J' R J) H^-1 with J the
/// Jacobian of the predicted ln adev in (level, shape) divided by each tau's standard error,
/// H = J' J, and R the errors' correlation across taus, here from the model's own simulated logs
/// (`standardised`: per log, its deviation at each tau in units of the spread there; R = the
/// mean of u u' over the K logs, divisor K - 1). kappa = [H^-1 J'RJ H^-1]_ss / [H^-1]_ss: 1 for
/// independent errors, above 1 where neighbouring overlapping Allan deviations err together (the
/// usual case: the profile interval is then too narrow). `j_level[i]` and `j_shape[i]` are the
/// derivatives at tau i over its standard error. 1 where it cannot be estimated (fewer than 3
/// logs, or a level and a shape the taus cannot tell apart).
pub fn correlation_factor(standardised: &[Vec<f64>], j_level: &[f64], j_shape: &[f64]) -> f64 {
    let k = standardised.len();
    let m = j_level.len();
    if k < 3 || j_shape.len() != m || standardised.iter().any(|u| u.len() != m) {
        return 1.0;
    }
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
    let (a, b, d) = (
        dot(j_level, j_level),
        dot(j_level, j_shape),
        dot(j_shape, j_shape),
    );
    let det = a * d - b * b;
    if !(a > 0.0 && det > 1e-12 * a * d) {
        return 1.0;
    }
    // Row "shape" of H^-1 is (-b, a) / det; its variance under R over [H^-1]_ss = a / det.
    let spread: f64 = standardised
        .iter()
        .map(|u| {
            let w = a * dot(j_shape, u) - b * dot(j_level, u);
            w * w
        })
        .sum::<f64>()
        / (k - 1) as f64;
    let kappa = spread / (a * det);
    if kappa.is_finite() && kappa > 0.0 {
        kappa
    } else {
        1.0
    }
}

/// Bayesian information criterion: chi2 + k ln M (Schwarz 1978), with chi2 = -2 ln L up to a constant
/// for Gaussian z-scores.
pub fn bic(chi2: f64, k: usize, m: usize) -> f64 {
    chi2 + k as f64 * (m.max(1) as f64).ln()
}

/// Akaike information criterion: chi2 + 2k (Akaike 1974), reported beside BIC.
pub fn aic(chi2: f64, k: usize) -> f64 {
    chi2 + 2.0 * k as f64
}

/// Widening factor of a profile interval for a fit whose chi2 exceeds its degrees of freedom: the Birge
/// ratio sqrt(chi2 / (M - k)) when above 1 (PDG review of particle physics, "Statistics", scale factor S).
pub fn birge_scale(chi2: f64, k: usize, m: usize) -> f64 {
    let dof = m.saturating_sub(k).max(1) as f64;
    (chi2 / dof).sqrt().max(1.0)
}

/// Profile interval on c of `fit` (from [`fit_linear`] on the same data) for a threshold delta:
/// [`CHI2_1_95`] for the 95 % interval, times the Birge ratio squared to widen it.
pub fn linear_interval(
    data: &FitData,
    f: &[f64],
    c0: f64,
    fit: &LinearFit,
    delta: f64,
) -> (f64, f64) {
    let chi = |c: f64| data.chi2(f, c - c0);
    let (_, hi) = c_range(data, f, c0);
    profile_interval(&chi, fit.c, fit.chi2, delta, hi.max(fit.c))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sandwich factor is 1 when the logs' errors are uncorrelated across taus (here exactly:
    /// the standardised rows are an orthogonal design, mean u u' = I), and for errors that move
    /// together at every tau it is the closed form: with u_k = x_k (1, ..., 1) the shape's
    /// variance is (1'(a j_s - b j_l))^2 var(x) / (a det).
    #[test]
    fn correlation_factor_is_one_for_independent_errors_and_exact_for_common_ones() {
        let jl = [1.0, 0.8, 0.5];
        let js = [-0.4, 0.1, 0.9];
        // K = 4 rows, divisor 3: rows sqrt(3) e_i and a zero row give mean u u' = I.
        let r3 = 3f64.sqrt();
        let independent = vec![
            vec![r3, 0.0, 0.0],
            vec![0.0, r3, 0.0],
            vec![0.0, 0.0, r3],
            vec![0.0, 0.0, 0.0],
        ];
        let kappa = correlation_factor(&independent, &jl, &js);
        assert!((kappa - 1.0).abs() < 1e-12, "{kappa}");
        let xs = [1.0, -1.0, 0.5, -0.5];
        let common: Vec<Vec<f64>> = xs.iter().map(|&x| vec![x; 3]).collect();
        let var_x = xs.iter().map(|x| x * x).sum::<f64>() / 3.0;
        let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
        let (a, b, d) = (dot(&jl, &jl), dot(&jl, &js), dot(&js, &js));
        let det = a * d - b * b;
        let one: f64 = (0..3).map(|i| a * js[i] - b * jl[i]).sum();
        let expected = one * one * var_x / (a * det);
        let kappa = correlation_factor(&common, &jl, &js);
        assert!(
            (kappa - expected).abs() < 1e-12 * expected,
            "{kappa} vs {expected}"
        );
        // Too few logs, or a shape the level explains: no correction.
        assert_eq!(correlation_factor(&common[..2], &jl, &js), 1.0);
        assert_eq!(correlation_factor(&common, &jl, &jl), 1.0);
    }

    /// A noise-free synthetic measurement: white noise in the model, the measurement has white noise plus
    /// rate random walk of known level. The fit must return the level exactly (no noise, so the tolerance
    /// is the golden-section convergence, 1e-6 relative).
    #[test]
    fn linear_fit_recovers_exact_level_without_noise() {
        let tau: Vec<f64> = (0..14).map(|j| 0.01 * 2f64.powi(j)).collect();
        let n2 = 1e-6;
        let k2 = 3e-8;
        let avar_band: Vec<f64> = tau.iter().map(|t| n2 / t).collect();
        let ln_band: Vec<f64> = avar_band.iter().map(|a| 0.5 * a.ln()).collect();
        let f_rrw: Vec<f64> = tau.iter().map(|t| t / 3.0).collect(); // K^2 T / 3 (docs/model.md §2, Hou 4.53)
        let ln_meas: Vec<f64> = tau
            .iter()
            .map(|t| 0.5 * (n2 / t + k2 * t / 3.0).ln())
            .collect();
        let s = vec![0.01; tau.len()];
        let data = FitData {
            ln_meas: &ln_meas,
            ln_band: &ln_band,
            avar_band: &avar_band,
            s: &s,
        };
        let fit = fit_linear(&data, &f_rrw, 0.0);
        assert!((fit.c / k2 - 1.0).abs() < 1e-6, "c {} vs {}", fit.c, k2);
        assert!(fit.chi2 < 1e-8);
        let (c_lo, c_hi) = linear_interval(&data, &f_rrw, 0.0, &fit, CHI2_1_95);
        assert!(c_lo < fit.c && fit.c < c_hi);
        // Wrong level of a present term: the model has white noise at n2, the truth at 2 n2.
        let f_white: Vec<f64> = tau.iter().map(|t| 1.0 / t).collect();
        let ln_meas2: Vec<f64> = tau.iter().map(|t| 0.5 * (2.0 * n2 / t).ln()).collect();
        let data2 = FitData {
            ln_meas: &ln_meas2,
            ..data
        };
        let fit2 = fit_linear(&data2, &f_white, n2);
        assert!((fit2.c / (2.0 * n2) - 1.0).abs() < 1e-6);
        // And a level below the model's.
        let ln_meas3: Vec<f64> = tau.iter().map(|t| 0.5 * (0.5 * n2 / t).ln()).collect();
        let data3 = FitData {
            ln_meas: &ln_meas3,
            ..data
        };
        let fit3 = fit_linear(&data3, &f_white, n2);
        assert!((fit3.c / (0.5 * n2) - 1.0).abs() < 1e-6);
    }

    /// The early-stopping bisection gives the bits of all 80 halvings, on either side of the
    /// bound, for bounds at many scales (and at 0 and at an end).
    #[test]
    fn bisect_equals_eighty_halvings() {
        let full = |chi: &dyn Fn(f64) -> f64, level: f64, mut inside: f64, mut outside: f64| {
            for _ in 0..80 {
                let mid = 0.5 * (inside + outside);
                if chi(mid) > level {
                    outside = mid;
                } else {
                    inside = mid;
                }
            }
            inside
        };
        for k in 0..400 {
            let bound = 1.37f64.powi(k - 200) * (1.0 + 0.1 * f64::from(k % 7));
            let rising = |c: f64| if c > bound { 5.0 } else { 1.0 };
            let falling = |c: f64| if c < bound { 5.0 } else { 1.0 };
            for (outside, inside) in [(bound * 3.0, bound * 0.5), (bound * 9.0, 0.0)] {
                let a = bisect(&rising, 2.0, inside, outside);
                assert_eq!(a.to_bits(), full(&rising, 2.0, inside, outside).to_bits());
            }
            for (inside, outside) in [(bound * 3.0, 0.0), (bound * 1.5, bound * 0.25)] {
                let a = bisect(&falling, 2.0, inside, outside);
                assert_eq!(a.to_bits(), full(&falling, 2.0, inside, outside).to_bits());
            }
            let a = bisect(&rising, 2.0, bound, bound);
            assert_eq!(a.to_bits(), full(&rising, 2.0, bound, bound).to_bits());
        }
    }

    /// The chunked chi2 gives the bits of the sum taken one tau at a time, over lengths across
    /// chunk boundaries, with empty bands and with changes that take the variance below zero.
    #[test]
    fn chunked_chi2_equals_the_plain_sum() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for m in [0, 1, 5, 18, 31, 32, 33, 64, 70] {
            let gen = |g: &mut dyn FnMut() -> f64, lo: f64, hi: f64| -> Vec<f64> {
                (0..m).map(|_| lo + (hi - lo) * g()).collect()
            };
            let ln_meas = gen(&mut uniform, -12.0, -2.0);
            let ln_band = gen(&mut uniform, -12.0, -2.0);
            let mut avar_band = gen(&mut uniform, -1e-6, 1e-5);
            avar_band.iter_mut().step_by(7).for_each(|a| *a = 0.0);
            let s = gen(&mut uniform, 0.01, 0.5);
            let f = gen(&mut uniform, 0.0, 2.0);
            let data = FitData {
                ln_meas: &ln_meas,
                ln_band: &ln_band,
                avar_band: &avar_band,
                s: &s,
            };
            // The prediction as first written, one expression per tau.
            let predicted = |ln_band: f64, avar_band: f64, delta: f64| {
                if avar_band > 0.0 {
                    let ratio = ((avar_band + delta) / avar_band).max(MIN_VARIANCE_RATIO);
                    ln_band + 0.5 * ratio.ln()
                } else {
                    0.5 * delta.max(f64::MIN_POSITIVE).ln()
                }
            };
            for dc in [0.0, 1e-7, -3e-6, 5e-5, -1.0, 1e300, f64::INFINITY, f64::NAN] {
                let mut plain = 0.0;
                for i in 0..m {
                    let ln_pred = predicted(ln_band[i], avar_band[i], dc * f[i]);
                    let z = (ln_meas[i] - ln_pred) / s[i];
                    plain += z * z;
                }
                let chunked = data.chi2(&f, dc);
                let same =
                    chunked.to_bits() == plain.to_bits() || chunked.is_nan() && plain.is_nan();
                assert!(same, "m {m} dc {dc}: {chunked} vs {plain}");
            }
        }
    }

    #[test]
    fn prediction_on_an_empty_band_is_the_added_term() {
        // Band with variance 4 (adev 2): adding 5 gives adev 3. Empty band: adding 9 gives adev 3.
        assert!((predicted_ln_adev(2f64.ln(), 4.0, 5.0) - 3f64.ln()).abs() < 1e-15);
        assert!((predicted_ln_adev(f64::MIN_POSITIVE.ln(), 0.0, 9.0) - 3f64.ln()).abs() < 1e-15);
    }

    #[test]
    fn profile_interval_of_quadratic_chi2_is_analytic() {
        // One tau, z linear in ln c near the optimum: check the interval brackets c and is finite.
        let ln_meas = [0.5 * 2f64.ln()];
        let ln_band = [0.0];
        let avar_band = [1.0];
        let s = [0.1];
        let f = [1.0];
        let data = FitData {
            ln_meas: &ln_meas,
            ln_band: &ln_band,
            avar_band: &avar_band,
            s: &s,
        };
        let fit = fit_linear(&data, &f, 0.0);
        assert!((fit.c - 1.0).abs() < 1e-6);
        // z(c) = (0.5 ln 2 - 0.5 ln(1 + c)) / 0.1; z^2 = 3.84 at ln(1+c) = ln 2 -/+ 2*0.1*1.96.
        let d = 2.0 * 0.1 * CHI2_1_95.sqrt();
        let lo = 2.0 * (-d).exp() - 1.0;
        let hi = 2.0 * d.exp() - 1.0;
        let (c_lo, c_hi) = linear_interval(&data, &f, 0.0, &fit, CHI2_1_95);
        assert!((c_lo - lo).abs() < 1e-6, "{} vs {}", c_lo, lo);
        assert!((c_hi - hi).abs() < 1e-6, "{} vs {}", c_hi, hi);
    }
}
