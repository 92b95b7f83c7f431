//! `imudrift spec SENSOR.toml...`: spec-sheet comparison of several sensors side by side: drift
//! at chosen times (heading and horizontal position, law and simulation), requirements answered
//! directly (`--require "pos_horizontal_m < 10 m @ 300 s"`: pass or fail with the margin), and on
//! request (`--readback`) the spec ARW and bias instability beside the values read back from a
//! simulated 12 h, 100 Hz static log (Woodman's Allan method).

use crate::cli::pool;
use crate::experiment_run::{check_memory, execute};
use crate::fmt;
use crate::output::{write_atomic, write_string};
use anyhow::{Context, Result};
use montecarlo::nav_quantity::NavQuantity;
use montecarlo::requirement::{evaluate, Requirement, RequirementResult, Verdict};
use montecarlo::spec::{
    drift_experiment, drift_rows, gyro_readback, gyro_spec_values, SensorSpec, READBACK_CONFIDENCE,
    READBACK_DURATION_S, READBACK_RATE_HZ,
};
use noise::{Effect, Sensor, SensorModel};
use serde::Serialize;
use std::path::PathBuf;

/// Drift times when neither --times nor --require gives any, s.
const DEFAULT_TIMES_S: [f64; 3] = [60.0, 600.0, 3600.0];
/// Monte Carlo runs per sensor: enough for the table (200), more when a requirement's p95 must be
/// placed against a threshold (500 runs: the p95's 95 % interval spans about ranks 465-485).
const DEFAULT_RUNS: u64 = 200;
const DEFAULT_RUNS_REQUIRE: u64 = 500;
/// Highest drift sample rate accepted, Hz.
const MAX_RATE_HZ: f64 = 1e6;
/// Most mechanisation steps (runs x samples) per sensor a spec run may ask for.
const MAX_STEPS_PER_SENSOR: f64 = 1e11;

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

#[derive(Serialize)]
struct SpecDoc {
    seed: u64,
    /// `null` when no readback was asked for.
    readback_duration_s: Option<f64>,
    readback_rate_hz: f64,
    readback_confidence: f64,
    drift_rate_hz: f64,
    sensors: Vec<SensorOut>,
}

/// One sensor's comparison with what the CLI adds: notes on what the model lacks, requirements.
#[derive(Serialize)]
struct SensorOut {
    #[serde(flatten)]
    spec: SensorSpec,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    model_notes: Vec<String>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    requirements: Vec<RequirementResult>,
}

/// Whether any axis of `sensor` has any error term.
fn has_any(model: &SensorModel, sensor: Sensor) -> bool {
    Effect::ALL.iter().any(|&e| model.has(sensor, e))
}

/// Whether the model has a term that drives `quantity`.
fn informs(model: &SensorModel, quantity: NavQuantity) -> bool {
    let gyro = has_any(model, Sensor::Gyro);
    let accel = has_any(model, Sensor::Accel);
    if quantity.name().ends_with("_rad") {
        gyro
    } else {
        gyro || accel
    }
}

pub fn run(args: Args) -> Result<()> {
    crate::output::note_inputs(&args.sensors);
    let _out_lock = args
        .out
        .as_deref()
        .map(crate::output::prepare_dir)
        .transpose()?;
    let settings = Settings::from_args(&args)?;
    let filter = noise::TermFilter::new(args.only.as_deref(), &args.without);
    let pool = pool(args.threads)?;
    let mut sensors = Vec::new();
    for path in &args.sensors {
        sensors.push(compare_sensor(path, &settings, &filter, &pool, args.seed)?);
    }
    let doc = SpecDoc {
        seed: args.seed,
        readback_duration_s: settings.readback_duration_s,
        readback_rate_hz: READBACK_RATE_HZ,
        readback_confidence: READBACK_CONFIDENCE,
        drift_rate_hz: args.rate,
        sensors,
    };
    let text = serde_json::to_string_pretty(&doc)? + "\n";
    crate::output::answer(&table(&doc), args.json.then_some(text.as_str()))?;
    if let Some(dir) = &args.out {
        let _set = crate::output::begin_set(dir)?;
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
        eprintln!(
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

/// The command's settings, checked before any work.
struct Settings {
    requirements: Vec<Requirement>,
    /// Drift times (the requirements' included), rounded to whole samples, sorted, s.
    times_s: Vec<f64>,
    rate_hz: f64,
    runs: u64,
    /// Length of the readback log, s (`None`: spec values only).
    readback_duration_s: Option<f64>,
}

impl Settings {
    fn from_args(args: &Args) -> Result<Settings> {
        let requirements = args
            .require
            .iter()
            .map(|r| r.parse::<Requirement>())
            .collect::<Result<Vec<_>, _>>()
            .context("--require")?;
        let mut times: Vec<f64> = match &args.times {
            Some(t) => t.clone(),
            None if !requirements.is_empty() => Vec::new(),
            None => DEFAULT_TIMES_S.to_vec(),
        };
        let rate = crate::cli::check_rate_hz("--rate", args.rate)?;
        if rate > MAX_RATE_HZ {
            anyhow::bail!("--rate: expected at most {MAX_RATE_HZ} Hz, found {rate}");
        }
        times.extend(requirements.iter().map(|r| r.t_s));
        // Drift is recorded at whole samples: each time is rounded to the nearest sample.
        for t in &mut times {
            let k = (*t * rate).round();
            if k < 1.0 {
                anyhow::bail!(
                    "--times / --require: {t} s is shorter than one sample at --rate {rate} Hz"
                );
            }
            *t = k / rate;
        }
        times.sort_by(f64::total_cmp);
        times.dedup();
        if times.is_empty() {
            anyhow::bail!("--times: expected positive times in seconds, e.g. 60,600,3600");
        }
        let runs = args.runs.unwrap_or(if requirements.is_empty() {
            DEFAULT_RUNS
        } else {
            DEFAULT_RUNS_REQUIRE
        });
        if runs == 0 {
            anyhow::bail!("--runs: expected an integer >= 1");
        }
        // Refuse work that would run for hours before starting it (about 1e7 steps/s per core).
        let steps = runs as f64 * times.last().copied().unwrap_or(0.0) * rate;
        if steps > MAX_STEPS_PER_SENSOR {
            anyhow::bail!(
            "{runs} runs of {} at {rate} Hz are {steps:.2e} mechanisation steps per sensor (limit {MAX_STEPS_PER_SENSOR:.0e}, about 3 h on 2 cores): use fewer --runs, a lower --rate or an earlier time",
            crate::fmt::time(times.last().copied().unwrap_or(0.0))
        );
        }
        let readback_duration = match args.readback_duration {
            Some(d) => Some(d),
            None => args.readback.then_some(READBACK_DURATION_S),
        };
        if let Some(d) = readback_duration {
            check_readback_duration(d)?;
        }
        Ok(Settings {
            requirements,
            times_s: times,
            rate_hz: rate,
            runs,
            readback_duration_s: readback_duration,
        })
    }
}

/// A readback log of `d` s must be long enough to read, and fit in memory.
fn check_readback_duration(d: f64) -> Result<()> {
    if !(d.is_finite() && d * READBACK_RATE_HZ >= 1000.0) {
        anyhow::bail!("--readback-duration: expected at least 10 s");
    }
    // 8 bytes per sample per axis; refuse before allocating what the machine cannot hold.
    if d * READBACK_RATE_HZ > 2e9 {
        anyhow::bail!(
            "--readback-duration: {d:e} s at {READBACK_RATE_HZ} Hz is more than 2e9 samples (16 GB per axis); use at most 5.5e6 s (64 days)"
        );
    }
    // The three axes are generated and analysed at once: each holds its samples and their
    // integral (16 bytes a sample).
    let need = 3.0 * 16.0 * d * READBACK_RATE_HZ;
    if let Some(available) = logio::available_memory_bytes() {
        if need > available as f64 {
            anyhow::bail!(
                "--readback-duration: a {} readback log needs about {:.1} GiB and {:.1} GiB is available: use a shorter --readback-duration",
                crate::fmt::time(d),
                need / (1u64 << 30) as f64,
                available as f64 / (1u64 << 30) as f64
            );
        }
    }
    Ok(())
}

/// One sensor: its spec values (or read back from a simulated log), drift runs, requirements.
fn compare_sensor(
    path: &std::path::Path,
    settings: &Settings,
    filter: &noise::TermFilter,
    pool: &rayon::ThreadPool,
    seed: u64,
) -> Result<SensorOut> {
    let Settings {
        requirements,
        times_s: times,
        rate_hz: rate,
        runs,
        readback_duration_s: readback_duration,
    } = settings;
    let (rate, runs, readback_duration) = (*rate, *runs, *readback_duration);
    let model = crate::files::sensor_model(path)?.filtered(filter);
    let exp = drift_experiment(&model, times, rate, runs, seed)
        .with_context(|| path.display().to_string())?;
    check_memory(&exp, exp.runs)?;
    crate::experiment_run::check_experiment_work(&exp, exp.runs)?;
    let gyro = match readback_duration {
        Some(d) => {
            eprintln!(
                "{}: reading back a {}, {} static log ...",
                model.name,
                fmt::time(d),
                fmt::rate(READBACK_RATE_HZ)
            );
            pool.install(|| gyro_readback(&model, seed, d, READBACK_RATE_HZ))
        }
        None => gyro_spec_values(&model, READBACK_RATE_HZ),
    };
    let batch = pool.install(|| execute(&exp, 0..exp.runs, &model.name));
    if batch.matrix.runs() == 0 {
        anyhow::bail!(
            "{}: every one of the {runs} drift runs failed ({}); the model's values are probably far too large (check their units)",
            path.display(),
            batch
                .failures
                .first()
                .map_or("no run finished".to_string(), |f| f.message.clone())
        );
    }
    let report = exp.report(&batch.matrix, &batch.failures);
    crate::experiment_run::check_finite(&report)
        .with_context(|| format!("{}: drift of {}", path.display(), model.name))?;
    for f in &batch.failures {
        eprintln!(
            "warning: {}: drift run {} failed: {}",
            model.name, f.run, f.message
        );
    }
    let checkpoint_times = exp.scenario.checkpoint_times_s();
    let requirements = requirements
        .iter()
        .map(|req| {
            let cp = checkpoint_times
                .iter()
                .position(|&t| (t - req.t_s).abs() <= 0.5 / rate)
                .context("a requirement's time is not a checkpoint")?;
            let values = batch.matrix.series(cp, req.quantity as usize);
            Ok(evaluate(req, values, informs(&model, req.quantity)))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(SensorOut {
        spec: SensorSpec {
            name: model.name.clone(),
            gyro,
            drift: drift_rows(&report),
            drift_runs: report.runs_ok,
        },
        model_notes: crate::model_notes::notes(&model, checkpoint_times.last().copied()),
        requirements,
    })
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
        "\ndrift, static and level ({} Monte Carlo, {} runs): heading rms and horizontal position, simulation / law",
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
