//! `imudrift allan LOG.csv`: Allan deviations of each channel of a log, with confidence
//! intervals (Greenhall EDF, chi-squared bounds) and the fitted IEEE 952 noise terms.
//! Prints a table per channel; `--json` prints one JSON document on stdout (tables go to
//! stderr); `--out DIR` writes allan.csv, allan.json and one SVG plot per channel.

use crate::log_input::{self, LogArgs};
use crate::output;
use crate::plot::{Band, LogLogPlot, Series, PALETTE};
use allan::fit::{Fit, SubrangeSpread, TERM_NAMES};
use allan::sheet::{Reading, SheetReadings, TermStatus};
use allan::{AllanPoint, Estimator, Options, TauGrid};
use anyhow::{bail, Result};
use logio::{Log, Quantity};
use noise::noise_file::AxisValue;
use rayon::prelude::*;
use request::error::LeaveOut;
use serde_json::{json, Map, Value};
use std::fmt::Write as _;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Log file: CSV or gzip-compressed CSV with a header row (`#` lines are comments), a ROS 1
    /// bag or a ROS 2 MCAP file (sensor_msgs/Imu)
    pub log: PathBuf,
    #[command(flatten)]
    pub log_args: LogArgs,
    /// Estimator: adev (non-overlapping, Woodman eq 19), oadev, mdev, hdev, ohdev, totdev, mtotdev,
    /// htotdev, theo1, theoh (NIST SP 1065 §5.2; the time-error metrics mtie, tierms and the gap-
    /// tolerant gradev are in Python's `imudrift.allantools`)
    #[arg(long, default_value = "oadev", value_parser = crate::cli::named(Estimator::ALL, Estimator::name))]
    pub estimator: Estimator,
    /// Tau grid: octave, decade, all, N/decade, or a comma list of averaging factors m
    #[arg(long, default_value = "octave", value_parser = crate::cli::grid)]
    pub grid: crate::cli::GridArg,
    /// Go on past Stable32's largest averaging time (N/5 for adev and hdev, N/4 for oadev, mdev
    /// and ohdev, N/2 for totdev) to the last with 2 or more terms, as allantools does (Python:
    /// `stable32_stop=False`); those points have few degrees of freedom and wide intervals
    #[arg(long)]
    pub no_stable32_stop: bool,
    /// Channels to analyse (default: every channel except temp)
    #[arg(long, value_delimiter = ',')]
    pub channels: Vec<String>,
    /// Confidence level of the intervals: 1sigma (68.27 %), a fraction (0.95) or a percentage (95%)
    #[arg(long, default_value = "1sigma", value_parser = crate::cli::confidence)]
    pub confidence: f64,
    /// EDF method: greenhall (noise identified per tau), simple (SP 1065 Table 5), none
    #[arg(long, value_enum, default_value = "greenhall")]
    pub edf: crate::cli::EdfArg,
    /// Print one JSON document on stdout (human text on stderr)
    #[arg(long)]
    pub json: bool,
    /// Write allan.csv, allan.json and `allan_<channel>.svg` into this directory
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Worker threads (default: all cores); results do not depend on it
    #[arg(long)]
    pub threads: Option<usize>,
    /// Print the time spent in each stage on stderr
    #[arg(long)]
    pub timing: bool,
    #[command(flatten)]
    pub noise_file: crate::noise_out::NoiseFileArgs,
}

/// Reduced chi-square above which the IEEE 952 fit is reported as not describing the curve.
const FIT_CHI2_WARNING: f64 = 25.0;

/// A resolved coefficient whose refits on parts of the curve leave value +- this many of its
/// standard errors depends on the taus fitted more than its +- says: its conclusion changes. Two
/// sigma: the refits share three quarters of their points with the whole fit, so on a curve the
/// five terms describe they stay well inside it (a leave-one-block-out refit of correlated
/// points moves a coefficient by less than its own standard error, Efron & Tibshirani 1993
/// §11.5); beyond it the misfit, not the scatter, moves the value.
const SPREAD_SIGMAS: f64 = 2.0;

/// The term labels of the text, in fit order.
const TERM_LETTERS: [&str; 5] = ["Q", "N", "B", "K", "R"];

/// Where the fit misses the curve most, counted in the point's own standard errors (the z that
/// makes the chi-square, ln(dev / fit) sqrt(edf / 2), SP 1065 §5.2): that point's relative
/// departure measured / fitted - 1 and its tau.
fn largest_misfit(r: &ChannelResult, f: &Fit) -> Option<(f64, f64)> {
    r.points
        .iter()
        .filter(|p| p.dev.is_finite() && p.dev > 0.0)
        .map(|p| {
            let ratio = p.dev / f.model_dev(p.tau_s);
            let z = ratio.ln().abs() * (allan::fit::capped_edf(p) / 2.0).sqrt();
            (z, ratio - 1.0, p.tau_s)
        })
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, d, t)| (d, t))
}

/// Each resolved term's refit range in spec-sheet units ("N 2.27-2.33 deg/sqrt(h)") and whether
/// it leaves value +- [`SPREAD_SIGMAS`] sigma or lies wholly on one side of the value.
fn spread_parts(r: &ChannelResult) -> Vec<(String, bool)> {
    let (Some(f), Some(status), Some(spread)) = (&r.fit, &r.terms, &r.spread) else {
        return Vec::new();
    };
    if spread.refits == 0 {
        return Vec::new();
    }
    let units = crate::fmt::allan_units(r.unit);
    f.terms()
        .iter()
        .enumerate()
        .filter_map(|(j, t)| {
            let t = t.filter(|_| status[j].resolved)?;
            let (scale, shown) = (&units[j + 1].0, &units[j + 1].1);
            let (lo, hi) = (spread.lo[j], spread.hi[j]);
            // Beyond +- 2 sigma, or every refit on one side of the whole fit's value (no three
            // quarters of the curve give it: the value rests on the misfit's balance).
            let beyond = lo < t.value - SPREAD_SIGMAS * t.sigma
                || hi > t.value + SPREAD_SIGMAS * t.sigma
                || t.value < lo
                || t.value > hi;
            Some((
                format!(
                    "{} {}-{} {shown} ({} +- {} printed)",
                    TERM_LETTERS[j],
                    crate::fmt::sig(lo * scale, 3),
                    crate::fmt::sig(hi * scale, 3),
                    crate::fmt::sig(t.value * scale, 4),
                    crate::fmt::sig(t.sigma * scale, 2),
                ),
                beyond,
            ))
        })
        .collect()
}

/// What the misfit of a fit the five terms cannot describe means for the numbers printed: the
/// largest departure of the fitted curve from the measured one, and each resolved coefficient's
/// range when refitted without each quarter of the taus in turn. None where the fit describes
/// the curve (reduced chi-square at most [`FIT_CHI2_WARNING`]).
fn misfit_note(r: &ChannelResult) -> Option<String> {
    let f = r.fit.as_ref()?;
    if f.reduced_chi2.is_nan() || f.reduced_chi2 <= FIT_CHI2_WARNING {
        return None;
    }
    let (worst, at) = largest_misfit(r, f)?;
    let parts: Vec<String> = spread_parts(r).into_iter().map(|(t, _)| t).collect();
    Some(format!(
        "the five IEEE 952 terms miss the curve (reduced chi-square {:.0}, a five-term curve gives below {:.0}: a filter, a sinusoid or a Gauss-Markov process shapes it, `imudrift diagnose` names them; most of its own standard errors at tau = {}, by {:+.1} %); refitted without each quarter of the taus in turn: {}",
        f.reduced_chi2,
        FIT_CHI2_WARNING,
        crate::fmt::time(at),
        100.0 * worst,
        if parts.is_empty() {
            "no resolved term".to_string()
        } else {
            parts.join(", ")
        }
    ))
}

/// What makes a channel's result weak though still meaningful (printed and in the JSON): a last
/// point with under 2 degrees of freedom, and a fit that does not describe the curve where that
/// changes a printed coefficient (a resolved term whose refits on parts of the curve leave its
/// value +- 2 sigma; elsewhere the misfit is a note, [`misfit_note`], not a warning).
fn warnings(r: &ChannelResult) -> Vec<String> {
    let mut w = Vec::new();
    if let Some(last) = r.points.last() {
        if last.edf < 2.0 {
            w.push(format!(
                "the longest averaging time ({}) has {} equivalent degrees of freedom (< 2): its deviation is uncertain by more than a factor of 2",
                crate::fmt::time(last.tau_s),
                crate::fmt::sig(last.edf, 2)
            ));
        }
    }
    if let Some(f) = &r.fit {
        // The Allan points are correlated and the flicker model is a finite sum, so even logs made
        // from the five-term model give reduced chi-squares up to about 9 (30 channels of 2 h MTx
        // logs, seeds 2-6); only a fit far beyond that is looked at.
        let moved: Vec<String> = spread_parts(r)
            .into_iter()
            .filter(|(_, beyond)| *beyond)
            .map(|(t, _)| t)
            .collect();
        if f.reduced_chi2 > FIT_CHI2_WARNING && !moved.is_empty() {
            w.push(format!(
                "the IEEE 952 fit does not describe the curve (reduced chi-square {:.1}, expected below {:.1}) and the value of {} depends on the taus fitted more than its +- says (a refit beyond {SPREAD_SIGMAS} sigma, or every refit on one side of it): refitted without each quarter of the taus in turn, {}; quote that range, not the +-; `imudrift diagnose` names the effects outside the five terms",
                f.reduced_chi2,
                FIT_CHI2_WARNING,
                if moved.len() == 1 { "this term" } else { "these terms" },
                moved.join(", ")
            ));
        }
    }
    w
}

/// The analysis of one channel.
pub struct ChannelResult {
    pub quantity: Quantity,
    pub name: String,
    pub unit: &'static str,
    pub points: Vec<AllanPoint>,
    /// The IEEE 952 fit: only for Allan-variance estimators (adev, oadev, totdev), whose
    /// per-term closed forms the model uses.
    pub fit: Option<Fit>,
    /// The spec-sheet readings (with the fit only).
    pub sheet: Option<SheetReadings>,
    /// Which fitted terms are resolved, and each one's bound (with the fit only).
    pub terms: Option<[TermStatus; 5]>,
    /// The fit's coefficients refitted without each quarter of the taus (with the fit only).
    pub spread: Option<SubrangeSpread>,
}

pub fn run(args: Args) -> Result<()> {
    args.noise_file.check()?;
    crate::output::note_inputs([&args.log]);
    args.noise_file.refuse_inputs()?;
    let _out_lock = args
        .out
        .as_deref()
        .map(crate::output::prepare_dir)
        .transpose()?;
    let est = args.estimator;
    let grid = args.grid.grid.clone();
    let edf = args.edf.into();
    if !(args.confidence > 0.0 && args.confidence < 1.0) {
        bail!(
            "--confidence {}: expected a level between 0 and 1",
            args.confidence
        );
    }
    let opts = Options {
        edf,
        confidence: args.confidence,
        stable32_stop: !args.no_stable32_stop,
        ..Options::default()
    };
    let pool = crate::cli::pool(args.threads)?;
    pool.install(|| run_inner(&args, est, &grid, &opts))
}

fn run_inner(args: &Args, est: Estimator, grid: &TauGrid, opts: &Options) -> Result<()> {
    let clock = std::time::Instant::now();
    let stage = |what: &str| {
        if args.timing {
            tell!(
                "timing: {what} done at {:.1} ms",
                clock.elapsed().as_secs_f64() * 1e3
            );
        }
    };
    let log = args.log_args.read(&args.log)?;
    tell!("{}: {}", log.source, log_input::mapping_text(&log));
    crate::plausibility::print(&log);
    stage("read + parse");
    let quantities = channel_quantities(args, &log)?;
    request::logs::refuse_constant(&log, quantities.iter().copied(), LeaveOut::Channel)
        .map_err(crate::cli::request_error)?;
    // The channels are analysed by value: each one's phase is computed in its own buffer.
    let samples = log.len();
    let mut log = log;
    let work: Vec<(Quantity, Vec<f64>)> = quantities
        .into_iter()
        .filter_map(|q| Some((q, log.take(q)?)))
        .collect();
    let dt_s = log.dt_s();
    // A fitted term is claimed at a family-wise false-claim rate of 1 % per log: over the five
    // terms of every channel analysed (docs/allan.md "Resolved terms"). The thresholds come from
    // the shipped table where it covers the analysis (the default ones); elsewhere the null logs
    // are simulated once (they depend only on the log's length and interval), before the channels.
    let mut opts = opts.clone();
    opts.claims.family = 5 * work.len().max(1);
    let opts = &opts;
    if matches!(
        est,
        Estimator::NonOverlapping | Estimator::Overlapping | Estimator::Total
    ) && allan::null::tabulated_thresholds(samples, est, grid, opts).is_none()
    {
        let progress = crate::progress::Progress::new(
            "null logs for the resolved-term thresholds (no table for this grid and options)",
            "logs",
            opts.claims.replicates as u64,
        );
        allan::null::null_thresholds_with(samples, dt_s, est, grid, opts, &|done, _| {
            progress.set(done as u64)
        });
        progress.finish();
        stage("null simulation");
    }
    let results: Vec<ChannelResult> = work
        .into_par_iter()
        .map(|(q, data)| analyse(data, q, dt_s, est, grid, opts, &stage))
        .collect();
    stage("all channels");
    check_usable(&log, samples, &results)?;
    let table = tables(&log, samples, &results, est, opts.confidence);
    let doc = json_document(&log, samples, &results, est, &args.grid.text, opts);
    let json = format!("{}\n", serde_json::to_string_pretty(&doc)?);
    output::answer(&table, args.json.then_some(json.as_str()))?;
    stage("printed");
    let per_channel = noise::ImuChannels::from_fn(|c| {
        let r = results.iter().find(|r| r.quantity == Quantity::Imu(c))?;
        noise_file_values(r)
    });
    // --kalibr and the --out files are one set: all of them, or none if one cannot be written.
    let set = output::begin_set();
    args.noise_file.write(
        &per_channel,
        log.rate_hz,
        &format!("`imudrift allan` of {}", log.source),
        log.topic.as_deref(),
    )?;
    if let Some(dir) = &args.out {
        write_files(dir, &log, &results, est, &doc)?;
    }
    set.commit()?;
    if let Some(dir) = &args.out {
        stage("files written");
        tell!(
            "wrote allan.csv, allan.json and {} to {}",
            svg_names(results.iter().map(|r| r.name.as_str())).join(", "),
            dir.display()
        );
    }
    Ok(())
}

/// The channels to analyse: `--channels` (each must be in the log), else every channel but the
/// temperature, in log order.
fn channel_quantities(args: &Args, log: &Log) -> Result<Vec<Quantity>> {
    if args.channels.is_empty() {
        return Ok(log
            .order
            .iter()
            .copied()
            .filter(|q| *q != Quantity::Temperature)
            .collect());
    }
    args.channels
        .iter()
        .map(|c| {
            Quantity::of_channel(c)
                .filter(|q| log.order.contains(q))
                .ok_or_else(|| {
                    anyhow::anyhow!(
                        "--channels: {}: no channel {c:?} (channels: {})",
                        log.source,
                        log.order_names().join(", ")
                    )
                })
        })
        .collect()
}

/// Refuse a channel's curve with too few usable averaging times (`request::allan::check_curve`,
/// the rule `imudrift.allan` applies too).
fn check_usable(log: &Log, samples: usize, results: &[ChannelResult]) -> Result<()> {
    for r in results {
        request::allan::check_curve(&log.source, Some(&r.name), samples, &r.points)
            .map_err(crate::cli::request_error)?;
    }
    Ok(())
}

/// `--out DIR`: allan.csv, allan.json and one SVG per channel (into the caller's set).
fn write_files(
    dir: &std::path::Path,
    log: &Log,
    results: &[ChannelResult],
    est: Estimator,
    doc: &Value,
) -> Result<()> {
    output::ensure_dir(dir)?;
    output::write_string(&dir.join("allan.csv"), &csv(results))?;
    output::write_string(&dir.join("allan.json"), &serde_json::to_string_pretty(doc)?)?;
    let files = svg_names(results.iter().map(|r| r.name.as_str()));
    for (r, name) in results.iter().zip(&files) {
        output::write_string(&dir.join(name), &plot(r, est, &log.source).to_svg())?;
    }
    Ok(())
}

/// Deviation curve, intervals and fit of one channel ([`allan::analyse_rate`]).
pub fn analyse(
    data: Vec<f64>,
    quantity: Quantity,
    dt_s: f64,
    est: Estimator,
    grid: &TauGrid,
    opts: &Options,
    stage: &(dyn Fn(&str) + Sync),
) -> ChannelResult {
    let allan::Analysis {
        points,
        fit,
        sheet,
        terms,
    } = allan::analyse_rate(data, dt_s, est, grid, opts, &|s| {
        let name = quantity.channel();
        stage(&format!("{name}: {s}"))
    });
    let spread = fit
        .as_ref()
        .map(|f| allan::fit::subrange_spread(&points, f));
    ChannelResult {
        quantity,
        name: quantity.channel().to_string(),
        unit: Log::unit_of(quantity),
        points,
        fit,
        sheet,
        terms,
        spread,
    }
}

fn tables(
    log: &Log,
    samples: usize,
    results: &[ChannelResult],
    est: Estimator,
    confidence: f64,
) -> String {
    let level = crate::fmt::confidence(confidence);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{}: {} samples at {} ({}), {} with {level} bounds",
        log.source,
        samples,
        crate::fmt::rate(log.rate_hz),
        crate::fmt::time(samples as f64 / log.rate_hz),
        est.name()
    );
    for r in results {
        let units = crate::fmt::allan_units(r.unit);
        let _ = writeln!(
            s,
            "\nchannel {} (deviation in {}; JSON and CSV in {})",
            r.name, units[0].1, r.unit
        );
        points_table(&mut s, r, &units);
        fit_lines(&mut s, r, est, &units, &level);
    }
    s
}

/// One channel's deviation at every tau with its interval, in spec-sheet units (`units[0]`).
fn points_table(s: &mut String, r: &ChannelResult, units: &[(f64, String); 6]) {
    let dev_scale = &units[0].0;
    let _ = writeln!(
        s,
        "{:>10} {:>9} {:>10} {:>3} {:>9} {:>11} {:>11} {:>11}",
        "tau", "m", "terms", "a", "edf", "dev_lo", "dev", "dev_hi"
    );
    let d = |v: f64| crate::fmt::sig(v * dev_scale, 4);
    let mut few_bins = false;
    for p in &r.points {
        // Woodman §5.1: fewer than 9 non-overlapping bins; such a point is shown and fitted,
        // but no reading (line, minimum) is taken from it.
        let flag = if p.woodman_ok() {
            ""
        } else {
            few_bins = true;
            " <9 bins"
        };
        let _ = writeln!(
            s,
            "{:>10} {:>9} {:>10} {:>3} {:>9} {:>11} {:>11} {:>11}{flag}",
            crate::fmt::time(p.tau_s),
            p.m,
            p.n_terms,
            p.alpha,
            crate::fmt::sig(p.edf, 3),
            d(p.lo),
            d(p.dev),
            d(p.hi)
        );
    }
    if few_bins {
        let _ = writeln!(
            s,
            "<9 bins: fewer than 9 non-overlapping averages of tau fit in the log (Woodman TR-696 §5.1); the point is shown and fitted, but no reading is taken from it"
        );
    }
}

/// One channel's IEEE 952 fit (each resolved coefficient in its spec-sheet unit and in SI, the
/// others as the bound the curve sets), its warnings and the spec-sheet readings; only the
/// Allan-variance estimators have one.
fn fit_lines(
    s: &mut String,
    r: &ChannelResult,
    est: Estimator,
    units: &[(f64, String); 6],
    level: &str,
) {
    let (Some(f), Some(status), Some(sheet)) = (&r.fit, &r.terms, &r.sheet) else {
        let _ = writeln!(
            s,
            "IEEE 952 fit: not done for {} (the model's closed forms are those of the Allan variance)",
            est.name()
        );
        return;
    };
    let unit = r.unit;
    let _ = writeln!(
        s,
        "IEEE 952 fit (weighted NNLS in ln avar, 1-sigma; reduced chi2 {:.2}, model error {:.1}%; a term is resolved when its statistic exceeds what logs of the null model give (1 % false claims per log); else it is given as the bound the curve sets):",
        f.reduced_chi2,
        100.0 * f.model_error
    );
    let si_units = [
        format!("{unit}*s"),
        format!("{unit}*sqrt(s)"),
        unit.to_string(),
        format!("{unit}/sqrt(s)"),
        format!("{unit}/s"),
    ];
    let labels = [
        "Q quantisation",
        "N white (ARW/VRW)",
        "B bias instability",
        "K rate random walk",
        "R rate ramp",
    ];
    for (i, ((t, label), st)) in f.terms().iter().zip(labels).zip(status).enumerate() {
        let (scale, shown) = (&units[i + 1].0, &units[i + 1].1);
        let alt = if i == 1 {
            crate::fmt::noise_density_alt(unit, t.map_or(st.bound, |t| t.value))
                .map_or(String::new(), |a| format!(" (= {a})"))
        } else {
            String::new()
        };
        // B is the fit's flicker coefficient, not the curve's minimum: its own Allan plateau is
        // 0.664 B (docs/model.md §2), which the readings' minimum lies above.
        let plateau = match t {
            Some(t) if i == 2 && st.resolved => format!(
                "; coefficient of the fit, its plateau 0.664 B = {} {shown}",
                crate::fmt::sig(t.value * allan::fit::BI_PLATEAU_FACTOR * scale, 4)
            ),
            _ => String::new(),
        };
        let _ = match t {
            Some(t) if st.resolved => writeln!(
                s,
                "  {label:<20} {} +- {} {shown}{alt}   ({:.4e} {}){plateau}",
                crate::fmt::sig(t.value * scale, 4),
                crate::fmt::sig(t.sigma * scale, 2),
                t.value,
                si_units[i]
            ),
            // A fitted value whose standard error is over ten times itself says nothing: only
            // the bound is shown (the "R = 0.018 +- 2299848 deg/h^2").
            Some(t) if t.sigma > 10.0 * t.value.abs() => writeln!(
                s,
                "  {label:<20} not resolved: < {} {shown} (the fit does not determine it)",
                crate::fmt::sig(st.bound * scale, 3),
            ),
            Some(t) => writeln!(
                s,
                "  {label:<20} not resolved: < {} {shown} (fitted {} +- {})",
                crate::fmt::sig(st.bound * scale, 3),
                crate::fmt::sig(t.value * scale, 2),
                crate::fmt::sig(t.sigma * scale, 2),
            ),
            None => writeln!(
                s,
                "  {label:<20} not fitted: < {} {shown}",
                crate::fmt::sig(st.bound * scale, 3)
            ),
        };
    }
    let warned = warnings(r);
    for w in &warned {
        let _ = writeln!(s, "warning: {}: {w}", r.name);
    }
    if let Some(note) = misfit_note(r) {
        // With a warning on a coefficient, the note's figures are in it already.
        if !warned
            .iter()
            .any(|w| w.contains("does not describe the curve"))
        {
            let _ = writeln!(s, "note: {}: {note}", r.name);
        }
    }
    reading_lines(s, unit, sheet, units, level);
    let _ = write!(s, "{}", fit_and_readings(r, f, status, sheet, units));
}

/// Why the fit's N and B and the readings differ: they are different quantities. Printed where
/// the fit resolves N (or B) and the ARW line (or the minimum) reads a value or bound beside it.
fn fit_and_readings(
    r: &ChannelResult,
    f: &Fit,
    status: &[TermStatus; 5],
    sheet: &SheetReadings,
    units: &[(f64, String); 6],
) -> String {
    let mut s = String::new();
    let arw = &sheet.arw;
    if let (Some(n), Some(line)) = (f.n.filter(|_| status[1].resolved), arw.value) {
        // The share of the fitted curve that is not white noise over the line's taus: what the
        // line reads as white noise and the fit gives to the other terms.
        let other = r
            .points
            .iter()
            .filter(|p| p.tau_s >= arw.tau_s[0] && p.tau_s <= arw.tau_s[1])
            .map(|p| 1.0 - (f.term_dev(1, p.tau_s).unwrap_or(0.0) / f.model_dev(p.tau_s)).powi(2))
            .fold(0.0f64, f64::max);
        let _ = writeln!(
            s,
            "  fit N vs ARW line: different quantities, {} vs {} {} ({:+.1} %): the line reads the curve over tau = {} .. {} as white noise alone and leaves out tau < 10 samples (the sensor's filter); the fit's N is the white-noise term of all five fitted to every tau together (the other terms make up to {} % of the fitted curve over the line's taus); the noise file (--kalibr) takes the line",
            crate::fmt::sig(n.value * units[2].0, 4),
            crate::fmt::sig(line * units[2].0, 4),
            units[2].1,
            100.0 * (line / n.value - 1.0),
            crate::fmt::time(arw.tau_s[0]),
            crate::fmt::time(arw.tau_s[1]),
            crate::fmt::sig(100.0 * other, 2),
        );
    }
    if let Some(b) = f.b.filter(|_| status[2].resolved) {
        let min = &sheet.bi_min;
        let plateau = b.value * allan::fit::BI_PLATEAU_FACTOR;
        let (verb, v) = match min.value {
            Some(v) => ("is", v),
            None => ("is below", min.bound),
        };
        let _ = writeln!(
            s,
            "  fit B vs Allan minimum: different quantities: B is the flicker coefficient of the fit (its plateau 0.664 B = {} {}); the minimum {verb} {} {} and is read off the curve alone, resolved only where the curve rises significantly after its lowest point; white noise and the other terms add to the plateau there",
            crate::fmt::sig(plateau * units[3].0, 4),
            units[3].1,
            crate::fmt::sig(v * units[3].0, 3),
            units[3].1,
        );
    }
    s
}

/// The spec-sheet readings of one channel, each a value with its interval or a bound.
fn reading_lines(
    s: &mut String,
    unit: &str,
    sheet: &SheetReadings,
    units: &[(f64, String); 6],
    level: &str,
) {
    let _ = writeln!(
        s,
        "readings of the curve alone (IEEE 952 / Kalibr practice, {level} intervals; a reading the curve does not resolve is given as a bound):"
    );
    let value = |rd: &Reading, (scale, shown): &(f64, String)| -> String {
        match rd.value {
            Some(v) => format!(
                "{} {shown} [{}, {}]",
                crate::fmt::sig(v * scale, 4),
                crate::fmt::sig(rd.lo * scale, 4),
                crate::fmt::sig(rd.hi * scale, 4)
            ),
            None => format!(
                "not resolved: < {} {shown} ({})",
                crate::fmt::sig(rd.bound * scale, 3),
                rd.why
            ),
        }
    };
    let range = |rd: &Reading| -> String {
        match rd.value {
            Some(_) if rd.tau_s[0] == rd.tau_s[1] => {
                format!(
                    "; from the one point at tau = {}",
                    crate::fmt::time(rd.tau_s[0])
                )
            }
            Some(_) => format!(
                "; line over tau = {} .. {}",
                crate::fmt::time(rd.tau_s[0]),
                crate::fmt::time(rd.tau_s[1])
            ),
            None => String::new(),
        }
    };
    let alt = sheet
        .arw
        .value
        .and_then(|v| crate::fmt::noise_density_alt(unit, v))
        .map_or(String::new(), |a| format!(" (= {a})"));
    let _ = writeln!(
        s,
        "  {:<26} {}{alt}{}",
        if unit == "m/s^2" {
            "VRW (-1/2 line at 1 s)"
        } else {
            "ARW (-1/2 line at 1 s)"
        },
        value(&sheet.arw, &units[2]),
        range(&sheet.arw)
    );
    let bi = &sheet.bi_min;
    let b_scale = &units[3];
    // The minimum as a B by the minimum convention (min / 0.664): named so, as the fit's B above
    // is another quantity.
    let ieee = match bi.value {
        Some(v) => format!(
            "; as B by the minimum convention, min/0.664 = {} {}; at tau = {}",
            crate::fmt::sig(allan::sheet::ieee_b(v) * b_scale.0, 4),
            b_scale.1,
            crate::fmt::time(bi.tau_s[0])
        ),
        None => format!(
            "; as B by the minimum convention, min/0.664 < {} {}",
            crate::fmt::sig(allan::sheet::ieee_b(bi.bound) * b_scale.0, 3),
            b_scale.1
        ),
    };
    let _ = writeln!(
        s,
        "  {:<26} {}{ieee}",
        "Allan minimum (bias inst.)",
        value(bi, b_scale)
    );
    let _ = writeln!(
        s,
        "  {:<26} {}{}",
        "RRW (+1/2 line at 3 s)",
        value(&sheet.rrw, &units[4]),
        range(&sheet.rrw)
    );
}

fn num(v: f64) -> Value {
    if v.is_finite() {
        json!(v)
    } else {
        Value::Null
    }
}

fn json_document(
    log: &Log,
    samples: usize,
    results: &[ChannelResult],
    est: Estimator,
    grid: &str,
    opts: &Options,
) -> Value {
    let confidence = opts.confidence;
    let mut channels = Map::new();
    for r in results {
        let col = |f: &dyn Fn(&AllanPoint) -> f64| -> Value {
            Value::Array(r.points.iter().map(|p| num(f(p))).collect())
        };
        let mut fit = Map::new();
        let mut sigma = Map::new();
        let terms = r.fit.as_ref().map_or([None; 5], Fit::terms);
        for (name, t) in TERM_NAMES.iter().zip(terms) {
            fit.insert(name.to_string(), t.map_or(Value::Null, |t| num(t.value)));
            sigma.insert(name.to_string(), t.map_or(Value::Null, |t| num(t.sigma)));
        }
        let readings = r.sheet.as_ref().map_or(Value::Null, readings_json);
        let (mut resolved, mut bound) = (Map::new(), Map::new());
        let (mut statistic, mut threshold) = (Map::new(), Map::new());
        if let (Some(f), Some(status)) = (&r.fit, &r.terms) {
            for ((name, t), st) in TERM_NAMES.iter().zip(f.terms()).zip(status) {
                resolved.insert(name.to_string(), json!(t.is_some() && st.resolved));
                statistic.insert(name.to_string(), num(st.statistic));
                threshold.insert(name.to_string(), num(st.threshold));
                let shown = !(t.is_some() && st.resolved);
                bound.insert(
                    name.to_string(),
                    if shown { num(st.bound) } else { Value::Null },
                );
            }
        }
        channels.insert(
            r.name.clone(),
            json!({
                "unit": r.unit,
                "tau_s": col(&|p| p.tau_s),
                "adev": col(&|p| p.dev),
                "adev_lo": col(&|p| p.lo),
                "adev_hi": col(&|p| p.hi),
                "m": r.points.iter().map(|p| p.m).collect::<Vec<_>>(),
                "n_terms": r.points.iter().map(|p| p.n_terms).collect::<Vec<_>>(),
                "bins": r.points.iter().map(|p| p.bins).collect::<Vec<_>>(),
                "alpha": r.points.iter().map(|p| p.alpha).collect::<Vec<_>>(),
                "edf": col(&|p| p.edf),
                "fit": fit,
                "fit_sigma": sigma,
                "fit_resolved": resolved,
                "fit_bound": bound,
                "fit_statistic": statistic,
                "fit_threshold": threshold,
                "fit_reduced_chi2": r.fit.as_ref().map_or(Value::Null, |f| num(f.reduced_chi2)),
                "fit_model_error": r.fit.as_ref().map_or(Value::Null, |f| num(f.model_error)),
                "readings": readings,
                "readings_tau_max_s": r.points.iter().filter(|p| p.woodman_ok()).map(|p| p.tau_s).fold(None, |_, t| Some(t)),
                "fit_subrange": subrange_json(r),
                "fit_note": misfit_note(r),
                "warnings": warnings(r),
            }),
        );
    }
    let (columns, skipped) = log_input::columns_json(log);
    json!({
        "source": log.source,
        "samples": samples,
        "rate_hz": log.rate_hz,
        "estimator": est.name(),
        "grid": grid,
        "stable32_stop": opts.stable32_stop,
        "confidence": confidence,
        "columns": columns,
        "skipped_columns": skipped,
        "channels": channels,
    })
}

/// `fit_subrange{term: [lo, hi]}`: each fitted term's smallest and largest value refitted
/// without each quarter of the taus in turn (SI; null for a term the fit does not have, or
/// without refits).
fn subrange_json(r: &ChannelResult) -> Value {
    let Some(spread) = r.spread.filter(|s| s.refits > 0) else {
        return Value::Null;
    };
    let mut o = Map::new();
    for (j, name) in TERM_NAMES.iter().enumerate() {
        let v = if spread.lo[j].is_finite() && spread.hi[j].is_finite() {
            json!([spread.lo[j], spread.hi[j]])
        } else {
            Value::Null
        };
        o.insert(name.to_string(), v);
    }
    Value::Object(o)
}

/// The readings in JSON: each under its name, `null` when the curve does not resolve it, with
/// `<name>_bound` (the largest value the curve allows) beside it; `_lo` / `_hi` the interval of a
/// resolved reading; `not_resolved{name: why}`.
fn readings_json(sheet: &SheetReadings) -> Value {
    let mut o = Map::new();
    let mut why = Map::new();
    let mut put = |name: &str, rd: &Reading, scale: f64| {
        let v = |x: f64| num(x * scale);
        o.insert(name.into(), rd.value.map_or(Value::Null, v));
        o.insert(
            format!("{name}_lo"),
            rd.value.map_or(Value::Null, |_| v(rd.lo)),
        );
        o.insert(
            format!("{name}_hi"),
            rd.value.map_or(Value::Null, |_| v(rd.hi)),
        );
        o.insert(
            format!("{name}_bound"),
            if rd.value.is_some() {
                Value::Null
            } else {
                v(rd.bound)
            },
        );
        if rd.value.is_none() {
            why.insert(name.into(), json!(rd.why));
        }
    };
    put("arw_at_1s", &sheet.arw, 1.0);
    put("bi_min", &sheet.bi_min, 1.0);
    put(
        "bi_ieee",
        &sheet.bi_min,
        1.0 / allan::fit::BI_PLATEAU_FACTOR,
    );
    put("rrw_at_3s", &sheet.rrw, 1.0);
    put("q_at_sqrt3s", &sheet.q, 1.0);
    let tau = |rd: &Reading, i: usize| rd.value.map_or(Value::Null, |_| num(rd.tau_s[i]));
    o.insert("arw_tau_s".into(), tau(&sheet.arw, 0));
    o.insert(
        "arw_tau_range_s".into(),
        json!([tau(&sheet.arw, 0), tau(&sheet.arw, 1)]),
    );
    o.insert("bi_min_tau_s".into(), tau(&sheet.bi_min, 0));
    o.insert("rrw_tau_s".into(), tau(&sheet.rrw, 0));
    o.insert(
        "rrw_tau_range_s".into(),
        json!([tau(&sheet.rrw, 0), tau(&sheet.rrw, 1)]),
    );
    o.insert("not_resolved".into(), Value::Object(why));
    Value::Object(o)
}

/// A channel's noise density and random walk for a noise file: the readings a Kalibr user takes
/// off the curve and `allan` prints, the ARW (the -1/2 line fitted where white noise dominates,
/// read at tau = 1 s) and the RRW (the +1/2 line read at 3 s); where a line is not resolved, the
/// IEEE 952 fit's N (K) if resolved, else the bound the curve sets (for K the largest random
/// walk the curve allows). Each value says which it is (the file's per-axis comments).
fn noise_file_values(r: &ChannelResult) -> Option<(AxisValue, AxisValue)> {
    let (fit, sheet, status) = (r.fit.as_ref()?, r.sheet.as_ref()?, r.terms.as_ref()?);
    let line = |rd: &Reading, what: &str, at: &str| -> Option<AxisValue> {
        rd.value.map(|v| AxisValue {
            value: v,
            how: format!(
                "{what}: {} line over tau = {} .. {} read at {at}",
                if what == "ARW" { "-1/2" } else { "+1/2" },
                crate::fmt::time(rd.tau_s[0]),
                crate::fmt::time(rd.tau_s[1])
            ),
        })
    };
    let fitted = |t: Option<allan::fit::Term>, j: usize, letter: &str| -> Option<AxisValue> {
        t.filter(|_| status[j].resolved).map(|t| AxisValue {
            value: t.value,
            how: format!(
                "IEEE 952 fit's {letter} (no resolved line), sigma {:.2e}",
                t.sigma
            ),
        })
    };
    let n = line(&sheet.arw, "ARW", "1 s")
        .or_else(|| fitted(fit.n, 1, "N"))
        .unwrap_or_else(|| AxisValue {
            value: status[1].bound,
            how: "not resolved; bound: -1/2 line touching the curve".into(),
        });
    let k = line(&sheet.rrw, "RRW", "3 s")
        .or_else(|| fitted(fit.k, 3, "K"))
        .unwrap_or_else(|| AxisValue {
            value: status[3].bound,
            how: "not resolved; bound: +1/2 line touching the curve's upper interval ends".into(),
        });
    Some((n, k))
}

fn csv(results: &[ChannelResult]) -> String {
    let mut s = String::from("channel,tau_s,m,n_terms,bins,alpha,edf,adev_lo,adev,adev_hi\n");
    for r in results {
        for p in &r.points {
            let _ = writeln!(
                s,
                "{},{:e},{},{},{},{},{:e},{:e},{:e},{:e}",
                r.name, p.tau_s, p.m, p.n_terms, p.bins, p.alpha, p.edf, p.lo, p.dev, p.hi
            );
        }
    }
    s
}

fn plot(r: &ChannelResult, est: Estimator, source: &str) -> LogLogPlot {
    let x: Vec<f64> = r.points.iter().map(|p| p.tau_s).collect();
    let mut p = LogLogPlot {
        title: format!("{} {}", r.name, est.name()),
        subtitle: std::path::Path::new(source)
            .file_name()
            .map_or(source.into(), |f| f.to_string_lossy().into_owned()),
        notes: Vec::new(),
        x_label: "tau (s)".into(),
        y_label: format!("{} ({})", est.name(), r.unit),
        series: vec![Series::new(
            est.name(),
            x.clone(),
            r.points.iter().map(|p| p.dev).collect(),
            PALETTE[0],
        )],
        bands: vec![Band {
            name: "confidence interval".into(),
            x: x.clone(),
            lo: r.points.iter().map(|p| p.lo).collect(),
            hi: r.points.iter().map(|p| p.hi).collect(),
            color: PALETTE[0].into(),
        }],
    };
    let fine: Vec<f64> = if x.is_empty() {
        Vec::new()
    } else {
        let (a, b) = (x[0].log10(), x[x.len() - 1].log10());
        (0..=100)
            .map(|i| 10f64.powf(a + (b - a) * i as f64 / 100.0))
            .collect()
    };
    let (Some(fit), Some(status), Some(sheet)) = (&r.fit, &r.terms, &r.sheet) else {
        return p.in_spec_sheet_units(est.name(), r.unit);
    };
    p.series.push(Series::dashed(
        "IEEE 952 fit",
        fine.clone(),
        fine.iter().map(|&t| fit.model_dev(t)).collect(),
        "#000000",
    ));
    let names = [
        "Q (tau^-1)",
        "N (tau^-1/2)",
        "B (flat)",
        "K (tau^+1/2)",
        "R (tau^+1)",
    ];
    // Only resolved terms are drawn; the others are named with their bound below the plot.
    for (j, name) in names.iter().enumerate() {
        if fit.terms()[j].is_some() && status[j].resolved {
            p.series.push(Series::dashed(
                name,
                fine.clone(),
                fine.iter()
                    .map(|&t| fit.term_dev(j, t).unwrap_or(f64::NAN))
                    .collect(),
                PALETTE[(j + 1) % PALETTE.len()],
            ));
        }
    }
    let units = crate::fmt::allan_units(r.unit);
    let mut notes = String::new();
    reading_lines(&mut notes, r.unit, sheet, &units, "");
    p.notes = notes
        .lines()
        .skip(1)
        .map(|l| l.split_whitespace().collect::<Vec<_>>().join(" "))
        .collect();
    // The points the readings leave out, as the table marks them.
    if let Some(first) = r.points.iter().find(|p| !p.woodman_ok()) {
        p.notes.push(format!(
            "points from tau = {} on have fewer than 9 non-overlapping averages (Woodman §5.1): shown and fitted, no reading taken from them",
            crate::fmt::time(first.tau_s)
        ));
    }
    p.in_spec_sheet_units(est.name(), r.unit)
}

/// One SVG file name per channel, `allan_<name>.svg` with the name made safe for a file system;
/// names that become equal (`a.b`, `a_b`, `a b`) get `_2`, `_3` ... so no plot overwrites another.
fn svg_names<'a>(names: impl Iterator<Item = &'a str>) -> Vec<String> {
    let mut used = std::collections::BTreeSet::new();
    names
        .map(|n| {
            let base = sanitize(n);
            let mut name = format!("allan_{base}.svg");
            let mut k = 2;
            while !used.insert(name.clone()) {
                name = format!("allan_{base}_{k}.svg");
                k += 1;
            }
            name
        })
        .collect()
}

fn sanitize(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}
