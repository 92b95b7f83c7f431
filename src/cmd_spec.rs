//! `imudrift spec SENSOR.toml...`: spec-sheet comparison of several sensors side by side: drift
//! at chosen times (heading and horizontal position, law and simulation), requirements answered
//! directly (`--require "pos_horizontal_m < 10 m @ 300 s"`: pass or fail with the margin), and on
//! request (`--readback`) the spec ARW and bias instability beside the values read back from a
//! simulated 12 h, 100 Hz static log (Woodman's Allan method).

use crate::cli::pool;
use crate::experiment_run::execute;
use crate::fmt;
use crate::output::{write_atomic, write_string};
use anyhow::{Context, Result};
use montecarlo::nav_quantity::NavQuantity;
use montecarlo::requirement::Verdict;
use montecarlo::spec::READBACK_RATE_HZ;
use montecarlo::spec_job::{
    self, SensorOut, SpecDoc, SpecError, SpecRequest, SpecSetting, SpecSettings,
};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Sensor TOMLs (configs/sensors/*.toml)
    #[arg(required = true)]
    pub sensors: Vec<PathBuf>,
    /// A requirement to answer per sensor, e.g. "pos_horizontal_m < 10 m @ 300 s" or
    /// "p50 heading_rad < 2 deg @ 10 min" (statistic of |error|: p50, p68, p95 (default), p99, rms,
    /// mean); repeat for several
    #[arg(long, value_name = "REQ")]
    pub require: Vec<String>,
    /// Also read the ARW and bias instability back from a simulated static log (12 h at 100 Hz
    /// unless --readback-duration says otherwise) and set them beside the spec values
    #[arg(long)]
    pub readback: bool,
    /// Monte Carlo runs per sensor for the drift table [default: 200; 500 with --require]
    #[arg(long)]
    pub runs: Option<u64>,
    /// Master seed (readback log and drift runs)
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (default: all cores); results are identical for any value
    #[arg(long)]
    pub threads: Option<usize>,
    /// Drift times (a bare number is seconds, or 10min, 1h) [default: 60,600,3600, or only the requirements' times with --require]
    #[arg(long, value_delimiter = ',', value_parser = crate::cli::duration_s)]
    pub times: Option<Vec<f64>>,
    /// Sample rate of the drift runs, Hz
    #[arg(long, default_value_t = 100.0)]
    pub rate: f64,
    /// Length of the simulated readback log (a bare number is seconds; Woodman: 12 h); implies --readback
    #[arg(long, value_parser = crate::cli::duration_s)]
    pub readback_duration: Option<f64>,
    /// Keep only these error terms
    #[arg(long, value_delimiter = ',', value_parser = noise::TermSelector::parse)]
    pub only: Option<Vec<noise::TermSelector>>,
    /// Switch these error terms off
    #[arg(long, value_delimiter = ',', value_parser = noise::TermSelector::parse)]
    pub without: Vec<noise::TermSelector>,
    /// Print one JSON document on stdout
    #[arg(long)]
    pub json: bool,
    /// Write spec.json, spec.csv and drift.csv into DIR
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

/// The flag that sets each setting of the comparison.
fn flag(setting: SpecSetting) -> &'static str {
    match setting {
        SpecSetting::Require => "--require",
        SpecSetting::Times => "--times",
        SpecSetting::Rate => "--rate",
        SpecSetting::Runs => "--runs",
        SpecSetting::ReadbackDuration => "--readback-duration",
    }
}

fn with_flags(e: SpecError) -> anyhow::Error {
    anyhow::anyhow!(e.render(&flag))
}

pub fn run(args: Args) -> Result<()> {
    crate::output::note_inputs(&args.sensors);
    let _out_lock = args
        .out
        .as_deref()
        .map(crate::output::prepare_dir)
        .transpose()?;
    let settings = SpecSettings::new(&SpecRequest {
        require: args.require.clone(),
        times_s: args.times.clone(),
        rate_hz: args.rate,
        runs: args.runs,
        readback: args.readback,
        readback_duration_s: args.readback_duration,
        available_memory_bytes: logio::available_memory_bytes(),
    })
    .map_err(with_flags)?;
    let filter = noise::TermFilter::new(args.only.as_deref(), &args.without);
    let pool = pool(args.threads)?;
    let mut sensors = Vec::new();
    for path in &args.sensors {
        sensors.push(compare_sensor(path, &settings, &filter, &pool, args.seed)?);
    }
    let doc = SpecDoc::new(args.seed, &settings, sensors);
    let text = doc.to_json();
    crate::output::answer(&table(&doc), args.json.then_some(text.as_str()))?;
    if let Some(dir) = &args.out {
        let set = crate::output::begin_out_set(dir)?;
        write_string(&dir.join("spec.json"), &text)?;
        write_spec_csv(dir, &doc)?;
        write_drift_csv(dir, &doc)?;
        let sensors: Vec<crate::spec_plot::SensorDrift> = doc
            .sensors
            .iter()
            .map(|s| crate::spec_plot::SensorDrift {
                name: &s.spec.name,
                drift: &s.spec.drift,
                requirements: &s.requirements,
            })
            .collect();
        let plots = crate::spec_plot::plots(&sensors);
        for (name, svg) in &plots {
            write_string(&dir.join(name), svg)?;
        }
        set.commit()?;
        tell!(
            "wrote {}/spec.json, spec.csv, drift.csv, {}",
            dir.display(),
            plots
                .iter()
                .map(|p| p.0.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    Ok(())
}

/// One sensor (`montecarlo::spec_job`): its spec values (or read back from a simulated log),
/// drift runs with progress, requirements.
fn compare_sensor(
    path: &std::path::Path,
    settings: &SpecSettings,
    filter: &noise::TermFilter,
    pool: &rayon::ThreadPool,
    seed: u64,
) -> Result<SensorOut> {
    let name = path.display().to_string();
    let model = crate::files::sensor_model(path)?.filtered(filter);
    let exp = spec_job::experiment(&model, settings, seed, &name).map_err(with_flags)?;
    crate::experiment_run::check_size(&exp, exp.runs)?;
    if let Some(d) = settings.readback_duration_s() {
        tell!(
            "{}: reading back a {}, {} static log ...",
            model.name,
            fmt::time(d),
            fmt::rate(READBACK_RATE_HZ)
        );
    }
    let run = |e: &montecarlo::experiment::Experiment, runs: std::ops::Range<u64>, label: &str| {
        Some(execute(e, runs, label))
    };
    let (out, failures) = pool
        .install(|| spec_job::compare(&model, &exp, settings, seed, &name, &run))
        .map_err(with_flags)?
        .context("the drift runs were stopped")?;
    for f in &failures {
        tell!(
            "warning: {}: drift run {} failed: {}",
            model.name,
            f.run,
            f.message
        );
    }
    Ok(out)
}

/// spec.csv: the gyro spec values against the simulated readback, per axis.
fn write_spec_csv(dir: &std::path::Path, doc: &SpecDoc) -> Result<()> {
    write_atomic(&dir.join("spec.csv"), |w| {
        writeln!(
            w,
            "sensor,axis,arw_spec,arw_sim,arw_sim_lo,arw_sim_hi,bi_spec,bi_sim,bi_sim_lo,bi_sim_hi"
        )?;
        for s in &doc.sensors {
            let (s, g) = (&s.spec, &s.spec.gyro);
            for a in 0..3 {
                let f = |x: Option<f64>| x.map_or(String::new(), |v| format!("{v:.6e}"));
                writeln!(
                    w,
                    "{},{},{},{},{},{},{},{},{},{}",
                    crate::fmt::csv_text(&s.name),
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
    .context("spec.csv")
}

/// drift.csv: heading and horizontal drift, simulated and by the laws, per sensor and time.
fn write_drift_csv(dir: &std::path::Path, doc: &SpecDoc) -> Result<()> {
    write_atomic(&dir.join("drift.csv"), |w| {
        writeln!(w, "sensor,t_s,heading_rms_sim_rad,heading_rms_law_rad,horizontal_mean_sim_m,horizontal_mean_law_m,horizontal_rms_sim_m,horizontal_rms_law_m,horizontal_p95_sim_m")?;
        for s in &doc.sensors {
            let s = &s.spec;
            for d in &s.drift {
                let f = |x: Option<f64>| x.map_or(String::new(), |v| format!("{v:.6e}"));
                writeln!(
                    w,
                    "{},{},{:.6e},{},{:.6e},{},{:.6e},{},{:.6e}",
                    crate::fmt::csv_text(&s.name),
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
    })
}

/// The text tables: the spec values (or spec vs readback), the drift, and each requirement.
fn table(doc: &SpecDoc) -> String {
    let mut s = String::new();
    spec_table(&mut s, doc);
    drift_table(&mut s, doc);
    requirement_tables(&mut s, doc);
    s
}

/// The gyro spec values per sensor and axis; with a readback, beside the values read back.
fn spec_table(s: &mut String, doc: &SpecDoc) {
    use std::fmt::Write as _;
    let opt = |x: Option<f64>, f: fn(f64) -> String| x.map_or("n/a".to_string(), f);
    if let Some(d) = doc.readback_duration_s {
        let _ = writeln!(
            s,
            "\nspec vs readback (simulated {}, {} static log; Woodman's method; {:.0} % intervals)",
            fmt::time(d),
            fmt::rate(doc.readback_rate_hz),
            100.0 * doc.readback_confidence
        );
    } else {
        let _ = writeln!(
            s,
            "\nspec values (--readback reads them back from a simulated 12 h static log)"
        );
        let _ = writeln!(
            s,
            "{:<22} {:>4} {:>18} {:>12}",
            "sensor", "axis", "ARW", "BI"
        );
        for sen in &doc.sensors {
            for a in 0..3 {
                let g = &sen.spec.gyro;
                let _ = writeln!(
                    s,
                    "{:<22} {:>4} {:>18} {:>12}",
                    sen.spec.name,
                    ["x", "y", "z"][a],
                    opt(g.arw_spec[a], fmt::arw),
                    opt(g.bi_spec[a], fmt::gyro_bias),
                );
            }
        }
    }
    for sen in doc
        .sensors
        .iter()
        .filter(|_| doc.readback_duration_s.is_some())
    {
        if std::ptr::eq(sen, &doc.sensors[0]) {
            let _ = writeln!(
                s,
                "{:<22} {:>4} {:>18} {:>18} {:>30} {:>12} {:>12} {:>26}",
                "sensor",
                "axis",
                "ARW spec",
                "ARW sim",
                "interval",
                "BI spec",
                "BI sim",
                "interval"
            );
        }
        let g = &sen.spec.gyro;
        for a in 0..3 {
            let _ = writeln!(
                s,
                "{:<22} {:>4} {:>18} {:>18} {:>30} {:>12} {:>12} {:>26}",
                sen.spec.name,
                ["x", "y", "z"][a],
                opt(g.arw_spec[a], fmt::arw),
                opt(g.arw_sim[a], fmt::arw),
                match (g.arw_sim_lo[a], g.arw_sim_hi[a]) {
                    (Some(lo), Some(hi)) => format!("[{}, {}]", fmt::arw(lo), fmt::arw(hi)),
                    _ => String::new(),
                },
                opt(g.bi_spec[a], fmt::gyro_bias),
                opt(g.bi_sim[a], fmt::gyro_bias),
                match (g.bi_sim_lo[a], g.bi_sim_hi[a]) {
                    (Some(lo), Some(hi)) =>
                        format!("[{}, {}]", fmt::gyro_bias(lo), fmt::gyro_bias(hi)),
                    _ => String::new(),
                },
            );
        }
        for n in &g.notes {
            let _ = writeln!(s, "  note: {}: {n}", sen.spec.name);
        }
    }
}

/// Heading and horizontal drift per sensor and time, simulation and law.
fn drift_table(s: &mut String, doc: &SpecDoc) {
    use std::fmt::Write as _;
    let _ = writeln!(
        s,
        "\ndrift, static and level, on the round, rotating WGS-84 Earth at 45 deg N with the height held ({} Monte Carlo, {} runs): heading rms and horizontal position, simulation / law",
        fmt::rate(doc.drift_rate_hz),
        doc.sensors.first().map_or(0, |x| x.spec.drift_runs)
    );
    let _ = writeln!(
        s,
        "{:<22} {:>8} {:>11} {:>11} {:>12} {:>12} {:>12} {:>12} {:>12}",
        "sensor",
        "t",
        "hdg sim",
        "hdg law",
        "hor mean sim",
        "hor mean law",
        "hor rms sim",
        "hor rms law",
        "hor p95 sim"
    );
    let (yaw, hor) = (NavQuantity::Yaw.name(), NavQuantity::PosHorizontal.name());
    for sen in &doc.sensors {
        for d in &sen.spec.drift {
            let _ = writeln!(
                s,
                "{:<22} {:>8} {:>11} {:>11} {:>12} {:>12} {:>12} {:>12} {:>12}",
                sen.spec.name,
                fmt::time(d.t_s),
                fmt::quantity_value(yaw, d.heading_rms_sim_rad),
                fmt::quantity_opt(yaw, d.heading_rms_law_rad),
                fmt::quantity_value(hor, d.horizontal_mean_sim_m),
                fmt::quantity_opt(hor, d.horizontal_mean_law_m),
                fmt::quantity_value(hor, d.horizontal_rms_sim_m),
                fmt::quantity_opt(hor, d.horizontal_rms_law_m),
                fmt::quantity_value(hor, d.horizontal_p95_sim_m),
            );
            if let Some(n) = &d.law_note {
                let _ = writeln!(s, "  {:<20} t = {}: {n}", "", fmt::time(d.t_s));
            }
        }
        for n in &sen.model_notes {
            let _ = writeln!(s, "  note: {}: {n}", sen.spec.name);
        }
    }
}

/// One table per requirement: each sensor's verdict, value, interval and margin.
fn requirement_tables(s: &mut String, doc: &SpecDoc) {
    use std::fmt::Write as _;
    // Every sensor answers the same requirements, in the order given.
    let reqs: Vec<&String> = doc
        .sensors
        .first()
        .map(|x| x.requirements.iter().map(|r| &r.requirement).collect())
        .unwrap_or_default();
    for req in reqs {
        let _ = writeln!(
            s,
            "\nrequirement \"{req}\" (statistic of |error| over the runs, with its 95 % Monte Carlo interval)"
        );
        let _ = writeln!(
            s,
            "{:<22} {:>10} {:>12} {:>28} {:>12} {:>22}",
            "sensor", "verdict", "value", "interval", "threshold", "margin"
        );
        for sen in &doc.sensors {
            for r in sen.requirements.iter().filter(|r| &r.requirement == req) {
                let v = |x: f64| fmt::quantity_value(r.quantity, x);
                let verdict = match r.verdict {
                    Verdict::Pass => "PASS",
                    Verdict::Fail => "FAIL",
                    Verdict::Undecided => "undecided",
                    Verdict::NotInformed => "n/a",
                };
                let _ = writeln!(
                    s,
                    "{:<22} {:>10} {:>12} {:>28} {:>12} {:>22}",
                    sen.spec.name,
                    verdict,
                    r.value.map_or("n/a".into(), v),
                    match (r.value_lo, r.value_hi) {
                        (Some(lo), Some(hi)) => format!("[{}, {}]", v(lo), v(hi)),
                        _ => String::new(),
                    },
                    v(r.threshold),
                    match (r.margin, r.value) {
                        (Some(m), Some(value)) if value <= 10.0 * r.threshold => {
                            format!("{} ({:+.0} %)", v(m), 100.0 * m / r.threshold)
                        }
                        (Some(_), Some(value)) => {
                            format!("{}x the threshold", fmt::sig(value / r.threshold, 3))
                        }
                        _ => String::new(),
                    },
                );
                if r.verdict == Verdict::NotInformed {
                    let _ = writeln!(
                        s,
                        "  note: {}: the model has no error term that drives {}",
                        sen.spec.name, r.quantity
                    );
                }
            }
        }
        let _ = writeln!(s, "  PASS / FAIL: the whole 95 % interval is under / over the threshold; undecided: more runs (--runs) decide it; margin = threshold - value");
    }
}
