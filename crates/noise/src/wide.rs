//! The wide normal sampler of the hot path: one term's stream of standard normals, drawn eight at
//! a time.
//!
//! A [`NormalStream`] holds eight Xoshiro256++ generators (Blackman & Vigna 2021, "Scrambled
//! linear pseudorandom number generators", ACM TOMS 47(4); the same step as `rand_xoshiro`'s
//! `Xoshiro256PlusPlus::next_u64`), advanced in lockstep (lane l gives draws 8k + l), and a
//! ninth, sequential one (the term's own stream, [`crate::ImuRng`]) whose first 32 outputs seeded
//! the eight lanes. Each 64-bit lane output goes through the first pass of the ziggurat of
//! `crate::ziggurat` (Doornik 2005, ZIGNOR, 256 layers: layer i from the low 8 bits, u in [-1, 1)
//! from the high 52, x = u X_i, accepted when |x| < X_{i+1}, about 98.8 % of draws); a draw that
//! fails that test is finished by the rest of the same algorithm (the base strip's tail, the
//! wedge test, a fresh draw) with further bits from the sequential generator, in draw order.
//! So every value has exactly the ziggurat's distribution (the bits the algorithm consumes are
//! independent uniform bits, only their source differs), and draw k is a pure function of the
//! stream and k: the values do not depend on how the caller splits its requests into blocks
//! (draws made ahead are kept in a buffer), which the block path and the sample-by-sample path
//! rely on (tested below).
//!
//! Why: one Xoshiro256++ generator is a serial dependency chain (about 2 ns per normal with the
//! ziggurat on the CI machine); eight independent lanes are eight chains the CPU runs side by
//! side, and with AVX2 / AVX-512 (chosen at run time) one instruction advances four or eight
//! lanes. The vector width changes only how many lanes an instruction does: integer steps,
//! one multiplication and one comparison per draw, the same bits at every width.

use crate::ziggurat::{finish_rejected_bits, with_exponent, ZIG_NORM_X};
use crate::ImuRng;
use rand::RngCore;

/// Lanes of a [`NormalStream`]: draws made per group.
pub(crate) const LANES: usize = 8;

/// One term's stream of standard normals (see the module docs).
#[derive(Clone, Debug)]
pub struct NormalStream {
    /// The four state words of each lane's Xoshiro256++ (word w of lane l at `state[w][l]`).
    state: [[u64; LANES]; 4],
    /// The sequential generator: the bits of the draws the first ziggurat pass rejects.
    fallback: ImuRng,
    /// The last groups drawn and how many of their values were handed out.
    buffer: [f64; BUFFERED],
    used: usize,
}

impl NormalStream {
    /// The stream of the sequential generator `rng`: its next 32 outputs seed the eight lanes
    /// (lane l, word w from output 4l + w; an all-zero state, which Xoshiro cannot leave, is
    /// replaced, with probability 2^-256), then it supplies the bits of the rejected draws.
    pub fn new(mut rng: ImuRng) -> NormalStream {
        let mut state = [[0u64; LANES]; 4];
        for lane in 0..LANES {
            for word in &mut state {
                word[lane] = rng.next_u64();
            }
            if state.iter().all(|w| w[lane] == 0) {
                state[0][lane] = 1;
            }
        }
        NormalStream {
            state,
            fallback: rng,
            buffer: [0.0; BUFFERED],
            used: BUFFERED,
        }
    }

    /// The next standard normal.
    #[inline]
    pub fn normal(&mut self) -> f64 {
        if self.used == BUFFERED {
            groups_fast(&mut self.state, &mut self.fallback, &mut self.buffer);
            self.used = 0;
        }
        self.used += 1;
        self.buffer[self.used - 1]
    }

    /// The next `out.len()` standard normals, in order: the values of as many [`Self::normal`] calls.
    pub fn fill(&mut self, out: &mut [f64]) {
        let take = (BUFFERED - self.used).min(out.len());
        out[..take].copy_from_slice(&self.buffer[self.used..self.used + take]);
        self.used += take;
        let rest = &mut out[take..];
        let whole = rest.len() / LANES * LANES;
        let (bulk, tail) = rest.split_at_mut(whole);
        groups_fast(&mut self.state, &mut self.fallback, bulk);
        if !tail.is_empty() {
            groups_fast(&mut self.state, &mut self.fallback, &mut self.buffer);
            tail.copy_from_slice(&self.buffer[..tail.len()]);
            self.used = tail.len();
        }
    }
}

/// Draws made ahead and kept for the next requests: eight groups, so that a caller asking for a
/// few draws at a time (one sample of a run: `ImuErrors::corrupt`) pays the call into the
/// sampler once per 64 draws rather than per 8 (the values do not depend on it: draw k is a
/// function of the stream and k alone).
const BUFFERED: usize = 8 * LANES;

/// Draws per pass: the first ziggurat pass runs over this many, the rejected ones (about 1.5 %)
/// are collected and finished after it, in draw order, so the main loop has no branch.
const PASS: usize = 512;

/// Fill `out` (a multiple of [`LANES`] long) with whole groups: the lanes' next outputs through
/// the ziggurat's first pass, the rejected ones finished from `fallback` in draw order.
#[inline(always)]
fn groups(state: &mut [[u64; LANES]; 4], fallback: &mut ImuRng, out: &mut [f64]) {
    let [mut s0, mut s1, mut s2, mut s3] = *state;
    let mut rejected_at = [0u16; PASS];
    for pass in out.chunks_mut(PASS) {
        let mut count = 0usize;
        for (g, group) in pass.chunks_exact_mut(LANES).enumerate() {
            let mut bits = [0u64; LANES];
            for l in 0..LANES {
                // Xoshiro256++ (Blackman & Vigna 2021, xoshiro256plusplus.c): output, then advance.
                bits[l] = s0[l]
                    .wrapping_add(s3[l])
                    .rotate_left(23)
                    .wrapping_add(s0[l]);
                let t = s1[l] << 17;
                s2[l] ^= s0[l];
                s3[l] ^= s1[l];
                s1[l] ^= s2[l];
                s0[l] ^= s3[l];
                s2[l] ^= t;
                s3[l] = s3[l].rotate_left(45);
            }
            for l in 0..LANES {
                // The ziggurat's first pass (crate::ziggurat::standard_normal): layer, u in
                // [-1, 1), x = u X_i, accepted when |x| < X_{i+1}. The bits of a draw are kept
                // in place of its value until it is finished (below); a rejected draw's position
                // is appended without a branch.
                let i = (bits[l] & 0xff) as usize;
                let x = (with_exponent(bits[l] >> 12, 1) - 3.0) * ZIG_NORM_X[i];
                let rejected = x.abs() >= ZIG_NORM_X[i + 1];
                group[l] = if rejected { f64::from_bits(bits[l]) } else { x };
                rejected_at[count] = (g * LANES + l) as u16;
                count += usize::from(rejected);
            }
        }
        for &at in &rejected_at[..count] {
            let at = usize::from(at);
            pass[at] = finish_rejected_bits(fallback, pass[at].to_bits());
        }
    }
    *state = [s0, s1, s2, s3];
}

/// [`groups`] with AVX-512 where the CPU has it (chosen at run time; [`avx512::groups`], the same
/// bits), else compiled with AVX2 enabled where available, else as is.
fn groups_fast(state: &mut [[u64; LANES]; 4], fallback: &mut ImuRng, out: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports AVX-512F (checked just above).
            return unsafe { avx512::groups(state, fallback, out) };
        }
        #[target_feature(enable = "avx2")]
        fn avx2(state: &mut [[u64; LANES]; 4], fallback: &mut ImuRng, out: &mut [f64]) {
            groups(state, fallback, out)
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            return unsafe { avx2(state, fallback, out) };
        }
    }
    groups(state, fallback, out)
}

/// [`groups`] written with AVX-512F intrinsics: the eight lanes' state words in four registers,
/// the two table lookups as gathers. The same operations on the same values in the same order as
/// [`groups`] (integer steps, one rounded multiplication, one comparison), so the same bits.
#[cfg(target_arch = "x86_64")]
mod avx512 {
    use super::{finish_rejected_bits, ImuRng, LANES, PASS};
    use crate::ziggurat::ZIG_NORM_X_PAIRS;
    use std::arch::x86_64::*;

    /// As [`super::groups`]. Safety: the CPU must support AVX-512F.
    #[target_feature(enable = "avx512f")]
    pub(super) fn groups(state: &mut [[u64; LANES]; 4], fallback: &mut ImuRng, out: &mut [f64]) {
        // SAFETY (every unsafe block below): unaligned loads and stores of exactly eight u64 /
        // f64 inside `state`, `layer`, `lo`, `hi` and `group` (each LANES = 8 long).
        let load = |w: &[u64; LANES]| unsafe { _mm512_loadu_si512(w.as_ptr().cast()) };
        let (mut s0, mut s1, mut s2, mut s3) = (
            load(&state[0]),
            load(&state[1]),
            load(&state[2]),
            load(&state[3]),
        );
        let low8 = _mm512_set1_epi64(0xff);
        let exponent = _mm512_set1_epi64(1024 << 52);
        let three = _mm512_set1_pd(3.0);
        let abs_mask = _mm512_set1_epi64(i64::MAX);
        let even = _mm512_set_epi64(14, 12, 10, 8, 6, 4, 2, 0);
        let odd = _mm512_set_epi64(15, 13, 11, 9, 7, 5, 3, 1);
        // Per group of the pass, the mask of its rejected lanes: one byte stored per group, no
        // branch and no dependency between groups (compressing the rejected lanes' positions
        // as they come made every group wait for the previous one's count).
        let mut rejected = [0u8; PASS / LANES];
        for pass in out.chunks_mut(PASS) {
            let groups = pass.len() / LANES;
            for (g, group) in pass.chunks_exact_mut(LANES).enumerate() {
                // Xoshiro256++: output rotl(s0 + s3, 23) + s0, then advance.
                let bits = _mm512_add_epi64(_mm512_rol_epi64::<23>(_mm512_add_epi64(s0, s3)), s0);
                // The advance's five xors as three three-way xors and one (0x96: a ^ b ^ c):
                // s2 ^ s0 ^ t, s1 ^ (s2 ^ s0), s0 ^ (s3 ^ s1), s3 ^ s1; the same values.
                let t = _mm512_slli_epi64::<17>(s1);
                let (n0, n1, n2) = (
                    _mm512_ternarylogic_epi64::<0x96>(s0, s3, s1),
                    _mm512_ternarylogic_epi64::<0x96>(s1, s2, s0),
                    _mm512_ternarylogic_epi64::<0x96>(s2, s0, t),
                );
                s3 = _mm512_rol_epi64::<45>(_mm512_xor_si512(s3, s1));
                (s0, s1, s2) = (n0, n1, n2);
                // The ziggurat's first pass: i = low 8 bits, u = [2, 4) - 3, x = u X_i,
                // accepted when |x| < X_{i+1}. The table is read with scalar loads (faster than
                // a gather on the CPUs measured, docs/performance.md).
                // Lane l's pair (X_i, X_{i+1}) in one load, at byte offset 16 i of the pair
                // table; lanes 0-3 into `a`, 4-7 into `b`, then the X_i and the X_{i+1} taken out
                // of them by two permutations. The offsets are read back from memory (volatile:
                // extracting them from the vector register took the shuffle unit the inserts need).
                let mut offset = [0u64; LANES];
                unsafe {
                    _mm512_storeu_si512(
                        offset.as_mut_ptr().cast(),
                        _mm512_slli_epi64::<4>(_mm512_and_si512(bits, low8)),
                    )
                };
                let table = ZIG_NORM_X_PAIRS.as_ptr().cast::<u8>();
                let pair = |l: usize| {
                    // SAFETY: l < LANES, and offset[l] = 16 i with i < 256 (stored just above),
                    // the start of pair i of the 256.
                    unsafe {
                        let at = std::ptr::read_volatile(offset.as_ptr().add(l)) as usize;
                        _mm_load_pd(table.add(at).cast())
                    }
                };
                let a = _mm512_insertf64x4::<1>(
                    _mm512_castpd256_pd512(_mm256_set_m128d(pair(1), pair(0))),
                    _mm256_set_m128d(pair(3), pair(2)),
                );
                let b = _mm512_insertf64x4::<1>(
                    _mm512_castpd256_pd512(_mm256_set_m128d(pair(5), pair(4))),
                    _mm256_set_m128d(pair(7), pair(6)),
                );
                let lo = _mm512_permutex2var_pd(a, even, b);
                let hi = _mm512_permutex2var_pd(a, odd, b);
                let u = _mm512_sub_pd(
                    _mm512_castsi512_pd(_mm512_or_si512(_mm512_srli_epi64::<12>(bits), exponent)),
                    three,
                );
                let x = _mm512_mul_pd(u, lo);
                let abs = _mm512_castsi512_pd(_mm512_and_si512(_mm512_castpd_si512(x), abs_mask));
                let accepted = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(abs, hi);
                // A rejected draw's bits are kept in place of its value until it is finished
                // (below), as in [`super::groups`].
                let kept = _mm512_mask_blend_pd(!accepted, x, _mm512_castsi512_pd(bits));
                unsafe { _mm512_storeu_pd(group.as_mut_ptr(), kept) };
                rejected[g] = !accepted;
            }
            // The rejected draws finished in draw order (group, then lane): eight groups' masks
            // read as one little-endian word, whose set bits are the positions in order (a
            // branch per word, not per group).
            // A short (last) pass leaves no earlier pass's masks after its own.
            rejected[groups..].fill(0);
            for g0 in (0..groups).step_by(8) {
                let word: [u8; 8] = rejected[g0..g0 + 8].try_into().expect("g0 <= 56");
                let mut mask = u64::from_le_bytes(word);
                while mask != 0 {
                    let at = g0 * LANES + mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    pass[at] = finish_rejected_bits(fallback, pass[at].to_bits());
                }
            }
        }
        let store =
            |w: &mut [u64; LANES], v| unsafe { _mm512_storeu_si512(w.as_mut_ptr().cast(), v) };
        store(&mut state[0], s0);
        store(&mut state[1], s1);
        store(&mut state[2], s2);
        store(&mut state[3], s3);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn stream(seed: u64) -> NormalStream {
        NormalStream::new(ImuRng::seed_from_u64(seed))
    }

    #[test]
    fn lanes_follow_rand_xoshiro() {
        // Lane l is rand_xoshiro's Xoshiro256++ seeded with the parent's outputs 4l..4l+3, and
        // draw 8k + l is its k-th output through the ziggurat (its first pass where that accepts).
        let mut parent = ImuRng::seed_from_u64(3);
        let words: Vec<u64> = (0..4 * LANES).map(|_| parent.next_u64()).collect();
        let mut lanes: Vec<ImuRng> = (0..LANES)
            .map(|l| {
                let mut seed = [0u8; 32];
                for w in 0..4 {
                    seed[8 * w..8 * w + 8].copy_from_slice(&words[4 * l + w].to_le_bytes());
                }
                ImuRng::from_seed(seed)
            })
            .collect();
        let mut out = vec![0.0; 8 * 1000];
        stream(3).fill(&mut out);
        let mut compared = 0;
        for (k, &v) in out.iter().enumerate() {
            let bits = lanes[k % LANES].next_u64();
            let i = (bits & 0xff) as usize;
            let x = (with_exponent(bits >> 12, 1) - 3.0) * ZIG_NORM_X[i];
            if x.abs() < ZIG_NORM_X[i + 1] {
                assert_eq!(v.to_bits(), x.to_bits(), "draw {k}");
                compared += 1;
            }
        }
        // About 98.5 % pass the first test (1.5 % rejection, computed from the table).
        assert!(compared > 7_700, "{compared}");
    }

    #[test]
    fn values_do_not_depend_on_the_block_split() {
        let n = 5_000;
        let mut whole = vec![0.0; n];
        stream(11).fill(&mut whole);
        // Uneven blocks, single draws and empty requests in between.
        let mut parts = Vec::with_capacity(n);
        let mut s = stream(11);
        let sizes = [1usize, 0, 3, 7, 8, 9, 15, 16, 17, 256, 1, 255, 2];
        let mut k = 0;
        while parts.len() < n {
            let m = sizes[k % sizes.len()].min(n - parts.len());
            if k % 5 == 4 && m > 0 {
                parts.push(s.normal());
            } else {
                let mut b = vec![0.0; m];
                s.fill(&mut b);
                parts.extend_from_slice(&b);
            }
            k += 1;
        }
        for (j, (a, b)) in whole.iter().zip(&parts).enumerate() {
            assert_eq!(a.to_bits(), b.to_bits(), "draw {j}");
        }
    }

    #[test]
    fn every_width_gives_the_same_bits() {
        let mut a = stream(17);
        let mut b = a.clone();
        let mut x = vec![0.0; 800_000];
        let mut y = vec![0.0; 800_000];
        groups_fast(&mut a.state, &mut a.fallback, &mut x);
        groups(&mut b.state, &mut b.fallback, &mut y);
        // The AVX2 build of the generic code too, where the CPU has it.
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            #[target_feature(enable = "avx2")]
            fn avx2(state: &mut [[u64; LANES]; 4], fallback: &mut ImuRng, out: &mut [f64]) {
                groups(state, fallback, out)
            }
            let mut c = stream(17);
            let mut z = vec![0.0; 800_000];
            // SAFETY: the CPU supports AVX2 (checked just above).
            unsafe { avx2(&mut c.state, &mut c.fallback, &mut z) };
            assert!(z.iter().zip(&y).all(|(p, q)| p.to_bits() == q.to_bits()));
        }
        assert!(x.iter().zip(&y).all(|(p, q)| p.to_bits() == q.to_bits()));
        assert_eq!(a.fallback.next_u64(), b.fallback.next_u64());
    }
}
