//! Four lanes' blocks to and from sample-major order (dst[4 k + l] = lane l's sample k), the
//! layout the four-run SIMD loops read (`discrete::fused4`, `terms::output_filter`'s lanes):
//! 4 x 4 transposes of 256-bit registers, the tail sample by sample. Values are moved, never
//! computed on.

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

thread_local! {
    /// Blocks this thread ran through the four-run SIMD loops: (noise terms, output filters).
    static SIMD_BLOCKS: std::cell::Cell<(u64, u64)> = const { std::cell::Cell::new((0, 0)) };
}

/// Count one block of the four-run noise loop (`filter` false) or filter loop (`filter` true).
pub(crate) fn count_block(filter: bool) {
    SIMD_BLOCKS.with(|c| {
        let (t, f) = c.get();
        c.set(if filter { (t, f + 1) } else { (t + 1, f) });
    });
}

/// Blocks this thread has run through the four-run SIMD loops so far: (noise terms, output
/// filters). For tests that must know the lanes ran in SIMD and not one run at a time.
#[doc(hidden)]
pub fn simd_blocks() -> (u64, u64) {
    SIMD_BLOCKS.with(|c| c.get())
}

/// The 4 x 4 transpose of rows r0..r3 (row l: lane l's four samples) into four registers, one
/// sample's four lanes each.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn transpose(r: [__m256d; 4]) -> [__m256d; 4] {
    // SAFETY: AVX is implied by the callers' AVX2 (`target_feature` on every caller).
    unsafe {
        let t0 = _mm256_unpacklo_pd(r[0], r[1]);
        let t1 = _mm256_unpackhi_pd(r[0], r[1]);
        let t2 = _mm256_unpacklo_pd(r[2], r[3]);
        let t3 = _mm256_unpackhi_pd(r[2], r[3]);
        [
            _mm256_permute2f128_pd::<0x20>(t0, t2),
            _mm256_permute2f128_pd::<0x20>(t1, t3),
            _mm256_permute2f128_pd::<0x31>(t0, t2),
            _mm256_permute2f128_pd::<0x31>(t1, t3),
        ]
    }
}

/// dst[4 k + l] = src[l][k] for k < dst.len() / 4 (each src at least that long).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(crate) fn interleave(src: [&[f64]; 4], dst: &mut [f64]) {
    let len = dst.len() / 4;
    assert!(
        src.iter().all(|s| s.len() >= len),
        "four blocks of the length"
    );
    let whole = len / 4 * 4;
    for k in (0..whole).step_by(4) {
        // SAFETY: src[l][k..k + 4] and dst[4k..4k + 16] are in bounds (k + 4 <= len).
        unsafe {
            let rows = src.map(|s| _mm256_loadu_pd(s.as_ptr().add(k)));
            let d = dst.as_mut_ptr().add(4 * k);
            for (i, v) in transpose(rows).into_iter().enumerate() {
                _mm256_storeu_pd(d.add(4 * i), v);
            }
        }
    }
    for k in whole..len {
        for (l, s) in src.iter().enumerate() {
            dst[4 * k + l] = s[k];
        }
    }
}

/// dst[l][k] = src[4 k + l] for k < src.len() / 4 (each dst at least that long).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(crate) fn deinterleave(src: &[f64], dst: [&mut [f64]; 4]) {
    let len = src.len() / 4;
    assert!(
        dst.iter().all(|d| d.len() >= len),
        "four blocks of the length"
    );
    let mut dst = dst;
    let whole = len / 4 * 4;
    for k in (0..whole).step_by(4) {
        // SAFETY: src[4k..4k + 16] and each dst[l][k..k + 4] are in bounds.
        unsafe {
            let s = src.as_ptr().add(4 * k);
            let rows = [0, 1, 2, 3].map(|i| _mm256_loadu_pd(s.add(4 * i)));
            for (d, v) in dst.iter_mut().zip(transpose(rows)) {
                _mm256_storeu_pd(d.as_mut_ptr().add(k), v);
            }
        }
    }
    for k in whole..len {
        for (l, d) in dst.iter_mut().enumerate() {
            d[k] = src[4 * k + l];
        }
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    /// Interleaving and back gives the blocks, at lengths with and without a tail.
    #[test]
    fn interleave_and_back() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        for len in [0usize, 1, 3, 4, 5, 17, 64] {
            let src: Vec<Vec<f64>> = (0..4)
                .map(|l| (0..len).map(|k| (100 * l + k) as f64).collect())
                .collect();
            let mut mixed = vec![0.0; 4 * len];
            // SAFETY: AVX2 checked above.
            unsafe { super::interleave(std::array::from_fn(|l| &src[l][..]), &mut mixed) };
            for k in 0..len {
                for l in 0..4 {
                    assert_eq!(mixed[4 * k + l], src[l][k]);
                }
            }
            let mut back = vec![vec![0.0; len]; 4];
            let [b0, b1, b2, b3] = &mut back[..] else {
                unreachable!()
            };
            // SAFETY: AVX2 checked above.
            unsafe { super::deinterleave(&mixed, [b0, b1, b2, b3].map(|b| &mut b[..])) };
            assert_eq!(back, src);
        }
    }
}
