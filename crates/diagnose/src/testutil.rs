//! Helpers shared by the unit tests.

/// `n` standard normals from a seeded Xoshiro256++ (reproducible test noise).
pub(crate) fn normals(n: usize, seed: u64) -> Vec<f64> {
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
    (0..n).map(|_| StandardNormal.sample(&mut rng)).collect()
}
