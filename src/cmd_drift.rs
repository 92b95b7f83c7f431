//! `imudrift drift LOG... --model SENSOR`: the drift measured on static logs against the drift
//! the model predicts under one protocol, with intervals and a verdict (docs/drift.md,
//! docs/cli.md for the JSON).

use crate::files;
use crate::log_input::{self, LogArgs};
use crate::output::write_string;
use crate::plot::{Band, LogLogPlot, Series};
use anyhow::{anyhow, Context, Result};
use diagnose::alternatives::Alternative;
use diagnose::document::ProtocolSetting;
use diagnose::drift_check::{
    check_drift_until, simulated_logs_averaged, CheckError, CheckSettings, DriftCheck, Models,
    Verdict,
};
use diagnose::fitted_on::FittedOn;
use diagnose::protocol::{Calibration, Initialisation, Protocol, Quantity};
use diagnose::LogInput;
use request::diagnose::{DriftRequest, ModelUnderTest, ProtocolRequest};
use std::fmt::Write as _;
use std::path::PathBuf;

/// The drift check's simulated logs on a progress bar.
struct Simulated(crate::progress::Progress);

impl diagnose::Observer for Simulated {
    fn simulated(&self, done: usize, _total: usize) {
        self.0.set(done as u64);
    }
}

/// A drift-check error, one about a setting named by the option that sets it.
fn with_flags(e: CheckError) -> anyhow::Error {
    anyhow!(request::diagnose::check_error(&e, &crate::cli::flag))
}

#[derive(clap::Args)]
pub struct Args {
    /// Static logs of one sensor (CSV, gzip CSV, ROS bag or MCAP), pooled
    #[arg(required = true)]
    pub logs: Vec<PathBuf>,
    /// Sensor model (TOML, or a Kalibr / OpenVINS / VINS-Fusion noise file)
    #[arg(long, value_name = "SENSOR.toml")]
    pub model: PathBuf,
    #[command(flatten)]
    pub log_args: LogArgs,
    #[command(flatten)]
    pub earth: crate::log_input::EarthArgs,
    /// Bias calibration before each segment: none, log-mean, or window:TIME (the mean over TIME
    /// before each segment) [default: log-mean]
    #[arg(long, value_name = "HOW", value_parser = calibration)]
    pub calibration: Option<Calibration>,
    /// Initial attitude: perfect, or level:TIME (roll and pitch from the accelerometers over TIME
    /// before each segment) [default: perfect]
    #[arg(long, value_name = "HOW", value_parser = initialisation)]
    pub init: Option<Initialisation>,
    /// Horizons (segment lengths): a comma list of times, e.g. 10,60,10min,1h [default:
    /// 10s,1min,10min,1h]
    #[arg(long, value_delimiter = ',', value_parser = crate::cli::duration_s)]
    pub horizons: Option<Vec<f64>>,
    /// Half-overlapping segments instead of consecutive ones
    #[arg(long)]
    pub overlap: bool,
    /// Simulated experiments for the model's 95 % band (each: one simulated log per measured log)
    /// [default: 40]
    #[arg(long)]
    pub replicates: Option<usize>,
    /// Take the model's levels and run-to-run spreads as exact even when it records the data they
    /// were fitted on (its [fitted_on] table, written by `diagnose`): no parametric bootstrap, no
    /// draw of the spreads
    #[arg(long)]
    pub exact_parameters: bool,
    /// Take the model's structure as certain even when it lists others the fit could not tell
    /// apart from it (its [[alternatives]], written by `diagnose`): no averaging over them
    #[arg(long)]
    pub one_structure: bool,
    /// Master seed of the simulated logs (written into the outputs) [default: 1]
    #[arg(long)]
    pub seed: Option<u64>,
    /// Print one JSON document on stdout (human text on stderr)
    #[arg(long)]
    pub json: bool,
    /// Write drift.json and drift_<quantity>.svg into this directory
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Worker threads (default: all cores); results do not depend on it
    #[arg(long)]
    pub threads: Option<usize>,
}

/// The value parser of `--calibration`: none, log-mean or window:TIME.
pub(crate) fn calibration(text: &str) -> std::result::Result<Calibration, String> {
    Calibration::parse(text, &crate::cli::duration_s)
}

/// The value parser of `--init`: perfect or level:TIME.
pub(crate) fn initialisation(text: &str) -> std::result::Result<Initialisation, String> {
    Initialisation::parse(text, &crate::cli::duration_s)
}

/// The flag of each protocol setting.
fn protocol_flag(setting: ProtocolSetting) -> &'static str {
    match setting {
        ProtocolSetting::Horizons => "--horizons",
        ProtocolSetting::CalibrationWindow => "--calibration window:",
        ProtocolSetting::LevelWindow => "--init level:",
    }
}

/// Refuse horizons and windows the logs' sampling cannot carry (`diagnose::document`), naming
/// the option.
pub(crate) fn check_sampling(protocol: &Protocol, dt_s: f64, samples: usize) -> Result<()> {
    diagnose::document::check_sampling(protocol, dt_s, samples)
        .map_err(|e| anyhow!(e.render(&protocol_flag)))
}

/// The request of the command line (`request::diagnose::DriftRequest`: one set of defaults and
/// checks).
fn request(args: &Args) -> DriftRequest {
    DriftRequest {
        protocol: ProtocolRequest {
            calibration: args.calibration,
            initialisation: args.init,
            horizons_s: args.horizons.clone(),
            overlapping: args.overlap,
            earth: args.earth.earth(),
        },
        replicates: args.replicates,
        seed: args.seed,
    }
}

pub fn run(args: Args) -> Result<()> {
    crate::output::note_inputs(args.logs.iter().chain([&args.model]));
    let _out_lock = args
        .out
        .as_deref()
        .map(crate::output::prepare_dir)
        .transpose()?;
    let settings = request(&args)
        .validate()
        .map_err(crate::cli::request_error)?;
    let pool = crate::cli::pool(args.threads)?;
    pool.install(|| run_inner(&args, settings))
}

/// The model to check against: its structures and the data its levels were fitted on.
struct Structures<'a> {
    model: &'a noise::SensorModel,
    alternatives: &'a [Alternative],
    fitted: Option<&'a FittedOn>,
}

impl Structures<'_> {
    /// The drift check of `inputs`, its simulated logs on a progress bar.
    fn check(&self, inputs: &[LogInput], settings: &CheckSettings) -> Result<DriftCheck> {
        let total = simulated_logs_averaged(
            inputs.len(),
            self.model,
            self.alternatives,
            self.fitted,
            settings.replicates,
        ) as u64;
        let bar = Simulated(crate::progress::Progress::new(
            "simulating the model",
            "logs",
            total,
        ));
        let models = Models::fitted(self.model, self.alternatives, self.fitted);
        let result = check_drift_until(inputs, models, settings, &bar, &crate::output::STOP);
        bar.0.finish();
        result.map_err(with_flags)
    }
}

fn run_inner(args: &Args, settings: CheckSettings) -> Result<()> {
    let protocol = &settings.protocol;
    let model_file = files::read_config(&args.model)?;
    let ModelUnderTest {
        model,
        fitted_on: fitted,
        alternatives,
    } = ModelUnderTest::read(&model_file, args.exact_parameters, args.one_structure)
        .map_err(crate::cli::request_error)?;
    let horizons = &protocol.horizons_s;
    crate::model_notes::print(&model, horizons.iter().copied().reduce(f64::max));
    args.earth
        .note(horizons.iter().copied().fold(0.0, f64::max));
    let logs = args.log_args.read_all(&args.logs)?;
    for log in &logs {
        tell!("{}: {}", log.source, log_input::mapping_text(log));
        crate::plausibility::print(log);
        request::logs::check_imu(log).map_err(crate::cli::request_error)?;
    }
    request::logs::refuse_repeated(&logs).map_err(crate::cli::request_error)?;
    let inputs: Vec<LogInput> = logs
        .iter()
        .map(|l| request::logs::log_input(l, false))
        .collect();
    if let Some(first) = inputs.first() {
        let longest = logs.iter().map(logio::Log::len).max().unwrap_or(0);
        check_sampling(protocol, first.dt_s, longest)?;
    }
    // An output filter in the model must fit the logs' rate.
    if let Some(first) = inputs.first() {
        noise::ImuErrors::check_rate(&model, first.dt_s).map_err(|e| {
            anyhow!(
                "{}: {e}; the logs are at {}",
                args.model.display(),
                crate::fmt::rate(1.0 / first.dt_s)
            )
        })?;
    }
    let started = std::time::Instant::now();
    let structures = Structures {
        model: &model,
        alternatives: &alternatives,
        fitted: fitted.as_ref(),
    };
    let result = structures.check(&inputs, &settings).with_context(|| {
        format!(
            "checking the drift of {} log(s) against {}",
            logs.len(),
            args.model.display()
        )
    })?;
    let elapsed_s = started.elapsed().as_secs_f64();
    let sources: Vec<String> = logs.iter().map(|l| l.source.clone()).collect();
    let human = text(&result, &sources, &args.model, elapsed_s)
        + &parameters_text(&result, args.exact_parameters)
        + &structures_text(&result, args.one_structure);
    let doc =
        diagnose::document::drift_document(&result, &sources, &args.model.display().to_string())
            .context("cannot serialise the drift check")?;
    let doc = serde_json::to_string_pretty(&doc)?;
    crate::output::answer(&human, args.json.then_some(format!("{doc}\n").as_str()))?;
    if let Some(dir) = &args.out {
        let set = crate::output::begin_out_set(dir)?;
        write_string(&dir.join("drift.json"), &doc)?;
        write_string(&dir.join("drift.csv"), &csv(&result))?;
        for q in Quantity::ALL {
            if let Some(svg) = plot(&result, q) {
                write_string(&dir.join(format!("drift_{}.svg", q.name())), &svg)?;
            }
        }
        set.commit()?;
        tell!(
            "wrote drift.csv, drift.json and drift_<quantity>.svg to {}",
            dir.display()
        );
    }
    Ok(())
}

fn text(r: &DriftCheck, logs: &[String], model: &std::path::Path, elapsed_s: f64) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "drift of {} log(s) against {} ({} simulated experiments, seed {}, {:.1} s)\nprotocol: {}",
        logs.len(),
        model.display(),
        r.replicates,
        r.seed,
        elapsed_s,
        r.protocol_text
    );
    let _ = writeln!(
        s,
        "{:>7} {:>5}  {:<20} {:>26} {:>30}  {:>6}  verdict",
        "horizon",
        "segs",
        "quantity",
        "measured rms [95 % interval]",
        "model rms [95 % band]",
        "ratio"
    );
    let mut causes = Vec::new();
    let mut differ = Vec::new();
    for h in &r.horizons {
        for q in Quantity::ALL {
            let c = &h.channels[q.name()];
            let v = |x: f64| crate::fmt::quantity_value(q.name(), x);
            let measured = c
                .measured
                .map(|m| format!("{} [{}, {}]", v(m.rms), v(m.rms_lo), v(m.rms_hi)))
                .unwrap_or_else(|| "-".into());
            let model = c
                .model
                .map(|m| format!("{} [{}, {}]", v(m.rms), v(m.band_lo), v(m.band_hi)))
                .unwrap_or_else(|| "-".into());
            let ratio = c.ratio.map_or("-".into(), |x| crate::fmt::sig(x, 3));
            let verdict = match (c.verdict, &c.note) {
                (Verdict::NotInformed, Some(n)) => format!("not informed ({n})"),
                (v, _) => v.name().to_string(),
            };
            if let Some(b) = c.between_logs.filter(|b| b.runs_differ) {
                differ.push(format!(
                    "{} {}: sd of ln(rms) over the logs {} against the model's {} (p = {})",
                    crate::fmt::time(h.t_s),
                    q.name(),
                    crate::fmt::sig(b.sd_ln_rms, 3),
                    crate::fmt::sig(b.model_sd_ln_rms, 3),
                    crate::fmt::sig(b.p_value, 2)
                ));
            }
            if let Some(cause) = &c.likely_cause {
                causes.push(format!("{} {}: {cause}", crate::fmt::time(h.t_s), q.name()));
            }
            let _ = writeln!(
                s,
                "{:>7} {:>5}  {:<20} {:>26} {:>30}  {:>6}  {verdict}",
                crate::fmt::time(h.t_s),
                h.segments,
                q.name(),
                measured,
                model,
                ratio
            );
        }
    }
    if let Some(j) = &r.joint {
        let _ = writeln!(
            s,
            "all {} cells together: {} outside the band (the model's own experiments: {} on average, \
             {} or more in {} % of them, none in {} %); most extreme: {} {} at |z| = {}; p = {}: {} (docs/drift.md)",
            j.cells,
            j.outside,
            crate::fmt::sig(j.model_outside_mean, 2),
            j.outside,
            crate::fmt::sig(100.0 * j.model_outside_at_least, 2),
            crate::fmt::sig(100.0 * j.model_all_inside, 2),
            crate::fmt::time(j.worst.t_s),
            j.worst.quantity,
            crate::fmt::sig(j.worst.abs_z, 3),
            crate::fmt::sig(j.p_value, 2),
            if j.consistent {
                "as many and as far out as a right model's misses"
            } else {
                "more, or further out, than a right model's misses"
            }
        );
    }
    if !differ.is_empty() {
        let _ = writeln!(
            s,
            "cells whose logs differ among themselves beyond the model's randomness, each tested \
             at 5 % (docs/drift.md):"
        );
        for d in differ {
            let _ = writeln!(s, "  {d}");
        }
    }
    if let Some(b) = &r.between_logs_joint {
        let _ = writeln!(
            s,
            "the logs among themselves, all {} cells together: {} flagged (the model's own \
             experiments: {} or more in {} % of them); p = {}: {}",
            b.cells,
            b.flagged,
            b.flagged,
            crate::fmt::sig(100.0 * b.model_flagged_at_least, 2),
            crate::fmt::sig(b.p_value, 2),
            if b.runs_differ {
                "the runs differ beyond the model's randomness (a run-to-run variation it does not hold)"
            } else {
                "as far apart as the runs of a right model"
            }
        );
    }
    if !causes.is_empty() {
        let _ = writeln!(s, "likely causes where the measurement leaves the band:");
        for c in causes {
            let _ = writeln!(s, "  {c}");
        }
    }
    s
}

/// How the model's levels entered the band: exact, or drawn (each level's spread).
/// The structures the band averaged over (none: nothing).
fn structures_text(r: &DriftCheck, one_flag: bool) -> String {
    if r.structures.is_empty() {
        return if one_flag {
            "model structure: taken as certain (--one-structure)\n".into()
        } else {
            String::new()
        };
    }
    let mut s = String::from(
        "model structure: the band averages over the structures the fit could not tell apart (the model's [[alternatives]], BIC weights; docs/drift.md):\n",
    );
    for st in &r.structures {
        let _ = writeln!(
            s,
            "  {:>5.1} %  {:>3} experiment{}  {}",
            100.0 * st.weight,
            st.replicates,
            if st.replicates == 1 { " " } else { "s" },
            st.label
        );
    }
    s
}

fn parameters_text(r: &DriftCheck, exact_flag: bool) -> String {
    let Some(p) = &r.parameters else {
        return format!(
            "model levels: taken as exact ({}); the band holds the spread of the data only\n",
            if exact_flag {
                "--exact-parameters"
            } else {
                "the model records no data it was fitted on"
            }
        );
    };
    let f = &p.fitted_on;
    let mut s = format!(
        "model levels: drawn per simulated experiment by a parametric bootstrap on data like the {} log(s) ({} in all, at {}) they were fitted on (docs/drift.md); 95 % of the draws:\n",
        f.samples.len(),
        crate::fmt::time(f.duration_s()),
        crate::fmt::rate(1.0 / f.sample_interval_s)
    );
    for (ch, levels) in &p.levels {
        // Spec-sheet units (deg/sqrt(h), deg/h, ug/sqrt(Hz) ...) as `diagnose` writes the same
        // levels; the JSON keeps SI.
        let channel = noise::Channel::from_name(ch);
        let text = |key: &str, v: &[f64]| match channel {
            Some(c) => diagnose::effect_text::values_text(key, c, v),
            None => v
                .iter()
                .map(|&x| crate::fmt::sig(x, 3))
                .collect::<Vec<_>>()
                .join(", "),
        };
        let parts: Vec<String> = levels
            .iter()
            .map(|l| {
                let model = text(l.parameter, &[l.model]);
                if l.informed {
                    let range = text(l.parameter, &[l.p2_5, l.p97_5]);
                    format!("{} {} = {model}, drawn [{range}]", l.effect, l.parameter)
                } else {
                    format!(
                        "{} {} = {model} (not informed: kept)",
                        l.effect, l.parameter
                    )
                }
            })
            .collect();
        let _ = writeln!(s, "  {ch}: {}", parts.join("; "));
    }
    if !p.run_to_run.is_empty() {
        let _ = writeln!(
            s,
            "run-to-run spreads (sd of ln level between power-ons): drawn per simulated experiment from their estimate on the {} runs (docs/drift.md, \"The spread's own uncertainty\"); 95 % of the draws:",
            f.samples.len()
        );
        for d in &p.run_to_run {
            let effects: Vec<&str> = d.effects.iter().map(|e| e.name()).collect();
            let _ = writeln!(
                s,
                "  {} {}: {} as fitted, drawn [{}, {}], 0 in {:.0} % of the experiments",
                d.channel.name(),
                effects.join(" + "),
                crate::fmt::sig(d.model, 3),
                crate::fmt::sig(d.p2_5, 3),
                crate::fmt::sig(d.p97_5, 3),
                100.0 * d.share_zero
            );
        }
    }
    s
}

/// `drift.csv`: the table of the text answer, one row per horizon and quantity, SI units (rad, m,
/// m/s, s), empty fields where a quantity is not informed; the JSON's names
/// (`horizons[].channels{q: {measured{..}, model{..}, verdict, ratio, note, likely_cause}}`).
fn csv(r: &DriftCheck) -> String {
    let mut s = String::from(
        "t_s,segments,quantity,measured_mean,measured_mean_lo,measured_mean_hi,measured_p50,measured_p95,\
         measured_rms,measured_rms_lo,measured_rms_hi,measured_n_eff,model_mean,model_p50,model_p95,\
         model_rms,model_band_lo,model_band_hi,ratio,verdict,note,likely_cause\n",
    );
    let num = |v: Option<f64>| {
        v.filter(|x| x.is_finite())
            .map_or(String::new(), |x| format!("{x:e}"))
    };
    for h in &r.horizons {
        for q in Quantity::ALL {
            let c = &h.channels[q.name()];
            let m = c.measured.as_ref();
            let b = c.model.as_ref();
            let fields = [
                format!("{:e}", h.t_s),
                h.segments.to_string(),
                q.name().to_string(),
                num(m.map(|m| m.mean)),
                num(m.map(|m| m.mean_lo)),
                num(m.map(|m| m.mean_hi)),
                num(m.map(|m| m.p50)),
                num(m.map(|m| m.p95)),
                num(m.map(|m| m.rms)),
                num(m.map(|m| m.rms_lo)),
                num(m.map(|m| m.rms_hi)),
                num(m.map(|m| m.n_eff)),
                num(b.map(|b| b.mean)),
                num(b.map(|b| b.p50)),
                num(b.map(|b| b.p95)),
                num(b.map(|b| b.rms)),
                num(b.map(|b| b.band_lo)),
                num(b.map(|b| b.band_hi)),
                num(c.ratio),
                c.verdict.name().to_string(),
                crate::fmt::csv_text(c.note.as_deref().unwrap_or("")),
                crate::fmt::csv_text(c.likely_cause.as_deref().unwrap_or("")),
            ];
            let _ = writeln!(s, "{}", fields.join(","));
        }
    }
    s
}

/// Drift against horizon: measured RMS with its interval over the model's 95 % band.
fn plot(r: &DriftCheck, q: Quantity) -> Option<String> {
    let rows: Vec<_> = r
        .horizons
        .iter()
        .filter_map(|h| {
            let c = &h.channels[q.name()];
            Some((h.t_s, c.measured?, c.model?))
        })
        .collect();
    if rows.is_empty() {
        return None;
    }
    let (scale, unit) = if q.name().ends_with("_rad") {
        (180.0 / std::f64::consts::PI, "deg")
    } else if q.name().ends_with("_mps") {
        (1.0, "m/s")
    } else {
        (1.0, "m")
    };
    let x: Vec<f64> = rows.iter().map(|r| r.0).collect();
    let col = |f: &dyn Fn(
        &(
            f64,
            diagnose::drift_check::Measured,
            diagnose::drift_check::Model,
        ),
    ) -> f64| { rows.iter().map(|r| f(r) * scale).collect::<Vec<f64>>() };
    Some(
        LogLogPlot {
            title: format!(
                "{}: measured vs model drift",
                crate::fmt::quantity_label(q.name())
            ),
            subtitle: r.protocol_text.clone(),
            notes: Vec::new(),
            x_label: "horizon (s)".into(),
            y_label: format!("RMS error ({unit})"),
            series: vec![
                Series::new("measured RMS", x.clone(), col(&|r| r.1.rms), "#000000"),
                Series::dashed("model RMS", x.clone(), col(&|r| r.2.rms), "#1f77b4"),
            ],
            bands: vec![
                Band {
                    name: "measured 95 % interval".into(),
                    x: x.clone(),
                    lo: col(&|r| r.1.rms_lo),
                    hi: col(&|r| r.1.rms_hi),
                    color: "#7f7f7f".into(),
                },
                Band {
                    name: "model 95 % band".into(),
                    x,
                    lo: col(&|r| r.2.band_lo),
                    hi: col(&|r| r.2.band_hi),
                    color: "#1f77b4".into(),
                },
            ],
        }
        .to_svg(),
    )
}
