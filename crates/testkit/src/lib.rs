//! Test support shared by the workspace's tests and benchmarks (a dev-dependency only): where the
//! real measured data are ([`data_dir`], [`data_file`]) and a small deterministic generator for
//! test inputs ([`SplitMix64`]).
//!
//! Tests that need the real IMU logs and the reference tables read them from the directory named
//! by the environment variable `IMUDRIFT_DATA` (`.ci/run` sets it), read when the tests run, not
//! when they are compiled (so setting it rebuilds nothing). Their test files use their own
//! harness, [`run_data_tests`]: without the data each such test shows as ignored in the test
//! summary, with the reason; run anyway (e.g. `--include-ignored`) without the data, it fails with
//! this explanation instead of passing.

use std::path::PathBuf;
use std::process::ExitCode;

/// Why a data test is ignored: printed once by [`run_data_tests`] when the data are missing.
pub const NO_DATA_REASON: &str =
    "needs the real IMU logs and reference tables: set IMUDRIFT_DATA to their directory";

/// Whether `IMUDRIFT_DATA` names a directory (read now, at run time).
pub fn has_data() -> bool {
    std::env::var_os("IMUDRIFT_DATA").is_some_and(|d| std::path::Path::new(&d).is_dir())
}

/// The `main` of a test file whose tests read the real data (`harness = false` in its
/// `[[test]]` section): runs `tests` as `cargo test` runs `#[test]` functions (same arguments,
/// filters and summary; a panic fails the test), each marked ignored when [`has_data`] is false.
pub fn run_data_tests(tests: &[(&'static str, fn())]) -> ExitCode {
    let args = libtest_mimic::Arguments::from_args();
    let ignore = !has_data();
    if ignore && !args.list {
        eprintln!("note: {NO_DATA_REASON}; these tests are ignored");
    }
    let trials = tests
        .iter()
        .map(|&(name, test)| {
            libtest_mimic::Trial::test(name, move || {
                test();
                Ok(())
            })
            .with_ignored_flag(ignore)
        })
        .collect();
    libtest_mimic::run(&args, trials).exit_code()
}

/// The data directory named by `IMUDRIFT_DATA`.
///
/// # Panics
/// If the variable is unset or does not name a directory: a test that calls this needs the data.
pub fn data_dir() -> PathBuf {
    match std::env::var_os("IMUDRIFT_DATA").map(PathBuf::from) {
        Some(dir) if dir.is_dir() => dir,
        Some(dir) => panic!(
            "IMUDRIFT_DATA={} is set but is not a directory",
            dir.display()
        ),
        None => panic!(
            "this test needs the real IMU logs and reference tables: set IMUDRIFT_DATA to their directory"
        ),
    }
}

/// `data_dir()/relative`.
///
/// # Panics
/// As [`data_dir`], and if the file does not exist.
pub fn data_file(relative: &str) -> PathBuf {
    let path = data_dir().join(relative);
    assert!(path.exists(), "missing reference file {}", path.display());
    path
}

/// SplitMix64 (Steele, Lea & Flood 2014): a tiny deterministic generator for test inputs and
/// benchmark data. Not for results (those draw from `noise::ImuRng` streams).
///
/// ```
/// let mut g = testkit::SplitMix64::new(0);
/// // The reference C implementation (prng.di.unimi.it/splitmix64.c) seeded with 0.
/// assert_eq!(g.next_u64(), 0xE220_A839_7B1D_CDAF);
/// // The same seed, the same draws; normal draws of unit variance.
/// let draws: Vec<f64> = (0..10_000).map(|_| g.normal()).collect();
/// let mut again = testkit::SplitMix64::new(0);
/// again.next_u64();
/// assert_eq!(again.normal(), draws[0]);
/// let var = draws.iter().map(|x| x * x).sum::<f64>() / draws.len() as f64;
/// assert!((var - 1.0).abs() < 0.06); // sd of the estimate: sqrt(2 / 10 000) = 0.014
/// ```
#[derive(Clone, Debug)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// A generator whose first output mixes `seed + 0x9E3779B97F4A7C15`.
    pub fn new(seed: u64) -> SplitMix64 {
        SplitMix64 { state: seed }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) on the 2^-53 grid (the top 53 bits).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [-0.5, 0.5).
    pub fn centred(&mut self) -> f64 {
        self.uniform() - 0.5
    }

    /// A standard normal draw by Box-Muller (Box & Muller 1958) from two uniforms, the first
    /// kept above 1e-300 so its logarithm is finite.
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::SplitMix64;

    #[test]
    fn splitmix64_reference_outputs() {
        // The reference C implementation (prng.di.unimi.it/splitmix64.c) seeded with 0 starts
        // with these outputs.
        let mut g = SplitMix64::new(0);
        assert_eq!(g.next_u64(), 0xE220_A839_7B1D_CDAF);
        assert_eq!(g.next_u64(), 0x6E78_9E6A_A1B9_65F4);
        let mut u = SplitMix64::new(1);
        let x = u.uniform();
        assert!((0.0..1.0).contains(&x));
        assert_eq!(SplitMix64::new(1).centred(), x - 0.5);
    }
}
