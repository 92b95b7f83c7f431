//! Pieces of command-line handling that several commands share.

use anyhow::{bail, Result};

/// A time given on the command line, s: a bare number is seconds, otherwise a value with its unit
/// (`"60"`, `"90 s"`, `"5 min"`, `"12 h"`); finite and > 0. The value parser of every duration
/// flag (`--duration`, `--horizons`, `--times`, ...): clap names the flag in the error.
pub fn duration_s(text: &str) -> std::result::Result<f64, String> {
    noise::units::duration_s(text)
}

/// As [`duration_s`], zero allowed (a lower bound that may be absent, such as `--tau-min`).
pub fn duration_or_zero_s(text: &str) -> std::result::Result<f64, String> {
    noise::units::duration_or_zero_s(text)
}

/// A confidence level: `1sigma` (erf(1/sqrt 2) = 0.6827, SP 1065 §5.3), a fraction (`0.95`) or
/// a percentage (`95%`); strictly between 0 and 1.
pub fn confidence(text: &str) -> std::result::Result<f64, String> {
    // clap puts the flag before the message: the request's own words follow it.
    request::allan::parse_confidence(text).map_err(|e| {
        let m = e.render(&|_| "");
        m.trim_start_matches([' ', ':']).to_string()
    })
}

/// Check the environment variables imudrift reads, before any work: a value that is not what
/// the variable takes is an error naming it (it was ignored silently, or panicked).
pub fn check_environment() -> Result<()> {
    let var = |name: &str| std::env::var_os(name).map(|v| v.to_string_lossy().into_owned());
    if let Some(v) = var("IMUDRIFT_PROGRESS_INTERVAL_S") {
        let max = crate::progress::MAX_INTERVAL_S;
        if !v
            .trim()
            .parse::<f64>()
            .is_ok_and(|s| (0.0..=max).contains(&s))
        {
            bail!(
                "environment variable IMUDRIFT_PROGRESS_INTERVAL_S={}: expected seconds from 0 to {max} between progress lines",
                logio::quote_prefix(&v)
            );
        }
    }
    if let Some(v) = var("IMUDRIFT_MEMORY_LIMIT") {
        if !v.trim().parse::<u64>().is_ok_and(|b| b > 0) {
            bail!(
                "environment variable IMUDRIFT_MEMORY_LIMIT={}: expected a whole number of bytes > 0, e.g. 8000000000 for 8 GB",
                logio::quote_prefix(&v)
            );
        }
    }
    Ok(())
}

/// The command line's name of a request's setting (its flag), for the request layer's messages.
pub fn flag(s: request::Setting) -> &'static str {
    use request::Setting;
    match s {
        Setting::Runs => "--runs",
        Setting::Seed => "--seed",
        Setting::Duration => "--duration",
        Setting::Rate => "--rate",
        Setting::Threads => "--threads",
        Setting::Only => "--only",
        Setting::Without => "--without",
        Setting::Shard => "--shard i/k",
        Setting::Merge => "`imudrift merge`",
        Setting::Output => "-o",
        Setting::Columns => "--col",
        Setting::Channels => "--channels",
        Setting::Seeds => "--seeds",
        Setting::Rounds => "--rounds",
        Setting::MinDeltaBic => "--min-delta-bic",
        Setting::TauMin => "--tau-min",
        Setting::Horizons => "--horizons",
        Setting::Latitude => "--latitude",
        Setting::Replicates => "--replicates",
        Setting::Confidence => "--confidence",
        Setting::Data => "the log",
        Setting::Taus => "--grid",
    }
}

/// A request error told with the command line's flags.
pub fn request_error(e: request::RequestError) -> anyhow::Error {
    anyhow::anyhow!(e.render(&flag))
}

/// A sample rate given on the command line (`--rate`), Hz, finite and > 0.
pub fn check_rate_hz(rate_hz: f64) -> Result<f64> {
    request::simulate::check_rate(rate_hz).map_err(request_error)
}

/// The one rayon pool of every command: `--threads N` workers (absent or 0: one per core;
/// `request::pool`).
pub fn pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    request::pool::pool(threads).map_err(request_error)
}

/// A term filter as the options that make it (for reports), e.g. `--without gyro.white_noise`:
/// each list as `sensor.effect` items in order.
pub fn describe_filter(filter: &noise::TermFilter) -> String {
    let list = |terms: &[(noise::Sensor, noise::Effect)]| {
        terms
            .iter()
            .map(|(s, e)| format!("{s}.{e}"))
            .collect::<Vec<_>>()
            .join(",")
    };
    let mut parts = Vec::new();
    if let Some(only) = filter.only_terms() {
        parts.push(format!("--only {}", list(&only)));
    }
    let without = filter.without_terms();
    if !without.is_empty() {
        parts.push(format!("--without {}", list(&without)));
    }
    parts.join(" ")
}

/// The value parser of a flag whose values are the names of a library's enum (`all` every
/// value, `name` its spelling): `--help` lists them and clap refuses any other.
pub fn named<T: Copy + Send + Sync + 'static, const N: usize>(
    all: [T; N],
    name: fn(T) -> &'static str,
) -> impl clap::builder::TypedValueParser<Value = T> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(all.map(name)).map(move |text| {
        *all.iter()
            .find(|&&v| name(v) == text)
            .expect("clap accepts only the possible values")
    })
}

/// `--edf`: how the equivalent degrees of freedom of each Allan point are found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum EdfArg {
    Greenhall,
    Simple,
    None,
}

impl From<EdfArg> for allan::EdfMethod {
    fn from(edf: EdfArg) -> allan::EdfMethod {
        match edf {
            EdfArg::Greenhall => allan::EdfMethod::Greenhall,
            EdfArg::Simple => allan::EdfMethod::Simple,
            EdfArg::None => allan::EdfMethod::None,
        }
    }
}

/// `--grid`: the tau grid, and its text as given (written into the JSON as typed).
#[derive(Clone, Debug, PartialEq)]
pub struct GridArg {
    pub text: String,
    pub grid: allan::TauGrid,
}

/// The value parser of `--grid`.
pub fn grid(text: &str) -> std::result::Result<GridArg, String> {
    let grid = allan::TauGrid::parse(text)
        .ok_or("expected octave, decade, all, N/decade or a comma list of m values")?;
    Ok(GridArg {
        text: text.to_string(),
        grid,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_filter_is_described_as_its_options() {
        let item = |s: &str| noise::TermSelector::parse(s).unwrap();
        assert_eq!(describe_filter(&noise::TermFilter::all()), "");
        let f = noise::TermFilter::new(Some(&[item("gyro.scale_factor")]), &[item("white_noise")]);
        assert_eq!(
            describe_filter(&f),
            "--only gyro.scale_factor --without gyro.white_noise,accel.white_noise"
        );
    }
}
