//! The hot kernels: the estimators' sums of squared differences (one tau, or all small taus in
//! one cache-blocked pass), each compiled for SSE2, AVX2 and AVX-512 and chosen at run time.
//! The only `unsafe` of the crate is here (calling a variant the CPU was checked to support).

use crate::sum::{compensated_sum, neumaier_acc, pairwise_lanes};
use crate::{edf, Estimator};

/// `fn name(args) -> ret { body }`, compiled three times: as is, with AVX2 and with AVX-512F
/// enabled, the widest the CPU has chosen at run time (x86-64). The results are the same bit
/// for bit: the kernels' additions are written out in a fixed order (lanes), Rust does not
/// contract a*b+c into FMA, and the vector width only changes how many lanes one instruction
/// does (measured on the 4.32 M-sample benchmark, one thread: blocked kernel 30 ms SSE2,
/// 20 ms AVX2, 17.5 ms AVX-512; noise identification 19.3 -> 16.3 ms from AVX2 to AVX-512).
/// The kernels the body calls are `#[inline(always)]`, so they are compiled inside each variant.
macro_rules! wide_variant {
    ($(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),*) -> $ret:ty $body:block) => {
        $(#[$meta])*
        $vis fn $name($($arg: $ty),*) -> $ret {
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
    pub(crate) fn blocked_diff_sums_fast(x: &[f64], ms: &[usize], order: usize) -> Vec<f64> {
        blocked_diff_sums(x, ms, order)
    }
}

wide_variant! {
    /// [`estimator_sum`], vectorised as wide as the CPU allows.
    pub(crate) fn estimator_sum_fast(x: &[f64], est: Estimator, m: usize) -> Option<(f64, usize)> {
        estimator_sum(x, est, m)
    }
}

wide_variant! {
    /// Noise identification of rate data from the phase: block sums at stride m.
    pub(crate) fn rate_noise_id_fast(x: &[f64], m: usize, blocks: usize, d_max: u32) -> Option<i32> {
        edf::rate_noise_id_fn(blocks, |j| x[(j + 1) * m] - x[j * m], d_max)
    }
}

/// Sum of squares of the estimator's differences and the number of terms, or `None` if the
/// record is too short for this m.
#[inline(always)]
pub(crate) fn estimator_sum(x: &[f64], est: Estimator, m: usize) -> Option<(f64, usize)> {
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
                neumaier_acc(&mut v, &mut vc, inc);
                let w = v + vc;
                s += w * w;
            }
            Some((s, terms))
        }
        Estimator::Total => {
            // SP 1065 eq (25) with the doubly reflected series of allantools `totdev`:
            // x*_{-j} = 2 x_0 - x_j, x*_{n-1+j} = 2 x_{n-1} - x_{n-1-j}, j = 1..n-2;
            // sum over i = 1..n-2 of (x*_{i-m} - 2 x*_i + x*_{i+m})^2. The reflections reach
            // i - m = 2 - n and i + m = 2n - 3 for m = n - 1, the largest factor (allantools and
            // SP 1065 eq 25 both allow it).
            if n < 3 || m >= n {
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
pub(crate) const BLOCKED_MAX_M: usize = 1 << 16;
/// Block length of the blocked kernel (phase values per block and factor).
const BLOCK: usize = 4096;

/// For each m (ascending), the sum over i < n - order*m of the squared `order`-th difference
/// at lag m (order 2: x[i+2m] - 2x[i+m] + x[i]; order 3: the Hadamard third difference),
/// computed block by block for all m together. Each m keeps 8 lane accumulators (lane =
/// i mod 8), so the result does not depend on the block size or on how the caller splits work.
#[inline(always)]
pub(crate) fn blocked_diff_sums(x: &[f64], ms: &[usize], order: usize) -> Vec<f64> {
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
