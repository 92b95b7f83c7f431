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
    // Two blocks per task, their recursions interleaved: each is a chain of dependent additions,
    // and two chains keep the adder busy where one waits on its latency (each block's additions
    // are unchanged, so the values are too).
    out[..rate.len()]
        .par_chunks_mut(2 * PHASE_BLOCK)
        .zip(rate.par_chunks(2 * PHASE_BLOCK))
        .zip(plan.starts.par_chunks(2))
        .for_each(|((dst, src), starts)| {
            let (d0, d1) = dst.split_at_mut(PHASE_BLOCK.min(dst.len()));
            let (s0, s1) = src.split_at(PHASE_BLOCK.min(src.len()));
            let (mut a, mut b) = (starts[0], starts.get(1).copied().unwrap_or_default());
            let both = d1.len();
            for i in 0..both {
                let (ya, yb) = (s0[i] - plan.mean, s1[i] - plan.mean);
                d0[i] = (a.0 + a.1) * tau0_s;
                d1[i] = (b.0 + b.1) * tau0_s;
                two_sum_acc(&mut a.0, &mut a.1, ya);
                two_sum_acc(&mut b.0, &mut b.1, yb);
            }
            for i in both..d0.len() {
                let y = s0[i] - plan.mean;
                d0[i] = (a.0 + a.1) * tau0_s;
                two_sum_acc(&mut a.0, &mut a.1, y);
            }
        });
    out[rate.len()] = (plan.total.0 + plan.total.1) * tau0_s;
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
        // which every estimator's differences cancel. Plain 8-lane sums are accurate enough.
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
