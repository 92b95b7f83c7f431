//! Pieces of command-line handling that several commands share.

use anyhow::{bail, Result};
use noise::units::{parse_quantity, Quantity};

/// A time given on the command line: a bare number is seconds, otherwise a value with its unit
/// (`"60"`, `"90 s"`, `"5 min"`, `"12 h"`). `flag` names the option in the error.
pub fn parse_duration_s(flag: &str, text: &str) -> Result<f64> {
    let duration_s = match text.trim().parse::<f64>() {
        Ok(v) => v,
        Err(_) => parse_quantity(text, Quantity::Time).map_err(|e| {
            anyhow::anyhow!(
                "{flag}: expected seconds or a time such as \"12 h\" ({e}), found \"{text}\""
            )
        })?,
    };
    if !(duration_s.is_finite() && duration_s > 0.0) {
        bail!("{flag}: expected a time > 0, found \"{text}\"");
    }
    Ok(duration_s)
}

/// A sample rate given on the command line, Hz, finite and > 0.
pub fn check_rate_hz(flag: &str, rate_hz: f64) -> Result<f64> {
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        bail!("{flag}: expected a sample rate in Hz > 0, found {rate_hz}");
    }
    Ok(rate_hz)
}

/// Most worker threads a command starts: four per core, and at least 64.
fn max_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get()) * 4
}

/// The one rayon pool of every command: `--threads N` workers (absent or 0: one per core).
/// Results never depend on N; N beyond [`max_threads`] is refused rather than started.
pub fn pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    let n = threads.unwrap_or(0);
    let max = max_threads().max(64);
    if n > max {
        bail!(
            "--threads {n}: expected at most {max} (this machine has {} cores; 0 or no --threads uses them all)",
            std::thread::available_parallelism().map_or(1, |n| n.get())
        );
    }
    use anyhow::Context as _;
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .context("cannot start the worker threads")
}

/// The term switches of `--only a,b` and `--without c` (comma lists in every command).
pub fn term_filter(only: Option<&[String]>, without: &[String]) -> Result<noise::TermFilter> {
    Ok(noise::TermFilter::parse(
        only.map(|v| v.join(",")).as_deref(),
        (!without.is_empty()).then(|| without.join(",")).as_deref(),
    )?)
}
