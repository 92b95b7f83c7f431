//! `imudrift diagnose LOG.csv --model SENSOR.toml`: where the model and the measurement disagree,
//! which effect is missing, the corrected model, and the gap before and after (docs/diagnose.md,
//! "The diagnose workflow").

use crate::cli::request_error;
use crate::log_input::{self, LogArgs};
use crate::output::write_string;
use crate::plot::{Band, LogLogPlot, Series};
use anyhow::{anyhow, Context, Result};
use diagnose::report::{ChannelReport, DriftRow, FoundEffect};
use diagnose::{diagnose_until, DiagnoseError, Diagnosis, LogInput, Settings};
use noise::noise_file::AxisValue;
use noise::SensorModel;
use request::diagnose::{DiagnoseRequest, ProtocolRequest};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct Args {
    /// Measured static log: CSV or gzip-compressed CSV with a header (`#` lines are comments;
    /// columns recognised by name, docs/cli.md), a ROS 1 bag or a ROS 2 MCAP file. Several logs:
    /// runs of one sensor (same rate and columns) fitted together (docs/diagnose.md, "Several runs")
    #[arg(required = true, value_name = "LOG")]
    pub logs: Vec<PathBuf>,
    /// Sensor model TOML to check against the log
    #[arg(long, value_name = "SENSOR.toml")]
    pub model: PathBuf,
    #[command(flatten)]
    pub log_args: LogArgs,
    #[command(flatten)]
    pub earth: crate::log_input::EarthArgs,
    /// Master seed of the simulated logs (written into the outputs) [default: 1]
    #[arg(long)]
    pub seed: Option<u64>,
    /// Simulated logs per model band [default: 16]
    #[arg(long)]
    pub seeds: Option<usize>,
    /// Add-and-resimulate rounds at most [default: 6]
    #[arg(long)]
    pub rounds: Option<usize>,
    /// Drift horizons: a comma list of times, e.g. 60,3600 or 1min,1h (a bare number is seconds)
    /// [default: 1min,1h]
    #[arg(long, value_delimiter = ',', value_parser = crate::cli::duration_s)]
    pub horizons: Option<Vec<f64>>,
    /// BIC improvement an effect needs to be named (> 10 is "very strong" evidence, Kass & Raftery
    /// 1995; 16 keeps false alarms near 1e-3 per clean 6-channel log) [default: 16]
    #[arg(long)]
    pub min_delta_bic: Option<f64>,
    /// Leave out taus below this time (a bare number is seconds), e.g. where the sensor's
    /// anti-alias filter shapes the curve [default: 0]
    #[arg(long, value_name = "TIME", value_parser = crate::cli::duration_or_zero_s)]
    pub tau_min: Option<f64>,
    /// Held-out logs (same rate, length and columns) to check the corrected model on: their gap with
    /// the original and with the corrected model (repeat or comma-separate)
    #[arg(long, value_delimiter = ',', value_name = "LOG")]
    pub check: Vec<PathBuf>,
    /// Run the drift check in the loop (docs/diagnose.md, "Drift in the loop"): the logs' drift
    /// under the `drift` protocol against the model's, before and after, and slow terms fitted to
    /// the Allan and drift gaps together. On by default with several logs; implied by
    /// --calibration or --init
    #[arg(long)]
    pub drift_check: bool,
    /// The drift check's bias calibration: none, log-mean (default) or window:TIME
    #[arg(long, value_name = "HOW", value_parser = crate::cmd_drift::calibration)]
    pub calibration: Option<diagnose::protocol::Calibration>,
    /// The drift check's initial attitude: perfect (default) or level:TIME
    #[arg(long, value_name = "HOW", value_parser = crate::cmd_drift::initialisation)]
    pub init: Option<diagnose::protocol::Initialisation>,
    /// Print one JSON document on stdout (human text on stderr)
    #[arg(long)]
    pub json: bool,
    /// Write report.md, diagnose.json, the corrected sensor TOML and SVG plots into this directory
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Worker threads (default: all cores); results do not depend on it
    #[arg(long)]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub noise_file: crate::noise_out::NoiseFileArgs,
}

/// diagnose's steps as the stages of a progress display.
struct Stages(crate::progress::Progress);

impl diagnose::Observer for Stages {
    fn step(&self, step: diagnose::Step) {
        self.0.stage(&step.to_string());
    }
    fn round_done(&self, done: &diagnose::RoundDone) {
        self.0.stage(&done.to_string());
    }
}

/// A diagnose error, one about a setting named by the option that sets it.
fn with_flags(e: DiagnoseError) -> anyhow::Error {
    anyhow!(request::diagnose::diagnose_error(&e, &crate::cli::flag))
}

/// The request of the command line (`request::diagnose`: one set of defaults and checks).
fn request(args: &Args) -> DiagnoseRequest {
    DiagnoseRequest {
        logs: args.logs.len(),
        seed: args.seed,
        seeds: args.seeds,
        rounds: args.rounds,
        min_delta_bic: args.min_delta_bic,
        tau_min_s: args.tau_min,
        drift_check: args.drift_check,
        protocol: ProtocolRequest {
            calibration: args.calibration,
            initialisation: args.init,
            horizons_s: args.horizons.clone(),
            overlapping: false,
            earth: args.earth.earth(),
        },
    }
}

pub fn run(args: Args) -> Result<()> {
    crate::output::note_inputs(args.logs.iter().chain([&args.model]).chain(&args.check));
    args.noise_file.refuse_inputs()?;
    args.noise_file.check()?;
    let _out_lock = args
        .out
        .as_deref()
        .map(crate::output::prepare_dir)
        .transpose()?;
    let settings = request(&args).validate().map_err(request_error)?;
    let pool = crate::cli::pool(args.threads)?;
    pool.install(|| run_inner(&args, &settings))
}

/// The channels of a log as diagnose reads them, once checked: a log without a gyro or
/// accelerometer channel, or with a constant one, is refused (`request::logs`).
fn log_channels(log: &logio::Log) -> Result<LogInput<'_>> {
    request::logs::check_imu(log).map_err(crate::cli::request_error)?;
    Ok(request::logs::log_input(log, true))
}

fn run_inner(args: &Args, settings: &Settings) -> Result<()> {
    let model = crate::files::sensor_model(&args.model)?;
    let horizons = &settings.horizons_s;
    crate::model_notes::print(&model, horizons.iter().copied().reduce(f64::max));
    args.earth
        .note(horizons.iter().copied().fold(0.0, f64::max));
    let logs = args.log_args.read_all(&args.logs)?;
    for log in &logs {
        tell!("{}: {}", log.source, log_input::mapping_text(log));
        crate::plausibility::print(log);
    }
    request::logs::refuse_repeated(&logs).map_err(crate::cli::request_error)?;
    let log = &logs[0];
    let sources = logs
        .iter()
        .map(|l| l.source.as_str())
        .collect::<Vec<_>>()
        .join(", ");
    let longest = logs.iter().map(logio::Log::len).max().unwrap_or(0);
    request::diagnose::check_simulation_memory(&log.source, longest, rayon::current_num_threads())
        .map_err(request_error)?;
    let inputs: Vec<LogInput> = logs.iter().map(log_channels).collect::<Result<_>>()?;
    let input = inputs[0];
    let protocol = request(args)
        .protocol
        .protocol(horizons)
        .map_err(request_error)?;
    crate::cmd_drift::check_sampling(&protocol, input.dt_s, longest)?;
    // An output filter in the model must fit the log's rate.
    noise::ImuErrors::check_rate(&model, input.dt_s).map_err(|e| {
        anyhow::anyhow!(
            "{}: {e}; the log is at {}",
            args.model.display(),
            crate::fmt::rate(1.0 / input.dt_s)
        )
    })?;
    let started = std::time::Instant::now();
    let stages = Stages(crate::progress::Progress::stages("diagnose"));
    let result = diagnose_until(&inputs, &model, settings, &stages, &crate::output::STOP);
    stages.0.finish();
    let result = result
        .map_err(with_flags)
        .with_context(|| format!("diagnosing {sources} against {}", args.model.display()))?;
    let elapsed_s = started.elapsed().as_secs_f64();
    let fitted_on = result.fitted_on(&inputs);
    let corrected = corrected_model(&result, &model, &args.model, fitted_on.as_ref());
    let mut human = text_report(&result, &sources, &args.model, elapsed_s);
    let mut checks = Vec::new();
    for path in &args.check {
        let held = args.log_args.read(path)?;
        let input = request::logs::log_input(&held, true);
        let gaps = result
            .check(&input)
            .with_context(|| format!("checking {}", held.source))?;
        checks.push((held.source.clone(), gaps));
    }
    if !checks.is_empty() {
        human.push_str(&checks_text(&checks));
    }
    let doc = json_document(&result, &logs, &args.model, &corrected, &checks)?;
    let per_channel = noise::ImuChannels::from_fn(|c| {
        result
            .channels
            .contains_key(&c)
            .then(|| model_noise_values(&result, c))
            .flatten()
    });
    // The noise file and the --out files are one set: all of them, or none if one cannot be
    // written.
    let set = crate::output::begin_set();
    args.noise_file.write(
        &per_channel,
        log.rate_hz,
        &format!(
            "the model `imudrift diagnose` corrected on {} (from {})",
            sources,
            args.model.display()
        ),
        log.topic.as_deref(),
    )?;
    crate::output::answer(&human, args.json.then_some(format!("{doc}\n").as_str()))?;
    if let Some(dir) = &args.out {
        crate::output::ensure_dir(dir)?;
        let toml_name = request::diagnose::diagnosed_model_name(&args.model.display().to_string());
        write_string(&dir.join(&toml_name), &corrected)?;
        write_string(&dir.join("diagnose.json"), &doc)?;
        write_string(&dir.join("diagnose.csv"), &effects_csv(&result))?;
        write_string(&dir.join("diagnose_drift.csv"), &drift_csv(&result))?;
        for (name, report) in &result.channels {
            write_string(
                &dir.join(format!("diagnose_{name}.svg")),
                &plot(*name, report, &result),
            )?;
        }
        write_string(
            &dir.join("report.md"),
            &markdown_report(&result, &sources, &args.model, &toml_name, &checks),
        )?;
    }
    set.commit()?;
    if let Some(dir) = &args.out {
        let toml_name = request::diagnose::diagnosed_model_name(&args.model.display().to_string());
        tell!(
            "wrote {} (report.md, diagnose.json, diagnose.csv, diagnose_drift.csv, {toml_name}, diagnose_<channel>.svg)",
            dir.display()
        );
    }
    Ok(())
}

/// `diagnose.csv`: the effects table of the text answer, one row per channel, effect and
/// parameter (SI, the JSON's names: `channels{ch: {gap_initial, gap_final, effects[{effect, kind,
/// round, stand_in, parameters, parameters_lo, parameters_hi, gap_before, gap_after,
/// delta_bic}]}}`); a channel without effects has one row with the effect fields empty. Channels
/// in log-column order (gx gy gz ax ay az); `delta_bic` empty for a time-domain finding.
fn effects_csv(result: &Diagnosis) -> String {
    let mut s = String::from(
        "channel,gap_initial,gap_final,round,kind,effect,stand_in,parameter,value,lo,hi,gap_before,gap_after,delta_bic\n",
    );
    let num = |v: Option<f64>| {
        v.filter(|x| x.is_finite())
            .map_or(String::new(), |x| format!("{x:e}"))
    };
    for (c, r) in &result.channels {
        let head = format!("{},{:e},{:e}", c.name(), r.gap_initial, r.gap_final);
        if r.effects.is_empty() {
            let _ = writeln!(s, "{head},,,,,,,,,,,");
        }
        for e in &r.effects {
            let mut params: Vec<(String, String)> = e
                .parameters
                .iter()
                .map(|(k, &v)| (k.clone(), format!("{v:e}")))
                .collect();
            if let Some(kind) = e.parameters.kind {
                params.insert(0, ("kind".into(), kind.into()));
            }
            for (k, v) in params {
                let _ = writeln!(
                    s,
                    "{head},{},{},{},{},{k},{v},{},{},{},{},{}",
                    e.round,
                    e.kind,
                    e.effect.name(),
                    e.stand_in,
                    num(e.parameters_lo.get(&k).copied()),
                    num(e.parameters_hi.get(&k).copied()),
                    num(Some(e.gap_before)),
                    num(Some(e.gap_after)),
                    num((e.round > 0).then_some(e.delta_bic)),
                );
            }
        }
    }
    s
}

/// `diagnose_drift.csv`: the drift table of the text answer (RMS over segments of the heading
/// and horizontal position error, rad and m), measured and with the model before and after.
fn drift_csv(result: &Diagnosis) -> String {
    let mut s = String::from("horizon_s,source,segments,heading_rms_rad,pos_horizontal_rms_m\n");
    for d in &result.drift {
        for (source, sum) in [
            ("measured", &d.measured),
            ("model_before", &d.model_initial),
            ("model_after", &d.model_final),
        ] {
            let _ = writeln!(
                s,
                "{:e},{source},{},{:e},{:e}",
                d.horizon_s, sum.segments, sum.heading_rms_rad, sum.horizontal_rms_m
            );
        }
    }
    s
}

/// The corrected model as TOML (`diagnose::document`), in the units and conventions of the
/// input model's file (spec-sheet units where it has none).
fn corrected_model(
    result: &Diagnosis,
    model: &SensorModel,
    model_path: &Path,
    fitted_on: Option<&diagnose::fitted_on::FittedOn>,
) -> String {
    let style = crate::files::read_config(model_path)
        .map(|file| noise::UnitStyle::from_config_text(&file.text))
        .unwrap_or_default();
    diagnose::document::corrected_model_toml(result, model, &style, fitted_on)
}

/// Whether the log can inform a drift quantity (it has every channel it comes from).
fn informed(result: &Diagnosis, q: diagnose::protocol::Quantity) -> bool {
    q.needs().iter().all(|c| result.channels.contains_key(c))
}

fn drift_line(d: &DriftRow, heading: bool, horizontal: bool) -> String {
    let cell = |s: &diagnose::drift::DriftSummary| {
        if s.segments == 0 {
            format!("{:>11} {:>11}", "-", "-")
        } else {
            let h = if heading {
                crate::fmt::quantity_value("heading_rad", s.heading_rms_rad)
            } else {
                "n/a".into()
            };
            let p = if horizontal {
                crate::fmt::quantity_value("pos_horizontal_m", s.horizontal_rms_m)
            } else {
                "n/a".into()
            };
            format!("{h:>11} {p:>11}")
        }
    };
    format!(
        "{:>10}  {}  {}  {}  (segments: {} measured)",
        crate::fmt::time(d.horizon_s),
        cell(&d.measured),
        cell(&d.model_initial),
        cell(&d.model_final),
        d.measured.segments
    )
}

fn text_report(result: &Diagnosis, log: &str, model: &Path, elapsed_s: f64) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "diagnose {log} against {} ({} samples at {}, {}; {} simulated logs per band, seed {}, {} round(s), {:.1} s)",
        model.display(),
        result.samples,
        crate::fmt::rate(1.0 / result.dt_s),
        crate::fmt::time(result.samples as f64 * result.dt_s),
        result.seeds,
        result.seed,
        result.rounds,
        elapsed_s
    );
    let _ = writeln!(
        s,
        "{:<4} {:>10} {:>10}  effects",
        "ch", "gap before", "gap after"
    );
    for (name, r) in &result.channels {
        let _ = writeln!(
            s,
            "{name:<4} {:>10.2} {:>10.2}  {}",
            r.gap_initial, r.gap_final, r.verdict
        );
        for e in &r.effects {
            let _ = writeln!(
                s,
                "       {} {} ({}): {}; gap {:.2} -> {:.2}, {}{}{}",
                e.kind,
                e.effect,
                crate::effect_text::model_text(e, *name),
                crate::effect_text::params_text(e, *name),
                e.gap_before,
                e.gap_after,
                crate::effect_text::evidence_text(e),
                drift_gap_text(e),
                if e.cannot_tell_from.is_empty() {
                    String::new()
                } else {
                    format!(
                        "; cannot tell it from {}",
                        e.cannot_tell_from
                            .iter()
                            .map(|x| x.name())
                            .collect::<Vec<_>>()
                            .join(", ")
                    )
                }
            );
        }
    }
    s.push_str(&runs_text(result));
    s.push_str(&run_to_run_text(result));
    s.push_str(&drift_check_text(result));
    let _ = writeln!(
        s,
        "drift (RMS over segments; bias removed by the log mean): heading, horizontal position"
    );
    let _ = writeln!(
        s,
        "{:>10}  {:^25}  {:^25}  {:^25}",
        "horizon", "measured", "model before", "model after"
    );
    use diagnose::protocol::Quantity;
    let (heading, horizontal) = (
        informed(result, Quantity::Heading),
        informed(result, Quantity::PosHorizontal),
    );
    for d in &result.drift {
        let _ = writeln!(s, "{}", drift_line(d, heading, horizontal));
    }
    if !(heading && horizontal) {
        let _ = writeln!(
            s,
            "n/a: the log cannot inform it (heading needs gz; horizontal position needs gx, gy, ax, ay); `imudrift drift` compares every quantity a log informs"
        );
    }
    s
}

/// The drift check in the loop: per horizon and quantity the measured RMS against the model's
/// band before and after, and the drift gap.
fn drift_check_text(result: &Diagnosis) -> String {
    let mut s = String::new();
    let Some(d) = &result.drift_check else {
        return s;
    };
    let _ = writeln!(
        s,
        "drift check ({}): drift gap {:.2} -> {:.2} ({} -> {} outside the 95 % band)",
        d.protocol_text, d.before.gap, d.after.gap, d.before.outside, d.after.outside
    );
    for r in drift_check_rows(d) {
        let _ = writeln!(
            s,
            "  {:>8} {:<18} measured {:>11}  model before {:>11} [{}, {}] {:<6} z {:>6.2}  after {:>11} [{}, {}] {:<6} z {:>6.2}",
            r.time, r.quantity, r.measured, r.before.model, r.before.lo, r.before.hi,
            r.before.verdict, r.before.z, r.after.model, r.after.lo, r.after.hi, r.after.verdict, r.after.z
        );
    }
    s.push_str(&alternatives_text(result, "  "));
    s
}

/// The structures the drift loop could not tell apart (the corrected model's `[[alternatives]]`),
/// one line each after a heading, every line starting with `indent`.
fn alternatives_text(result: &Diagnosis, indent: &str) -> String {
    let mut s = String::new();
    if result.alternatives.is_empty() {
        return s;
    }
    let _ = writeln!(
        s,
        "{indent}structures the drift evidence could not tell apart (posterior odds above 1:20 against the kept one; the corrected model lists them and `imudrift drift` averages its band over them with these weights):"
    );
    for a in &result.alternatives {
        let mut what: Vec<String> = a.effects.iter().map(|e| e.name().to_string()).collect();
        what.extend(a.removed.iter().map(|e| format!("no {}", e.name())));
        let _ = writeln!(
            s,
            "{indent}  {}: {} (weight {:.2}, -2 ln odds {:.1})",
            a.channel.name(),
            what.join(", "),
            a.weight,
            a.delta_bic
        );
    }
    s
}

/// Several runs: each channel's run-to-run variation of its slow group and of its white noise (docs/diagnose.md,
/// "Runs that differ"), the estimate with its 95 % interval and the test against the null.
fn run_to_run_text(result: &Diagnosis) -> String {
    let mut s = String::new();
    if result.run_to_run.is_empty() {
        return s;
    }
    let _ = writeln!(
        s,
        "run-to-run variation (sd of ln level between power-ons of each channel's slow terms and of its white noise; every estimate above 0 is written as `run_to_run`, so a next run's band holds it; named: the runs differ by the naming rule):"
    );
    for r in &result.run_to_run {
        let runs: Vec<String> = r
            .ln_multipliers
            .iter()
            .map(|x| format!("{x:+.2}"))
            .collect();
        let _ = writeln!(
            s,
            "  {} {}: spread {:.3} [{:.3}, {:.3}]  per-run ln level {}  p = {:.3} (chi2 {}) {}",
            r.channel.name(),
            r.effects.join("+"),
            r.spread,
            r.interval[0],
            r.interval[1],
            runs.join(" "),
            r.p_value,
            // A tail probability below the double's reach prints as a bound, not as 0.
            if r.p_chi2 < 1e-15 {
                "< 1e-15".to_string()
            } else {
                format!("{:.1e}", r.p_chi2)
            },
            if r.named { "named" } else { "not named" }
        );
    }
    s
}

/// Each run's gap per channel (several runs): against one log of the original model, and of the
/// corrected model.
fn runs_text(result: &Diagnosis) -> String {
    let mut s = String::new();
    if result.runs.is_empty() {
        return s;
    }
    let _ = writeln!(
        s,
        "runs (pooled above): each run's gap against one log of the original model -> of the corrected model"
    );
    for (i, run) in result.runs.iter().enumerate() {
        let cells: Vec<String> = run
            .channels
            .iter()
            .map(|(ch, c)| format!("{ch} {:.2} -> {:.2}", c.gap_initial, c.gap_final))
            .collect();
        let _ = writeln!(
            s,
            "  run {} ({} samples): {}",
            i + 1,
            run.samples,
            cells.join(", ")
        );
        for (ch, found) in &run.findings {
            for e in found {
                let _ = writeln!(
                    s,
                    "       {ch}: {} {}",
                    e.effect,
                    crate::effect_text::params_text(e, *ch)
                );
            }
        }
    }
    s
}

/// "; drift gap 3.1 -> 1.2" for an effect the drift loop named.
fn drift_gap_text(e: &FoundEffect) -> String {
    match (e.drift_gap_before, e.drift_gap_after) {
        (Some(b), Some(a)) => format!("; drift gap {b:.2} -> {a:.2}"),
        _ => String::new(),
    }
}

type Checks = diagnose::document::HeldOutChecks;

fn checks_text(checks: &Checks) -> String {
    let mut s =
        String::from("held-out logs: gap with the original model -> with the corrected model\n");
    for (log, gaps) in checks {
        let cells: Vec<String> = gaps
            .iter()
            .map(|(ch, g)| format!("{ch} {:.2} -> {:.2}", g.gap_model, g.gap_corrected))
            .collect();
        let _ = writeln!(s, "  {log}: {}", cells.join(", "));
    }
    s
}

/// A channel's noise density and random walk for a noise file, from the corrected model: its
/// white noise N, and its rate random walk K or, where it has none, the largest random walk its
/// Allan curve allows over the log's averaging times (the +1/2 line touching the model's curve,
/// which covers its bias instability there).
fn model_noise_values(result: &Diagnosis, c: noise::Channel) -> Option<(AxisValue, AxisValue)> {
    let a = result.model_final.axis(c.sensor(), c.axis());
    let taus: Vec<f64> = result
        .grid_m
        .iter()
        .map(|&m| m as f64 * result.dt_s)
        .collect();
    noise::noise_file::axis_noise_values(a, &taus, "corrected model", &crate::fmt::time)
}

fn json_document(
    result: &Diagnosis,
    logs: &[logio::Log],
    model: &Path,
    corrected: &str,
    checks: &Checks,
) -> Result<String> {
    let names: Vec<String> = logs.iter().map(|l| l.source.clone()).collect();
    let model = model.display().to_string();
    let sources = diagnose::document::DiagnoseSources {
        logs: &names,
        columns: log_input::columns_json(&logs[0]),
        model: &model,
    };
    let v = diagnose::document::diagnose_document(result, sources, corrected, checks)
        .context("cannot serialise the diagnosis")?;
    serde_json::to_string_pretty(&v).context("cannot serialise the diagnosis")
}

/// One side (before or after) of a drift-check row, formatted in the quantity's units.
struct DriftSide {
    model: String,
    lo: String,
    hi: String,
    verdict: &'static str,
    z: f64,
}

/// One row of the drift check (a horizon and a quantity), for the text and report.md tables.
struct DriftCheckRow {
    time: String,
    quantity: String,
    measured: String,
    before: DriftSide,
    after: DriftSide,
}

/// The drift check's rows: each horizon's quantities found both before and after.
fn drift_check_rows(d: &diagnose::report::DriftLoop) -> Vec<DriftCheckRow> {
    let mut rows = Vec::new();
    for (h0, h1) in d.before.horizons.iter().zip(&d.after.horizons) {
        for (q, z0) in &h0.quantities {
            let Some(z1) = h1.quantities.get(q) else {
                continue;
            };
            let v = |x: f64| crate::fmt::quantity_value(q, x);
            let side = |z: &diagnose::drift_gap::DriftZ| DriftSide {
                model: v(z.model_rms),
                lo: v(z.band_lo),
                hi: v(z.band_hi),
                verdict: z.verdict.name(),
                z: z.z,
            };
            rows.push(DriftCheckRow {
                time: crate::fmt::time(h0.t_s),
                quantity: q.to_string(),
                measured: v(z0.measured_rms),
                before: side(z0),
                after: side(z1),
            });
        }
    }
    rows
}

/// The drift check's section of report.md: per horizon and quantity the measured RMS against the
/// model's 95 % band before and after, beside the Allan gaps of the table above.
fn drift_check_markdown(result: &Diagnosis) -> String {
    let mut s = String::new();
    let Some(d) = &result.drift_check else {
        return s;
    };
    let _ = writeln!(
        s,
        "\n## Drift check\n\nProtocol: {}. z = (ln RMS measured - mean ln RMS of the model's replicates) / their spread; the band is the 95 % range of the replicates (log-normal). Drift gap (RMS of z): {:.2} before, {:.2} after; outside the band: {} before, {} after.\n",
        d.protocol_text, d.before.gap, d.after.gap, d.before.outside, d.after.outside
    );
    let _ = writeln!(
        s,
        "| horizon | quantity | measured | model before [95 %] | verdict (z) | model after [95 %] | verdict (z) |\n|---|---|---|---|---|---|---|"
    );
    for r in drift_check_rows(d) {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} [{}, {}] | {} ({:.2}) | {} [{}, {}] | {} ({:.2}) |",
            r.time,
            r.quantity,
            r.measured,
            r.before.model,
            r.before.lo,
            r.before.hi,
            r.before.verdict,
            r.before.z,
            r.after.model,
            r.after.lo,
            r.after.hi,
            r.after.verdict,
            r.after.z
        );
    }
    let alternatives = alternatives_text(result, "");
    if !alternatives.is_empty() {
        s.push('\n');
        for line in alternatives.lines() {
            let _ = writeln!(
                s,
                "{}",
                line.strip_prefix("  ")
                    .map_or(line.to_string(), |l| format!("- {l}"))
            );
        }
    }
    s
}

/// The runs' section of report.md (several runs): each run's gaps and step-0 findings.
fn runs_markdown(result: &Diagnosis) -> String {
    let mut s = String::new();
    if result.runs.is_empty() {
        return s;
    }
    let _ = writeln!(
        s,
        "\n## Runs\n\nThe logs are runs of one sensor fitted together: the table above is of their pooled Allan variances. Each run's gap against one log of the original model -> of the corrected model, and what the time-domain detectors found in it.\n"
    );
    let _ = writeln!(
        s,
        "| run | samples | {} | found |",
        noise::Channel::ALL.map(noise::Channel::name).join(" | ")
    );
    let _ = writeln!(
        s,
        "|---|---|{}---|",
        "---|".repeat(noise::Channel::ALL.len())
    );
    for (i, run) in result.runs.iter().enumerate() {
        let cells: Vec<String> = noise::Channel::ALL
            .iter()
            .map(|ch| {
                run.channels.get(ch).map_or("-".into(), |c| {
                    format!("{:.2} -> {:.2}", c.gap_initial, c.gap_final)
                })
            })
            .collect();
        let found: Vec<String> = run
            .findings
            .iter()
            .flat_map(|(ch, f)| {
                f.iter().map(move |e| {
                    format!(
                        "{ch}: {} {}",
                        e.effect,
                        crate::effect_text::params_text(e, *ch)
                    )
                })
            })
            .collect();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} |",
            i + 1,
            run.samples,
            cells.join(" | "),
            if found.is_empty() {
                "-".into()
            } else {
                found.join("<br>")
            }
        );
    }
    s
}

/// report.md's drift table: heading and horizontal position, measured and both models.
fn drift_markdown(result: &Diagnosis) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\n## Drift (RMS over segments, bias removed by the log mean)\n"
    );
    let _ = writeln!(s, "| horizon | measured heading | model before | model after | measured horizontal | model before | model after |\n|---|---|---|---|---|---|---|");
    let (heading, horizontal) = (
        informed(result, diagnose::protocol::Quantity::Heading),
        informed(result, diagnose::protocol::Quantity::PosHorizontal),
    );
    for d in &result.drift {
        let ang = |v: f64| {
            if heading {
                crate::effect_text::degrees(v)
            } else {
                "n/a".into()
            }
        };
        let len = |v: f64| {
            if horizontal {
                crate::effect_text::metres(v)
            } else {
                "n/a".into()
            }
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} |",
            crate::fmt::time(d.horizon_s),
            ang(d.measured.heading_rms_rad),
            ang(d.model_initial.heading_rms_rad),
            ang(d.model_final.heading_rms_rad),
            len(d.measured.horizontal_rms_m),
            len(d.model_initial.horizontal_rms_m),
            len(d.model_final.horizontal_rms_m),
        );
    }
    s
}

fn markdown_report(
    result: &Diagnosis,
    log: &str,
    model: &Path,
    toml_name: &str,
    checks: &Checks,
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# imudrift diagnose\n");
    let _ = writeln!(
        s,
        "Log `{log}` ({} samples at {}, {}) against model `{}`; {} simulated logs per band, seed {}, {} round(s). Corrected model: `{toml_name}`. Parameters in spec-sheet units with their 95 % intervals (discrete choices have none); `diagnose.json` has them in SI.\n",
        result.samples,
        crate::fmt::rate(1.0 / result.dt_s),
        crate::fmt::time(result.samples as f64 * result.dt_s),
        model.display(),
        result.seeds,
        result.seed,
        result.rounds
    );
    let _ = writeln!(s, "Gap = RMS over tau of z = (ln adev_measured - ln adev_model) / s, s from the EDF of each point (or the seed spread of the model band where larger) and the band-centre error. Drift: each segment dead-reckoned from rest (strapdown, Accurate scheme) after removing the log mean.\n");
    let _ = writeln!(
        s,
        "| channel | gap before | gap after | effects | verdict |\n|---|---|---|---|---|"
    );
    for (name, r) in &result.channels {
        let effects: Vec<String> = r
            .effects
            .iter()
            .map(|e| {
                format!(
                    "{} {} ({}): {}{}{}",
                    e.kind,
                    e.effect,
                    crate::effect_text::model_text(e, *name),
                    crate::effect_text::params_text(e, *name),
                    drift_gap_text(e),
                    if e.round == 0 {
                        format!("; {}", crate::effect_text::evidence_text(e))
                    } else {
                        String::new()
                    }
                )
            })
            .collect();
        let _ = writeln!(
            s,
            "| {name} | {:.2} | {:.2} | {} | {} |",
            r.gap_initial,
            r.gap_final,
            if effects.is_empty() {
                "-".into()
            } else {
                effects.join("<br>")
            },
            r.verdict
        );
    }
    s.push_str(&runs_markdown(result));
    if !checks.is_empty() {
        let _ = writeln!(
            s,
            "\n## Held-out logs\n\nGap of logs the diagnosis did not see, with the original model -> the corrected model.\n"
        );
        let _ = writeln!(
            s,
            "| log | {} |",
            noise::Channel::ALL.map(noise::Channel::name).join(" | ")
        );
        let _ = writeln!(s, "|---|{}", "---|".repeat(noise::Channel::ALL.len()));
        for (log, gaps) in checks {
            let cells: Vec<String> = noise::Channel::ALL
                .iter()
                .map(|ch| {
                    gaps.get(ch).map_or("-".into(), |g| {
                        format!("{:.2} -> {:.2}", g.gap_model, g.gap_corrected)
                    })
                })
                .collect();
            let _ = writeln!(s, "| {log} | {} |", cells.join(" | "));
        }
    }
    s.push_str(&drift_check_markdown(result));
    s.push_str(&drift_markdown(result));
    let _ = writeln!(s, "\n## Plots\n");
    for name in result.channels.keys() {
        let _ = writeln!(s, "![{name}](diagnose_{name}.svg)");
    }
    s
}

fn plot(name: noise::Channel, r: &ChannelReport, result: &Diagnosis) -> String {
    let c = &r.curves;
    let unit = logio::Log::unit_of(logio::Quantity::Imu(name));
    let pooled = !result.runs.is_empty();
    let mut series = vec![
        Series::new(
            if pooled {
                "measured, pooled"
            } else {
                "measured"
            },
            c.tau_s.clone(),
            c.adev.clone(),
            "#000000",
        ),
        Series::dashed(
            "model before",
            c.tau_s.clone(),
            c.band_initial.centre.clone(),
            "#d62728",
        ),
        Series::dashed(
            "model after",
            c.tau_s.clone(),
            c.band_final.centre.clone(),
            "#1f77b4",
        ),
    ];
    // Several runs: each run's own curve beside the pooled one.
    const RUN_COLOURS: [&str; 6] = [
        "#8c564b", "#e377c2", "#bcbd22", "#17becf", "#9467bd", "#ff7f0e",
    ];
    for (i, run) in result.runs.iter().enumerate() {
        if let Some(rc) = run.channels.get(&name) {
            series.push(Series {
                markers: false,
                ..Series::new(
                    &format!("run {}", i + 1),
                    rc.tau_s.clone(),
                    rc.adev.clone(),
                    RUN_COLOURS[i % RUN_COLOURS.len()],
                )
            });
        }
    }
    LogLogPlot {
        title: format!(
            "{name}: measured vs model band (gap {:.2} -> {:.2})",
            r.gap_initial, r.gap_final
        ),
        subtitle: String::new(),
        notes: Vec::new(),
        x_label: "tau (s)".into(),
        y_label: format!("Allan deviation ({unit})"),
        series,
        bands: vec![
            Band {
                name: "measured 1-sigma".into(),
                x: c.tau_s.clone(),
                lo: c.adev_lo.clone(),
                hi: c.adev_hi.clone(),
                color: "#7f7f7f".into(),
            },
            Band {
                name: "model before, 95 % of seeds".into(),
                x: c.tau_s.clone(),
                lo: c.band_initial.lo.clone(),
                hi: c.band_initial.hi.clone(),
                color: "#d62728".into(),
            },
            Band {
                name: "model after, 95 % of seeds".into(),
                x: c.tau_s.clone(),
                lo: c.band_final.lo.clone(),
                hi: c.band_final.hi.clone(),
                color: "#1f77b4".into(),
            },
        ],
    }
    .in_spec_sheet_units("Allan deviation", unit)
    .to_svg()
}
