//! Summation shared by the phase conversion and the estimator kernels: the fixed-order 8-lane
//! reduction, Knuth's TwoSum accumulation and the Neumaier compensated sum.

/// The sum of 8 accumulator lanes, pairwise in a fixed order (the same result on every target).
#[inline(always)]
pub(crate) fn pairwise_lanes(acc: &[f64; 8]) -> f64 {
    ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]))
}

/// sum += v with the exact rounding error added to comp (Knuth's TwoSum, branch-free).
#[inline(always)]
pub(crate) fn two_sum_acc(sum: &mut f64, comp: &mut f64, v: f64) {
    let t = *sum + v;
    let bv = t - *sum;
    *comp += (*sum - (t - bv)) + (v - bv);
    *sum = t;
}

/// sum += v with the rounding error added to comp (Neumaier 1974: the larger addend's error).
#[inline(always)]
pub(crate) fn neumaier_acc(sum: &mut f64, comp: &mut f64, v: f64) {
    let t = *sum + v;
    if sum.abs() >= v.abs() {
        *comp += (*sum - t) + v;
    } else {
        *comp += (v - t) + *sum;
    }
    *sum = t;
}

/// Neumaier compensated sum.
pub fn compensated_sum(values: impl Iterator<Item = f64>) -> f64 {
    let (mut sum, mut comp) = (0.0f64, 0.0f64);
    for v in values {
        neumaier_acc(&mut sum, &mut comp, v);
    }
    sum + comp
}
