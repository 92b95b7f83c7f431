//! `imudrift plan SENSOR.toml`: how long a static log must be to read each noise term of each
//! axis off its Allan deviation to a stated relative uncertainty, and what a given length
//! resolves (the method and its sources: `allan::plan`).

use crate::cli::check_rate_hz;
use crate::fmt;
use anyhow::{bail, Context, Result};
use diagnose::log_plan::{PlanDoc, MAX_DURATION_S, MAX_RATE_HZ, MIN_RATE_HZ};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Sensor TOML (configs/sensors/*.toml)
    pub sensor: PathBuf,
    /// Target relative standard uncertainty of each reading: a fraction (0.1) or a percentage (10%)
    #[arg(long, default_value = "10%")]
    pub uncertainty: String,
    /// Also say how well a log of this length reads each term: seconds or a time ("2 h")
    #[arg(long, value_parser = crate::cli::duration_s)]
    pub duration: Option<f64>,
    /// Sample rate of the log, Hz
    #[arg(long, default_value_t = 100.0)]
    pub rate: f64,
    /// Print one JSON document on stdout (human text stays on stderr)
    #[arg(long)]
    pub json: bool,
}

fn parse_fraction(text: &str) -> Result<f64> {
    let t = text.trim();
    let v = match t.strip_suffix('%') {
        Some(p) => p.trim().parse::<f64>().map(|v| v / 100.0),
        None => t.parse::<f64>(),
    }
    .ok()
    .filter(|v| v.is_finite() && *v > 0.0 && *v < 1.0);
    v.with_context(|| {
        format!("--uncertainty: expected a fraction in (0, 1) or a percentage such as 10%, found \"{text}\"")
    })
}

pub fn run(args: Args) -> Result<()> {
    let model = crate::files::sensor_model(&args.sensor)?;
    let target = parse_fraction(&args.uncertainty)?;
    let rate_hz = check_rate_hz(args.rate)?;
    if !(MIN_RATE_HZ..=MAX_RATE_HZ).contains(&rate_hz) {
        bail!("--rate: expected {MIN_RATE_HZ} to {MAX_RATE_HZ} Hz, found {rate_hz}");
    }
    let duration_s = args.duration;
    if let Some(d) = duration_s {
        if d > MAX_DURATION_S || d * rate_hz < 3.0 {
            bail!("--duration: expected at least 3 samples and at most {MAX_DURATION_S:e} s (about 300 years), found {d:e} s");
        }
    }
    let Some(doc) = diagnose::log_plan::plan(&model, rate_hz, target, duration_s) else {
        bail!(
            "{}: the model has no white noise, bias instability or rate random walk to plan for",
            args.sensor.display()
        );
    };
    let json = serde_json::to_string_pretty(&doc)? + "\n";
    crate::output::answer(&text(&doc), args.json.then_some(json.as_str()))?;
    Ok(())
}

/// A duration as a person plans it: "41 s", "12.5 min", "3.2 h", "2.1 days".
fn human_duration(s: f64) -> String {
    if s < 120.0 {
        format!("{} s", fmt::sig(s, 3))
    } else if s < 2.0 * 3600.0 {
        format!("{} min", fmt::sig(s / 60.0, 3))
    } else if s < 48.0 * 3600.0 {
        format!("{} h", fmt::sig(s / 3600.0, 3))
    } else {
        format!("{} days", fmt::sig(s / 86400.0, 3))
    }
}

fn text(doc: &PlanDoc) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{}: static log at {}; each term read where it dominates the Allan deviation, to {} % (1 sigma)",
        doc.sensor,
        fmt::rate(doc.rate_hz),
        fmt::sig(100.0 * doc.target_uncertainty, 3)
    );
    let _ = writeln!(
        s,
        "{:<6} {:>4} {:<17} {:>11} {:>7} {:>14} {:>16}",
        "sensor",
        "axis",
        "term",
        "read at",
        "share",
        "needs a log of",
        doc.duration_s
            .map_or(String::new(), |d| format!("{} gives", human_duration(d)))
    );
    for a in &doc.axes {
        for t in &a.terms {
            let _ = writeln!(
                s,
                "{:<6} {:>4} {:<17} {:>11} {:>7} {:>14} {:>16}",
                a.sensor,
                a.axis,
                t.term.name(),
                t.tau_s
                    .map_or("-".into(), |v| format!("{} s", fmt::sig(v, 3))),
                t.share
                    .map_or("-".into(), |v| format!("{:.0} %", 100.0 * v)),
                t.required_duration_s
                    .map_or("cannot".into(), human_duration),
                match (doc.duration_s, t.uncertainty_at_duration) {
                    (None, _) => String::new(),
                    (Some(_), Some(u)) => format!("{} %", fmt::sig(100.0 * u, 2)),
                    (Some(_), None) => "not resolved".into(),
                }
            );
            if let Some(n) = &t.note {
                let _ = writeln!(s, "  note: {} {} {}: {n}", a.sensor, a.axis, t.term.name());
            }
        }
    }
    if let Some(d) = doc.required_duration_s {
        let _ = writeln!(
            s,
            "\na static log of {} ({} samples at {}) reads every readable term above to {} %",
            human_duration(d),
            (d * doc.rate_hz).ceil(),
            fmt::rate(doc.rate_hz),
            fmt::sig(100.0 * doc.target_uncertainty, 3)
        );
    }
    let _ = writeln!(
        s,
        "uncertainty = 1/sqrt(2 nu), nu the equivalent degrees of freedom of the overlapping Allan variance at that tau (Greenhall & Riley 2003; NIST SP 1065 5.3); share = the term's part of the model's Allan variance there (the rest biases the reading)"
    );
    s
}
