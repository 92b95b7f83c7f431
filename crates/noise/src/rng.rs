//! The generator of every result: Xoshiro256++ (Blackman & Vigna 2021, "Scrambled linear
//! pseudorandom number generators", ACM TOMS 47(4), reference code xoshiro256plusplus.c), the
//! same generator as `rand_xoshiro` 0.6's `Xoshiro256PlusPlus` and seeded the same way, so every
//! seed gives the same outputs (tested below against that crate). Our own type because the wide
//! sampler (`crate::wide`) needs its four state words: the rejected draws' outcomes are chosen
//! word by word without a branch (`crate::ziggurat::finish_rejected_bits`), which the other
//! crate's private state does not allow.

use rand::{RngCore, SeedableRng};

/// Xoshiro256++ (see the module docs).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImuRng {
    s: [u64; 4],
}

impl ImuRng {
    /// The state words.
    #[inline(always)]
    pub(crate) fn words(&self) -> (u64, u64, u64, u64) {
        (self.s[0], self.s[1], self.s[2], self.s[3])
    }

    /// Set the state words (not all zero).
    #[inline(always)]
    pub(crate) fn set_words(&mut self, (s0, s1, s2, s3): (u64, u64, u64, u64)) {
        self.s[0] = s0;
        self.s[1] = s1;
        self.s[2] = s2;
        self.s[3] = s3;
    }

    /// [`Self::step`] of state words held as scalars: the output and the next state.
    #[inline(always)]
    pub(crate) fn step_words(
        (s0, s1, s2, s3): (u64, u64, u64, u64),
    ) -> (u64, (u64, u64, u64, u64)) {
        let out = s0.wrapping_add(s3).rotate_left(23).wrapping_add(s0);
        let t = s1 << 17;
        let s2 = s2 ^ s0;
        let s3 = s3 ^ s1;
        let s1 = s1 ^ s2;
        let s0 = s0 ^ s3;
        (out, (s0, s1, s2 ^ t, s3.rotate_left(45)))
    }

    /// The output of the state `s`, and `s` advanced (xoshiro256plusplus.c `next`).
    #[inline(always)]
    pub(crate) fn step(s: &mut [u64; 4]) -> u64 {
        let out = s[0].wrapping_add(s[3]).rotate_left(23).wrapping_add(s[0]);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        out
    }
}

impl RngCore for ImuRng {
    #[inline]
    fn next_u32(&mut self) -> u32 {
        (self.next_u64() >> 32) as u32
    }

    #[inline]
    fn next_u64(&mut self) -> u64 {
        ImuRng::step(&mut self.s)
    }

    /// Whole outputs little-endian, then the rest from one more output: a u64's first bytes
    /// for more than four, a u32's for one to four (rand_core 0.6 `fill_bytes_via_next`).
    fn fill_bytes(&mut self, dest: &mut [u8]) {
        let mut chunks = dest.chunks_exact_mut(8);
        for chunk in &mut chunks {
            chunk.copy_from_slice(&self.next_u64().to_le_bytes());
        }
        let rest = chunks.into_remainder();
        let n = rest.len();
        if n > 4 {
            rest.copy_from_slice(&self.next_u64().to_le_bytes()[..n]);
        } else if n > 0 {
            rest.copy_from_slice(&self.next_u32().to_le_bytes()[..n]);
        }
    }

    #[inline]
    fn try_fill_bytes(&mut self, dest: &mut [u8]) -> Result<(), rand::Error> {
        self.fill_bytes(dest);
        Ok(())
    }
}

impl SeedableRng for ImuRng {
    type Seed = [u8; 32];

    /// The state from the seed's four little-endian words; an all-zero seed, which Xoshiro
    /// cannot leave, is replaced by `seed_from_u64(0)` (as `rand_xoshiro`).
    fn from_seed(seed: [u8; 32]) -> ImuRng {
        if seed.iter().all(|&b| b == 0) {
            return ImuRng::seed_from_u64(0);
        }
        ImuRng {
            s: std::array::from_fn(|w| {
                u64::from_le_bytes(seed[8 * w..8 * w + 8].try_into().expect("8 bytes"))
            }),
        }
    }

    /// The seed from SplitMix64's outputs (as `rand_xoshiro`).
    fn seed_from_u64(seed: u64) -> ImuRng {
        let mut bytes = [0u8; 32];
        rand_xoshiro::SplitMix64::seed_from_u64(seed).fill_bytes(&mut bytes);
        ImuRng::from_seed(bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_xoshiro::Xoshiro256PlusPlus;

    /// The reference vector of rand_xoshiro's own test (from the C reference code).
    #[test]
    fn reference_outputs() {
        let mut seed = [0u8; 32];
        for (w, v) in [1u8, 2, 3, 4].iter().enumerate() {
            seed[8 * w] = *v;
        }
        let mut rng = ImuRng::from_seed(seed);
        let expected = [
            41943041u64,
            58720359,
            3588806011781223,
            3591011842654386,
            9228616714210784205,
            9973669472204895162,
            14011001112246962877,
            12406186145184390807,
            15849039046786891736,
            10450023813501588000,
        ];
        for e in expected {
            assert_eq!(rng.next_u64(), e);
        }
    }

    /// Every way of seeding and drawing gives rand_xoshiro's values.
    #[test]
    fn same_outputs_as_rand_xoshiro() {
        for seed in [0u64, 1, 2, 42, u64::MAX, 0x9E37_79B9_7F4A_7C15] {
            let (mut a, mut b) = (
                ImuRng::seed_from_u64(seed),
                Xoshiro256PlusPlus::seed_from_u64(seed),
            );
            for k in 0..1000 {
                match k % 3 {
                    0 => assert_eq!(a.next_u64(), b.next_u64()),
                    1 => assert_eq!(a.next_u32(), b.next_u32()),
                    _ => {
                        // Lengths with every remainder (none, 1-4 and 5-7 bytes).
                        let n = k % 19;
                        let (mut x, mut y) = (vec![0u8; n], vec![0u8; n]);
                        a.fill_bytes(&mut x);
                        b.fill_bytes(&mut y);
                        assert_eq!(x, y);
                    }
                }
            }
        }
        for bytes in [[0u8; 32], [7u8; 32], std::array::from_fn(|i| i as u8)] {
            let (mut a, mut b) = (
                ImuRng::from_seed(bytes),
                Xoshiro256PlusPlus::from_seed(bytes),
            );
            for _ in 0..100 {
                assert_eq!(a.next_u64(), b.next_u64());
            }
        }
    }
}
