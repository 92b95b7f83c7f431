//! The estimators beyond the Allan and Hadamard families' plain sums:
//! - modified total and Hadamard total deviation, which detrend and reflect every subsequence
//!   of 3m points (NIST SP 1065 eq (27) and §5.2.13; Howe & Vernotte 1999, Howe et al. 2005),
//! - Theo1 (SP 1065 eq (30); Howe & Tasset 2004) and the bias factor of TheoBR / TheoH
//!   (SP 1065 §5.2.14; Taylor & Howe 2010),
//! - the gap-tolerant overlapping Allan deviation (allantools `gradev`: NaN samples are gaps),
//! - the time-interval errors MTIE and TIE rms (ITU-T G.810 §4.5.13-14; Stable32 "MTIE (Fast)"
//!   and "TIE rms").
//!
//! Units: phase (integrated rate) in, the phase's unit out for MTIE and TIE rms; the variance
//! sums here are normalised by the caller ([`crate::Series`]).
//!
//! Cost: the total estimators are O(N m) per tau (every subsequence's reflected sum is O(m),
//! as in Stable32 and allantools, only compiled and parallel), Theo1 O(N m / 2); the
//! subsequences are summed in fixed blocks merged in index order, so the result does not
//! depend on the number of threads.

use crate::sum::{compensated_sum, pairwise_lanes};
use crate::wide_variant;
use rayon::prelude::*;

/// Subsequences per parallel task of the total estimators (a fixed split: the order of the
/// additions, hence the result, does not depend on the threads).
const WINDOWS_PER_TASK: usize = 512;

/// The total estimators' sum over subsequences: for each of the N - 3m + 1 subsequences of
/// 3m values, remove the linear trend through the means of its first and last halves, extend
/// it by uninverted even reflection to 9m values, and add (1/(6m)) sum over its 6m overlapping
/// second differences of m-sums, each divided by m, squared (SP 1065 eq (27) on phase data
/// (MTOT); the same on frequency data is the Hadamard total's, §5.2.13). Returns the sum and
/// the number of subsequences, `None` when there is none.
pub(crate) fn total_window_sum(data: &[f64], m: usize) -> Option<(f64, usize)> {
    if m == 0 {
        return None;
    }
    let windows = (data.len() + 1).checked_sub(3 * m)?;
    if windows == 0 {
        return None;
    }
    let tasks = windows.div_ceil(WINDOWS_PER_TASK);
    let sums: Vec<f64> = (0..tasks)
        .into_par_iter()
        .map(|t| {
            let start = t * WINDOWS_PER_TASK;
            let end = (start + WINDOWS_PER_TASK).min(windows);
            total_task_fast(data, m, start, end)
        })
        .collect();
    Some((compensated_sum(sums.into_iter()), windows))
}

wide_variant! {
    /// The subsequences start..end of [`total_window_sum`], added in index order.
    fn total_task_fast(data: &[f64], m: usize, start: usize, end: usize) -> f64 {
        total_task(data, m, start, end)
    }
}

#[inline(always)]
fn total_task(data: &[f64], m: usize, start: usize, end: usize) -> f64 {
    let len = 3 * m;
    let mut z = vec![0.0f64; len];
    let mut prefix = vec![0.0f64; 9 * m + 1];
    let mut acc = 0.0f64;
    for i in start..end {
        acc += window_value(&data[i..i + len], m, &mut z, &mut prefix);
    }
    acc
}

/// One subsequence's (1/(6m)) sum_j ((S_j - 2 S_{j+m} + S_{j+2m}) / m)^2, S the m-sums of
/// the reflected, detrended subsequence `xs` of 3m values.
#[inline(always)]
fn window_value(xs: &[f64], m: usize, z: &mut [f64], prefix: &mut [f64]) -> f64 {
    let len = xs.len();
    // The trend (SP 1065 §5.2.12, allantools `calc_mtotdev_phase`): the means of the first and
    // last floor(3m/2) values, whose centres lie 3m/2 apart (3m even) or (3m - 1)/2 + 1 apart
    // (3m odd, the middle value left out).
    let half = len / 2;
    let mean_first = xs[..half].iter().sum::<f64>() / half as f64;
    let mean_last = xs[len - half..].iter().sum::<f64>() / half as f64;
    let distance = if len.is_multiple_of(2) {
        0.5 * len as f64
    } else {
        0.5 * (len - 1) as f64 + 1.0
    };
    let slope = (mean_last - mean_first) / distance;
    let mut mean = 0.0;
    for (k, (zk, &x)) in z.iter_mut().zip(xs).enumerate() {
        *zk = x - slope * k as f64;
        mean += *zk;
    }
    // A constant drops out of every second difference; removing the mean keeps the running
    // sums below small (their rounding is then that of the differences themselves).
    mean /= len as f64;
    // prefix[p] = sum of the first p values of [reversed z, z, reversed z], from the one
    // running sum of z (a chain of 3m additions; the 9m prefix values are then independent):
    // with Z_k the sum of the first k values of z and Z = Z_{3m}, prefix[p] = Z - Z_{3m-p}
    // (p <= 3m), Z + Z_{p-3m} (3m <= p <= 6m), 3Z - Z_{9m-p} (p >= 6m).
    let (head, rest) = prefix.split_at_mut(len + 1);
    let zsum = &mut head[..];
    let mut run = 0.0;
    zsum[0] = 0.0;
    for (k, &v) in z.iter().enumerate() {
        run += v - mean;
        zsum[k + 1] = run;
    }
    let total = run;
    // rest holds prefix[3m+1 ..= 9m]; head becomes prefix[0 ..= 3m] after the first part.
    for (q, slot) in rest[..len].iter_mut().enumerate() {
        // p = 3m + 1 + q in (3m, 6m]
        *slot = total + zsum[q + 1];
    }
    for (q, slot) in rest[len..].iter_mut().enumerate() {
        // p = 6m + 1 + q in (6m, 9m]
        *slot = 3.0 * total - zsum[len - 1 - q];
    }
    // prefix[p] = Z - Z_{3m-p} for p <= 3m, in place (p and 3m - p swap: the pairs are
    // disjoint, each read before it is written).
    for p in 0..=len / 2 {
        let (a, b) = (zsum[p], zsum[len - p]);
        zsum[p] = total - b;
        zsum[len - p] = total - a;
    }
    // S_j - 2 S_{j+m} + S_{j+2m} = -P_j + 3 P_{j+m} - 3 P_{j+2m} + P_{j+3m}, j < 6m.
    let terms = 6 * m;
    let a = &prefix[..terms];
    let b = &prefix[m..m + terms];
    let c = &prefix[2 * m..2 * m + terms];
    let d = &prefix[3 * m..3 * m + terms];
    let mut lanes = [0.0f64; 8];
    let full = terms / 8 * 8;
    for j in (0..full).step_by(8) {
        for (l, slot) in lanes.iter_mut().enumerate() {
            let k = j + l;
            let v = d[k] - 3.0 * c[k] + 3.0 * b[k] - a[k];
            *slot += v * v;
        }
    }
    for k in full..terms {
        let v = d[k] - 3.0 * c[k] + 3.0 * b[k] - a[k];
        lanes[0] += v * v;
    }
    pairwise_lanes(&lanes) / (terms as f64 * (m * m) as f64)
}

/// Where TheoH takes the overlapping Allan deviation: tau = m tau0 below a tenth of the record
/// T = (N - 1) tau0 (SP 1065 §5.2.14: AVAR for 1 <= m < k/tau0, k the boundary at 0.1 T).
pub fn theoh_uses_avar(m: usize, n_phase: usize) -> bool {
    m >= 1 && (m as f64) < 0.1 * n_phase.saturating_sub(1) as f64
}

/// Where TheoH takes TheoBR: even m < N with 0.75 m tau0 at or beyond the boundary
/// (SP 1065 §5.2.14: TheoBR for k/(0.75 tau0) <= m <= N - 1, m even).
pub fn theoh_uses_theo(m: usize, n_phase: usize) -> bool {
    m.is_multiple_of(2) && m >= 2 && m < n_phase && 0.75 * m as f64 >= 0.1 * (n_phase - 1) as f64
}

/// Theo1's double sum at an even averaging factor m (SP 1065 eq (30), Howe & Tasset 2004):
/// sum over i < N - m and delta < m/2 of (x_i - x_{i-delta+m/2} + x_{i+m} - x_{i+delta+m/2})^2
/// / (m/2 - delta), with the number of terms (N - m) m/2; `None` for odd m or m >= N.
pub(crate) fn theo1_sum(x: &[f64], m: usize) -> Option<(f64, usize)> {
    let n = x.len();
    if m < 2 || !m.is_multiple_of(2) || m >= n {
        return None;
    }
    let half = m / 2;
    let outer = n - m;
    let per_delta: Vec<f64> = (0..half)
        .into_par_iter()
        .map(|delta| theo1_lag_fast(x, m, delta) / (half - delta) as f64)
        .collect();
    Some((compensated_sum(per_delta.into_iter()), outer * half))
}

wide_variant! {
    /// Theo1's inner sum over i for one delta.
    fn theo1_lag_fast(x: &[f64], m: usize, delta: usize) -> f64 {
        theo1_lag(x, m, delta)
    }
}

#[inline(always)]
fn theo1_lag(x: &[f64], m: usize, delta: usize) -> f64 {
    let half = m / 2;
    let outer = x.len() - m;
    let a = &x[..outer];
    let b = &x[m..m + outer];
    let c = &x[half - delta..half - delta + outer];
    let d = &x[half + delta..half + delta + outer];
    let mut lanes = [0.0f64; 8];
    let full = outer / 8 * 8;
    for i in (0..full).step_by(8) {
        for (l, slot) in lanes.iter_mut().enumerate() {
            let k = i + l;
            let v = (a[k] - c[k]) + (b[k] - d[k]);
            *slot += v * v;
        }
    }
    for k in full..outer {
        let v = (a[k] - c[k]) + (b[k] - d[k]);
        lanes[0] += v * v;
    }
    pairwise_lanes(&lanes)
}

/// The gap-tolerant overlapping Allan sum (allantools `calc_gradev_phase`, stride 1): the sum
/// of (x_{i+2m} - 2 x_{i+m} + x_i)^2 over the i < N - 2m whose three phase points are all
/// present (not NaN), and how many there are.
pub fn gap_sum(x: &[f64], m: usize) -> (f64, usize) {
    let terms = x.len().saturating_sub(2 * m);
    if m == 0 || terms == 0 {
        return (0.0, 0);
    }
    let mut lanes = [0.0f64; 8];
    let mut count = 0usize;
    for i in 0..terms {
        let v = x[i + 2 * m] - 2.0 * x[i + m] + x[i];
        if !v.is_nan() {
            lanes[i % 8] += v * v;
            count += 1;
        }
    }
    (pairwise_lanes(&lanes), count)
}

/// Phase of rate samples with gaps, as allantools' `frequency2phase` makes it for `gradev`:
/// leading and trailing gaps (NaN) dropped, the mean of the samples present removed, then
/// x_0 = 0, x_{k+1} = x_k + tau0 (y_k - mean) (compensated), so a gap inside the record makes
/// every later phase point a gap too (allantools' cumulative sum does the same: `gradev`
/// documents that phase input "works better").
pub fn rate_to_phase_with_gaps(rate: &[f64], tau0_s: f64) -> Vec<f64> {
    let first = rate.iter().position(|v| !v.is_nan()).unwrap_or(rate.len());
    let last = rate
        .iter()
        .rposition(|v| !v.is_nan())
        .map_or(first, |i| i + 1);
    let rate = &rate[first..last.max(first)];
    let present = rate.iter().filter(|v| !v.is_nan()).count().max(1);
    let mean = compensated_sum(rate.iter().copied().filter(|v| !v.is_nan())) / present as f64;
    let mut phase = Vec::with_capacity(rate.len() + 1);
    phase.push(0.0);
    let (mut sum, mut comp) = (0.0f64, 0.0f64);
    for &y in rate {
        crate::sum::two_sum_acc(&mut sum, &mut comp, tau0_s * (y - mean));
        phase.push(sum + comp);
    }
    phase
}

/// Maximum time-interval error at averaging factor m: the largest peak-to-peak phase over the
/// N - m windows of m + 1 consecutive points (ITU-T G.810 §4.5.14; Stable32 "MTIE (Fast)",
/// allantools `mtie`). O(N) by monotonic queues of the window's maximum and minimum.
/// Returns (MTIE, N - m), `None` when m = 0 or m >= N.
pub fn mtie(x: &[f64], m: usize) -> Option<(f64, usize)> {
    let n = x.len();
    if m == 0 || m >= n {
        return None;
    }
    let width = m + 1;
    let mut hi: std::collections::VecDeque<usize> = std::collections::VecDeque::new();
    let mut lo: std::collections::VecDeque<usize> = std::collections::VecDeque::new();
    let mut worst = f64::NEG_INFINITY;
    for (k, &v) in x.iter().enumerate() {
        while hi.back().is_some_and(|&j| x[j] <= v) {
            hi.pop_back();
        }
        hi.push_back(k);
        while lo.back().is_some_and(|&j| x[j] >= v) {
            lo.pop_back();
        }
        lo.push_back(k);
        if k + 1 >= width {
            let first = k + 1 - width;
            while hi.front().is_some_and(|&j| j < first) {
                hi.pop_front();
            }
            while lo.front().is_some_and(|&j| j < first) {
                lo.pop_front();
            }
            worst = worst.max(x[hi[0]] - x[lo[0]]);
        }
    }
    Some((worst, n - m))
}

/// Root-mean-square time-interval error at averaging factor m: sqrt of the mean of
/// (x_{i+m} - x_i)^2 over the N - m pairs (ITU-T G.810 §4.5.13; Stable32 "TIE rms", allantools
/// `tierms`, whose max - min of two points is this difference's magnitude). Returns
/// (TIE rms, N - m), `None` when m = 0 or m >= N.
pub fn tie_rms(x: &[f64], m: usize) -> Option<(f64, usize)> {
    let n = x.len();
    if m == 0 || m >= n {
        return None;
    }
    let terms = n - m;
    let mut lanes = [0.0f64; 8];
    for (i, (a, b)) in x[..terms].iter().zip(&x[m..]).enumerate() {
        let v = b - a;
        lanes[i % 8] += v * v;
    }
    Some(((pairwise_lanes(&lanes) / terms as f64).sqrt(), terms))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn walk(n: usize, seed: u64) -> Vec<f64> {
        let mut g = testkit::SplitMix64::new(seed);
        let mut x = 0.0;
        (0..n)
            .map(|_| {
                x += g.normal();
                x
            })
            .collect()
    }

    /// The subsequence sum written out as SP 1065 / allantools state it: the 9m-point
    /// extended sequence built explicitly and its 6m m-point averages' second differences.
    fn total_reference(x: &[f64], m: usize) -> f64 {
        let len = 3 * m;
        let mut total = 0.0;
        for i in 0..=x.len() - len {
            let xs = &x[i..i + len];
            let half = len / 2;
            let m1: f64 = xs[..half].iter().sum::<f64>() / half as f64;
            let m2: f64 = xs[len - half..].iter().sum::<f64>() / half as f64;
            let dist = if len % 2 == 1 {
                0.5 * (len - 1) as f64 + 1.0
            } else {
                0.5 * len as f64
            };
            let s = (m2 - m1) / dist;
            let z: Vec<f64> = xs
                .iter()
                .enumerate()
                .map(|(k, v)| v - s * k as f64)
                .collect();
            let mut ext: Vec<f64> = z.iter().rev().copied().collect();
            ext.extend(&z);
            ext.extend(z.iter().rev());
            let avg = |j: usize| ext[j..j + m].iter().sum::<f64>() / m as f64;
            let mut sq = 0.0;
            for j in 0..6 * m {
                let v = avg(j) - 2.0 * avg(j + m) + avg(j + 2 * m);
                sq += v * v;
            }
            total += sq / (6 * m) as f64;
        }
        total
    }

    #[test]
    fn total_sum_matches_its_definition() {
        // Reason for 1e-12: the same sums by running prefix sums instead of direct averages.
        const REL_TOL: f64 = 1e-12;
        let x = walk(300, 3);
        for m in [1, 2, 3, 5, 8, 33, 99] {
            let (s, n) = total_window_sum(&x, m).unwrap();
            assert_eq!(n, 300 - 3 * m + 1);
            let r = total_reference(&x, m);
            assert!(((s - r) / r).abs() < REL_TOL, "m={m}: {s} vs {r}");
        }
        assert!(total_window_sum(&x, 101).is_none());
    }

    #[test]
    fn total_sum_ignores_a_linear_trend() {
        // Each subsequence's trend is removed: a phase ramp (a frequency offset) changes the
        // sum only by rounding (1e-9: the ramp reaches 1e3 times the walk's steps).
        let x = walk(500, 4);
        let ramp: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(k, v)| v + 0.7 * k as f64 + 5.0)
            .collect();
        for m in [1, 4, 16, 50] {
            let a = total_window_sum(&x, m).unwrap().0;
            let b = total_window_sum(&ramp, m).unwrap().0;
            assert!(((a - b) / a).abs() < 1e-9, "m={m}: {a} vs {b}");
        }
    }

    #[test]
    fn theo1_matches_its_definition() {
        // Reason for 1e-12: the same terms added in another order.
        const REL_TOL: f64 = 1e-12;
        let x = walk(200, 5);
        for m in [2, 4, 10, 64, 198] {
            let (s, n) = theo1_sum(&x, m).unwrap();
            let h = m / 2;
            let mut r = 0.0;
            for i in 0..200 - m {
                for d in 0..h {
                    let v = x[i] - x[i + h - d] + x[i + m] - x[i + h + d];
                    r += v * v / (h - d) as f64;
                }
            }
            assert_eq!(n, (200 - m) * h);
            assert!(((s - r) / r).abs() < REL_TOL, "m={m}: {s} vs {r}");
        }
        assert!(theo1_sum(&x, 3).is_none());
        assert!(theo1_sum(&x, 200).is_none());
    }

    #[test]
    fn mtie_and_tie_rms_match_their_definitions() {
        let x = walk(257, 6);
        for m in [1, 2, 7, 64, 256] {
            let (v, n) = mtie(&x, m).unwrap();
            let direct = (0..x.len() - m)
                .map(|i| {
                    let w = &x[i..=i + m];
                    w.iter().cloned().fold(f64::MIN, f64::max)
                        - w.iter().cloned().fold(f64::MAX, f64::min)
                })
                .fold(f64::MIN, f64::max);
            // Exact: the same differences of the same samples.
            assert_eq!(v, direct, "m={m}");
            assert_eq!(n, x.len() - m);
            let (t, _) = tie_rms(&x, m).unwrap();
            let r = ((0..x.len() - m)
                .map(|i| (x[i + m] - x[i]).powi(2))
                .sum::<f64>()
                / (x.len() - m) as f64)
                .sqrt();
            assert!(((t - r) / r).abs() < 1e-13, "m={m}");
        }
        assert!(mtie(&x, 257).is_none() && tie_rms(&x, 0).is_none());
    }

    #[test]
    fn gaps_leave_out_only_the_terms_they_touch() {
        let mut x = walk(100, 7);
        let (full, n_full) = gap_sum(&x, 3);
        assert_eq!(n_full, 94);
        x[50] = f64::NAN;
        let (s, n) = gap_sum(&x, 3);
        // x[50] enters the terms i = 50, 47 and 44 (as x_i, x_{i+m}, x_{i+2m}).
        assert_eq!(n, 91);
        let touched: f64 = [44usize, 47, 50]
            .iter()
            .map(|&i| {
                let y = walk(100, 7);
                (y[i + 6] - 2.0 * y[i + 3] + y[i]).powi(2)
            })
            .sum();
        assert!(((full - touched - s) / s).abs() < 1e-12);
    }
}
