//! Rate samples to phase (integrated rate) with compensated summation, in parallel over fixed
//! blocks so the result does not depend on the thread count.

use crate::sum::{pairwise_lanes, two_sum_acc};

/// Phase (integrated rate) with x_0 = 0 and x_n = tau0 * sum_{k<n} (y_k - mean(y)),
/// docs/model.md §2.1 and allantools `frequency2phase` (mean removed before the sum to keep the
/// phase small). The running sum is compensated (Knuth's TwoSum error term carried along,
/// as in Neumaier 1974), so x_n is the partial sum to within a few ulps.
///
/// Reads `rate` in place (two read passes and the pass that writes the phase into a new array:
/// no copy of the rate); the same values as [`rate_to_phase_in_place`].
pub fn rate_to_phase(rate: &[f64], tau0_s: f64) -> Vec<f64> {
    // Zeroed by the allocator (fresh pages of a large array cost no pass here).
    let mut out = vec![0.0f64; rate.len() + 1];
    rate_to_phase_into(rate, tau0_s, &mut out);
    out
}

/// [`rate_to_phase`] into `out`, of `rate.len() + 1` points (a caller's array, e.g. one its
/// allocator backs with huge pages). Panics on another length (a programming error).
pub fn rate_to_phase_into(rate: &[f64], tau0_s: f64, out: &mut [f64]) {
    use rayon::prelude::*;
    assert_eq!(
        out.len(),
        rate.len() + 1,
        "the phase has one point more than the rate"
    );
    let plan = PhasePlan::of(rate);
    // Up to eight blocks per task, their recursions interleaved: each is a chain of dependent
    // additions, and eight chains keep the adders busy where one waits on its latency (each
    // block's additions are unchanged, so the values are too; test below).
    out[..rate.len()]
        .par_chunks_mut(LOCKSTEP * PHASE_BLOCK)
        .zip(rate.par_chunks(LOCKSTEP * PHASE_BLOCK))
        .zip(plan.starts.par_chunks(LOCKSTEP))
        .for_each(|((dst, src), starts)| {
            let mut blocks: Vec<PhaseBlock> = dst
                .chunks_mut(PHASE_BLOCK)
                .zip(src.chunks(PHASE_BLOCK))
                .zip(starts.iter().copied())
                .map(|((d, s), st)| (d, s, st))
                .collect();
            // Groups of 8, 4, 2, 1 whole blocks side by side; a short last block alone.
            let mut rest = &mut blocks[..];
            while !rest.is_empty() {
                let whole = rest.iter().take_while(|b| b.0.len() == PHASE_BLOCK).count();
                let n = match whole {
                    8.. => recursions::<8>(rest, plan.mean, tau0_s),
                    4..=7 => recursions::<4>(rest, plan.mean, tau0_s),
                    2..=3 => recursions::<2>(rest, plan.mean, tau0_s),
                    _ => recursions::<1>(rest, plan.mean, tau0_s),
                };
                rest = &mut rest[n..];
            }
        });
    out[rate.len()] = (plan.total.0 + plan.total.1) * tau0_s;
}

/// One block of the phase recursion: its destination, its rate samples and the running
/// compensated sum (sum, error) at its start.
type PhaseBlock<'a> = (&'a mut [f64], &'a [f64], (f64, f64));

/// Blocks whose recursions one task runs side by side.
const LOCKSTEP: usize = 8;

/// The compensated phase recursion of the first `N` blocks of `blocks` (destination, rate, start)
/// side by side over their common length, each block's remainder after it alone; returns N.
#[inline(always)]
fn recursions<const N: usize>(blocks: &mut [PhaseBlock], mean: f64, tau0_s: f64) -> usize {
    let group = &mut blocks[..N];
    let common = group.iter().map(|b| b.0.len()).min().unwrap_or(0);
    let mut sum: [f64; N] = std::array::from_fn(|k| group[k].2 .0);
    let mut comp: [f64; N] = std::array::from_fn(|k| group[k].2 .1);
    for i in 0..common {
        for k in 0..N {
            let y = group[k].1[i] - mean;
            group[k].0[i] = (sum[k] + comp[k]) * tau0_s;
            two_sum_acc(&mut sum[k], &mut comp[k], y);
        }
    }
    for (k, (d, s, _)) in group.iter_mut().enumerate() {
        for i in common..d.len() {
            let y = s[i] - mean;
            d[i] = (sum[k] + comp[k]) * tau0_s;
            two_sum_acc(&mut sum[k], &mut comp[k], y);
        }
    }
    N
}

/// Samples per block of the phase conversion. Fixed, not per thread: the result does not
/// depend on the thread count.
const PHASE_BLOCK: usize = 1 << 16;

/// What the phase recursion needs before it runs: the mean of the rate, the compensated running
/// (sum, error) of (y - mean) at every block start, and at the end.
struct PhasePlan {
    mean: f64,
    starts: Vec<(f64, f64)>,
    total: (f64, f64),
}

impl PhasePlan {
    /// The mean from per-block 8-lane sums added in block order; each block's compensated sum
    /// (8 lanes of TwoSum, then the lanes in order); the running (sum, error) at every block
    /// start from those, in block order.
    fn of(rate: &[f64]) -> PhasePlan {
        use rayon::prelude::*;
        let n = rate.len();
        // The mean only keeps the phase small: any rounding in it adds a linear phase trend,
        // which every estimator's differences cancel. Plain 8-lane sums are accurate enough (and
        // not `stats::mean`'s left-to-right sum: the block sums are the lanes' order).
        let block_sums: Vec<f64> = rate.par_chunks(PHASE_BLOCK).map(block_sum).collect();
        let mean = block_sums.iter().sum::<f64>() / n.max(1) as f64;
        // Compensated sum of (y - mean) of every block: (sum, error).
        let block_totals: Vec<(f64, f64)> = rate
            .par_chunks(PHASE_BLOCK)
            .map(|b| block_total(b, mean))
            .collect();
        let mut starts = Vec::with_capacity(block_totals.len());
        let (mut sum, mut comp) = (0.0f64, 0.0f64);
        for &(s, c) in &block_totals {
            starts.push((sum, comp));
            two_sum_acc(&mut sum, &mut comp, s);
            comp += c;
        }
        PhasePlan {
            mean,
            starts,
            total: (sum, comp),
        }
    }
}

crate::wide_variant! {
    /// The sum of one block: 8 lanes in a fixed order, then the tail ([`PhasePlan::of`]'s mean).
    fn block_sum(b: &[f64]) -> f64 {
        let mut lanes = [0.0f64; 8];
        let chunks = b.chunks_exact(8);
        let tail: f64 = chunks.remainder().iter().sum();
        for c in chunks {
            for (l, v) in lanes.iter_mut().zip(c) {
                *l += v;
            }
        }
        pairwise_lanes(&lanes) + tail
    }
}

crate::wide_variant! {
    /// The compensated sum (sum, error) of one block of y - `mean`: 8 lanes of TwoSum, then the
    /// lanes and the tail in order ([`PhasePlan::of`]'s block totals).
    fn block_total(b: &[f64], mean: f64) -> (f64, f64) {
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
    }
}

/// [`rate_to_phase`] in the rate's own buffer (x_k overwrites y_k, x_n is appended), in
/// parallel over fixed blocks ([`PhasePlan`], then every block runs the compensated recursion
/// from its start).
pub fn rate_to_phase_in_place(mut buf: Vec<f64>, tau0_s: f64) -> Vec<f64> {
    use rayon::prelude::*;
    let plan = PhasePlan::of(&buf);
    buf.par_chunks_mut(PHASE_BLOCK)
        .zip(plan.starts.par_iter())
        .for_each(|(b, &(mut sum, mut comp))| {
            for v in b.iter_mut() {
                let y = *v - plan.mean;
                *v = (sum + comp) * tau0_s;
                two_sum_acc(&mut sum, &mut comp, y);
            }
        });
    buf.push((plan.total.0 + plan.total.1) * tau0_s);
    buf
}
