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
/// Exported for the other crates' lane kernels (`diagnose`'s transient profile).
#[macro_export]
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
    /// [`streamed_diff_sums`], vectorised as wide as the CPU allows.
    pub(crate) fn streamed_diff_sums_fast(x: &[f64], ms: &[usize], order: usize) -> Vec<f64> {
        streamed_diff_sums(x, ms, order)
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
        // Their sums need more than one pass over the phase (subsequences, frequency, a bias
        // factor): `crate::total`, reached through `Series::raw_point`.
        Estimator::ModifiedTotal => crate::total::total_window_sum(x, m),
        Estimator::Theo1 => crate::total::theo1_sum(x, m),
        Estimator::HadamardTotal | Estimator::TheoH => {
            unreachable!("Series::raw_point computes {est:?} from its parts")
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
    diff_sums_by_block(x, ms, order, Tail::ByIndex)
}

/// For each m, exactly the sum [`estimator_sum`] gives for the overlapping estimators (lanes
/// i mod 8 over whole groups of 8 terms, the last terms % 8 terms into lane 0), computed block by
/// block for all m together: for factors too large for [`blocked_diff_sums`]'s reuse window,
/// the m of a grid share their streams instead (an octave grid's offsets m, 2m coincide with the
/// next factor's: 7 streams for 5 factors rather than 15 passes over the record).
#[inline(always)]
pub(crate) fn streamed_diff_sums(x: &[f64], ms: &[usize], order: usize) -> Vec<f64> {
    diff_sums_by_block(x, ms, order, Tail::LaneZero)
}

/// Where the terms after the last whole group of 8 go.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Tail {
    /// Lane i mod 8 (the blocked kernel).
    ByIndex,
    /// Lane 0 (the single-factor kernels `second_diff_sum_sq`, `third_diff_sum_sq`).
    LaneZero,
}

#[inline(always)]
fn diff_sums_by_block(x: &[f64], ms: &[usize], order: usize, tail: Tail) -> Vec<f64> {
    const LANES: usize = 8;
    let n = x.len();
    let terms: Vec<usize> = ms.iter().map(|&m| n.saturating_sub(order * m)).collect();
    let max_terms = terms.iter().copied().max().unwrap_or(0);
    let mut acc = vec![[0.0f64; LANES]; ms.len()];
    let mut start = 0;
    // The factors whose block is whole, in groups of FUSED: their sums advance in one loop.
    let mut whole_block: Vec<usize> = Vec::with_capacity(ms.len());
    while start < max_terms {
        whole_block.clear();
        for (i, (&m, &t)) in ms.iter().zip(&terms).enumerate() {
            if start >= t {
                continue;
            }
            let end = (start + BLOCK).min(t);
            // The single-factor kernels put the terms after the last whole group into lane 0.
            let whole = if tail == Tail::LaneZero {
                t / LANES * LANES
            } else {
                t
            };
            let split = end.min(whole.max(start));
            if split == start + BLOCK {
                whole_block.push(i);
                continue;
            }
            let a = &mut acc[i];
            if order == 2 {
                block_second(x, m, start, split, a);
            } else {
                block_third(x, m, start, split, a);
            }
            tail_terms(x, m, order, split, end, &mut a[0]);
        }
        let mut groups = whole_block.chunks_exact(FUSED);
        for group in &mut groups {
            fused::<FUSED>(x, ms, order, group, start, &mut acc);
        }
        for &i in groups.remainder() {
            if order == 2 {
                block_second(x, ms[i], start, start + BLOCK, &mut acc[i]);
            } else {
                block_third(x, ms[i], start, start + BLOCK, &mut acc[i]);
            }
        }
        start += BLOCK;
    }
    acc.iter().map(pairwise_lanes).collect()
}

/// Factors advanced together over a whole block: each factor's lanes form their own chain of
/// additions, so up to FUSED chains run at once where one factor alone waits on the latency of
/// its additions (the order of each factor's additions is unchanged: the same sums, bit for bit).
/// Three, not four: with four factors (one AVX2 register of f64) the compiler vectorised across
/// the factors, transposing every step (the deviations of 4.32 M samples took 115-165 ms); with
/// three it keeps one factor's 8 lanes in two registers (43-66 ms, as before that flip).
const FUSED: usize = 3;

/// The whole block at `start` of the K factors `ms[group[k]]`, their lanes `acc[group[k]]`.
#[inline(always)]
fn fused<const K: usize>(
    x: &[f64],
    ms: &[usize],
    order: usize,
    group: &[usize],
    start: usize,
    acc: &mut [[f64; 8]],
) {
    let idx: [usize; K] = std::array::from_fn(|k| group[k]);
    let mut lanes: [[f64; 8]; K] = idx.map(|i| acc[i]);
    let lags = idx.map(|i| ms[i]);
    if order == 2 {
        fused_second(x, lags, start, &mut lanes);
    } else {
        fused_third(x, lags, start, &mut lanes);
    }
    for (&i, l) in idx.iter().zip(lanes) {
        acc[i] = l;
    }
}

/// The whole block of `x` at `from`.
#[inline(always)]
fn window(x: &[f64], from: usize) -> &[f64; BLOCK] {
    x[from..from + BLOCK]
        .try_into()
        .expect("a whole block lies inside the record")
}

/// `block_second` over the whole block at `start` for K factors at once.
// Indexed lanes: the shape the compiler turns into one vector register per factor.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn fused_second<const K: usize>(x: &[f64], ms: [usize; K], start: usize, acc: &mut [[f64; 8]; K]) {
    let win = |off: usize| window(x, start + off);
    let a = win(0);
    let b: [&[f64; BLOCK]; K] = ms.map(&win);
    let c: [&[f64; BLOCK]; K] = ms.map(|m| win(2 * m));
    for j in 0..BLOCK / 8 {
        for k in 0..K {
            for l in 0..8 {
                let i = 8 * j + l;
                let v = c[k][i] - 2.0 * b[k][i] + a[i];
                acc[k][l] += v * v;
            }
        }
    }
}

/// `block_third` over the whole block at `start` for K factors at once.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn fused_third<const K: usize>(x: &[f64], ms: [usize; K], start: usize, acc: &mut [[f64; 8]; K]) {
    let win = |off: usize| window(x, start + off);
    let a = win(0);
    let b: [&[f64; BLOCK]; K] = ms.map(&win);
    let c: [&[f64; BLOCK]; K] = ms.map(|m| win(2 * m));
    let d: [&[f64; BLOCK]; K] = ms.map(|m| win(3 * m));
    for j in 0..BLOCK / 8 {
        for k in 0..K {
            for l in 0..8 {
                let i = 8 * j + l;
                let v = d[k][i] - 3.0 * c[k][i] + 3.0 * b[k][i] - a[i];
                acc[k][l] += v * v;
            }
        }
    }
}

/// The terms start..end added one by one into `acc`, in index order.
#[inline(always)]
fn tail_terms(x: &[f64], m: usize, order: usize, start: usize, end: usize, acc: &mut f64) {
    for k in start..end {
        let v = if order == 2 {
            x[k + 2 * m] - 2.0 * x[k + m] + x[k]
        } else {
            x[k + 3 * m] - 3.0 * x[k + 2 * m] + 3.0 * x[k + m] - x[k]
        };
        *acc += v * v;
    }
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
