//! `imudrift spec SENSOR.toml...`: spec-sheet values beside the values read back from a simulated
//! 12 h, 100 Hz static log (Woodman's Allan method), and drift at 1 min, 10 min and 1 h (heading and
//! horizontal position, law and simulation) side by side for all sensors given.

use crate::cmd_simulate::{check_memory, execute, pool};
use crate::output::{ensure_dir, write_atomic, write_string};
use anyhow::{Context, Result};
use montecarlo::spec::{
    drift_experiment, drift_rows, gyro_readback, SensorSpec, READBACK_CONFIDENCE,
    READBACK_DURATION_S, READBACK_RATE_HZ,
};
use noise::{SensorModel, TermFilter};
use serde::Serialize;
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Sensor TOMLs (configs/sensors/*.toml)
    #[arg(required = true)]
    pub sensors: Vec<PathBuf>,
    /// Monte Carlo runs for the drift table
    #[arg(long, default_value_t = 200)]
    pub runs: u64,
    /// Master seed (readback log and drift runs)
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (default: all cores); results are identical for any value
    #[arg(long)]
    pub threads: Option<usize>,
    /// Drift times, s
    #[arg(long, value_delimiter = ',', default_values_t = [60.0, 600.0, 3600.0])]
    pub times: Vec<f64>,
    /// Sample rate of the drift runs, Hz
    #[arg(long, default_value_t = 100.0)]
    pub rate: f64,
    /// Length of the simulated readback log, s (Woodman: 12 h)
    #[arg(long, default_value_t = READBACK_DURATION_S)]
    pub readback_duration: f64,
    /// Keep only these error terms
    #[arg(long, value_delimiter = ',')]
    pub only: Option<Vec<String>>,
    /// Switch these error terms off
    #[arg(long, value_delimiter = ',')]
    pub without: Vec<String>,
    /// Print one JSON document on stdout
    #[arg(long)]
    pub json: bool,
    /// Write spec.json, spec.csv and drift.csv into DIR
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

#[derive(Serialize)]
struct SpecDoc {
    seed: u64,
    readback_duration_s: f64,
    readback_rate_hz: f64,
    readback_confidence: f64,
    drift_rate_hz: f64,
    sensors: Vec<SensorSpec>,
}

pub fn run(args: Args) -> Result<()> {
    if args.times.is_empty() || args.times.iter().any(|t| !(t.is_finite() && *t > 0.0)) {
        anyhow::bail!("--times: expected positive times in seconds, e.g. 60,600,3600");
    }
    if !(args.readback_duration.is_finite() && args.readback_duration * READBACK_RATE_HZ >= 1000.0)
    {
        anyhow::bail!("--readback-duration: expected at least 10 s");
    }
    let filter = TermFilter::parse(
        args.only.as_ref().map(|v| v.join(",")).as_deref(),
        (!args.without.is_empty())
            .then(|| args.without.join(","))
            .as_deref(),
    )?;
    let pool = pool(args.threads)?;
    let mut sensors = Vec::new();
    for path in &args.sensors {
        let model = SensorModel::load(path)
            .map_err(|e| anyhow::anyhow!("{e}"))?
            .filtered(&filter);
        let exp = drift_experiment(&model, &args.times, args.rate, args.runs, args.seed)
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
        check_memory(&exp, exp.runs)?;
        eprintln!(
            "{}: reading back a {:.0} h, {} Hz static log ...",
            model.name,
            args.readback_duration / 3600.0,
            READBACK_RATE_HZ
        );
        let gyro = pool
            .install(|| gyro_readback(&model, args.seed, args.readback_duration, READBACK_RATE_HZ));
        let batch = pool.install(|| execute(&exp, 0..exp.runs, &model.name));
        let report = exp.report(&batch.matrix, &batch.failures);
        for f in &batch.failures {
            eprintln!(
                "warning: {}: drift run {} failed: {}",
                model.name, f.run, f.message
            );
        }
        sensors.push(SensorSpec {
            name: model.name.clone(),
            gyro,
            drift: drift_rows(&report),
            drift_runs: report.runs_ok,
        });
    }
    let doc = SpecDoc {
        seed: args.seed,
        readback_duration_s: args.readback_duration,
        readback_rate_hz: READBACK_RATE_HZ,
        readback_confidence: READBACK_CONFIDENCE,
        drift_rate_hz: args.rate,
        sensors,
    };
    eprint!("{}", table(&doc));
    let text = serde_json::to_string_pretty(&doc)? + "\n";
    if args.json {
        let mut out = std::io::stdout().lock();
        out.write_all(text.as_bytes())?;
        out.flush()?;
    }
    if let Some(dir) = &args.out {
        ensure_dir(dir)?;
        write_string(&dir.join("spec.json"), &text)?;
        write_atomic(&dir.join("spec.csv"), |w| {
            writeln!(w, "sensor,axis,arw_spec,arw_sim,arw_sim_lo,arw_sim_hi,bi_spec,bi_sim,bi_sim_lo,bi_sim_hi")?;
            for s in &doc.sensors {
                let g = &s.gyro;
                for a in 0..3 {
                    let f = |x: Option<f64>| x.map_or(String::new(), |v| format!("{v:.6e}"));
                    writeln!(
                        w,
                        "\"{}\",{},{},{},{},{},{},{},{},{}",
                        s.name,
                        ["x", "y", "z"][a],
                        f(g.arw_spec[a]),
                        f(g.arw_sim[a]),
                        f(g.arw_sim_lo[a]),
                        f(g.arw_sim_hi[a]),
                        f(g.bi_spec[a]),
                        f(g.bi_sim[a]),
                        f(g.bi_sim_lo[a]),
                        f(g.bi_sim_hi[a])
                    )?;
                }
            }
            Ok(())
        })
        .context("spec.csv")?;
        write_atomic(&dir.join("drift.csv"), |w| {
            writeln!(w, "sensor,t_s,heading_rms_sim_rad,heading_rms_law_rad,horizontal_mean_sim_m,horizontal_mean_law_m,horizontal_rms_sim_m,horizontal_rms_law_m,horizontal_p95_sim_m")?;
            for s in &doc.sensors {
                for d in &s.drift {
                    let f = |x: Option<f64>| x.map_or(String::new(), |v| format!("{v:.6e}"));
                    writeln!(
                        w,
                        "\"{}\",{},{:.6e},{},{:.6e},{},{:.6e},{},{:.6e}",
                        s.name,
                        d.t_s,
                        d.heading_rms_sim_rad,
                        f(d.heading_rms_law_rad),
                        d.horizontal_mean_sim_m,
                        f(d.horizontal_mean_law_m),
                        d.horizontal_rms_sim_m,
                        f(d.horizontal_rms_law_m),
                        d.horizontal_p95_sim_m
                    )?;
                }
            }
            Ok(())
        })?;
        eprintln!("wrote {}/spec.json, spec.csv, drift.csv", dir.display());
    }
    Ok(())
}

fn table(doc: &SpecDoc) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let deg = 180.0 / std::f64::consts::PI;
    let f =
        |x: Option<f64>, scale: f64| x.map_or("n/a".to_string(), |v| format!("{:.4}", v * scale));
    let _ = writeln!(
        s,
        "\nspec vs readback (simulated {:.0} h, {} Hz static log; Woodman's method; {:.0} % intervals)",
        doc.readback_duration_s / 3600.0,
        doc.readback_rate_hz,
        100.0 * doc.readback_confidence
    );
    let _ = writeln!(
        s,
        "{:<22} {:>4} {:>11} {:>11} {:>21} {:>11} {:>11} {:>21}",
        "sensor", "axis", "ARW spec", "ARW sim", "interval", "BI spec", "BI sim", "interval"
    );
    let _ = writeln!(
        s,
        "{:<22} {:>4} {:>11} {:>11} {:>21} {:>11} {:>11} {:>21}",
        "", "", "deg/sqrt(h)", "deg/sqrt(h)", "", "deg/h", "deg/h", ""
    );
    for sen in &doc.sensors {
        let g = &sen.gyro;
        for a in 0..3 {
            let _ = writeln!(
                s,
                "{:<22} {:>4} {:>11} {:>11} {:>21} {:>11} {:>11} {:>21}",
                sen.name,
                ["x", "y", "z"][a],
                // deg/sqrt(h) = 60 deg/sqrt(s) (theory.md §2 unit conversions).
                f(g.arw_spec[a], deg * 60.0),
                f(g.arw_sim[a], deg * 60.0),
                format!(
                    "[{}, {}]",
                    f(g.arw_sim_lo[a], deg * 60.0),
                    f(g.arw_sim_hi[a], deg * 60.0)
                ),
                f(g.bi_spec[a], deg * 3600.0),
                f(g.bi_sim[a], deg * 3600.0),
                format!(
                    "[{}, {}]",
                    f(g.bi_sim_lo[a], deg * 3600.0),
                    f(g.bi_sim_hi[a], deg * 3600.0)
                ),
            );
        }
        for n in &g.notes {
            let _ = writeln!(s, "  note: {}: {n}", sen.name);
        }
    }
    let _ = writeln!(s, "\ndrift, static and level ({} Hz Monte Carlo): heading rms (deg) and horizontal position (m), simulation / law", doc.drift_rate_hz);
    let _ = writeln!(
        s,
        "{:<22} {:>8} {:>10} {:>10} {:>12} {:>12} {:>12} {:>12}",
        "sensor",
        "t_s",
        "hdg sim",
        "hdg law",
        "hor mean sim",
        "hor mean law",
        "hor rms sim",
        "hor rms law"
    );
    for sen in &doc.sensors {
        for d in &sen.drift {
            let g = |x: Option<f64>| x.map_or("n/a".to_string(), |v| format!("{v:.4e}"));
            let _ = writeln!(
                s,
                "{:<22} {:>8} {:>10.4} {:>10} {:>12.4e} {:>12} {:>12.4e} {:>12}",
                sen.name,
                d.t_s,
                d.heading_rms_sim_rad * deg,
                d.heading_rms_law_rad
                    .map_or("n/a".to_string(), |v| format!("{:.4}", v * deg)),
                d.horizontal_mean_sim_m,
                g(d.horizontal_mean_law_m),
                d.horizontal_rms_sim_m,
                g(d.horizontal_rms_law_m),
            );
            if let Some(n) = &d.law_note {
                let _ = writeln!(s, "  {:<20} t = {} s: {n}", "", d.t_s);
            }
        }
    }
    s
}
