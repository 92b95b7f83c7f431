//! `imudrift simulate SCENARIO.toml`: Monte Carlo drift run; every navigation-error quantity beside
//! its growth law.

use crate::cli::{pool, request_error};
use crate::experiment_run::execute;
use crate::fmt;
use crate::output::{ensure_dir, write_atomic, write_string};
use crate::plot::{Band, LogLogPlot, Series, PALETTE};
use anyhow::{bail, Result};
use montecarlo::ablation::{self, AblationRow};
use montecarlo::experiment::Experiment;
use montecarlo::job::{self, reference_out, FlagCount, ReferenceOut};
use montecarlo::nav_quantity::NavQuantity;
use montecarlo::report::DriftReport;
use request::simulate::{SimulateJob, SimulateRequest, Subject};
use std::io::Write;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct Args {
    /// Scenario TOML (configs/scenarios/*.toml), or a sensor TOML (configs/sensors/*.toml): a sensor
    /// alone is simulated lying still and level (the default static scenario: --duration 60 s,
    /// --rate 100 Hz, --runs 500, --seed 1)
    pub scenario: PathBuf,
    /// Length of each run: seconds, or a time with its unit ("90 s", "5 min", "1 h"); overrides the scenario
    #[arg(long, value_parser = crate::cli::duration_s)]
    pub duration: Option<f64>,
    /// Sample rate in Hz; overrides the scenario
    #[arg(long)]
    pub rate: Option<f64>,
    /// Number of Monte Carlo runs (overrides the scenario)
    #[arg(long)]
    pub runs: Option<u64>,
    /// Master seed (overrides the scenario); run i uses its own stream derived from (seed, i)
    #[arg(long)]
    pub seed: Option<u64>,
    /// Worker threads (default: all cores); results are identical for any value
    #[arg(long)]
    pub threads: Option<usize>,
    /// Print one JSON document on stdout (human text stays on stderr)
    #[arg(long)]
    pub json: bool,
    /// Write drift.csv, drift.json and drift.svg into DIR (with --shard: the shard file)
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Keep only these error terms, e.g. `gyro.white_noise,accel.white_noise`
    #[arg(long, value_delimiter = ',', value_parser = noise::TermSelector::parse)]
    pub only: Option<Vec<noise::TermSelector>>,
    /// Switch these error terms off, e.g. `gyro.bias_instability`
    #[arg(long, value_delimiter = ',', value_parser = noise::TermSelector::parse)]
    pub without: Vec<noise::TermSelector>,
    /// Run only the deterministic slice i/k of the runs (0 <= i < k) and write a shard file for
    /// `imudrift merge` into --out DIR
    #[arg(long, value_name = "I/K")]
    pub shard: Option<String>,
    /// Also run each active term alone and the model without it (ablation table); on by default
    /// when the scenario says `ablation = true`
    #[arg(long)]
    pub ablation: bool,
    /// No ablation table even if the scenario asks for one
    #[arg(long, conflicts_with = "ablation")]
    pub no_ablation: bool,
}

pub fn run(args: Args) -> Result<()> {
    crate::output::note_inputs([&args.scenario]);
    // Shards of one job write their own files into one directory at once: no lock for them.
    let _out_lock = match (&args.out, &args.shard) {
        (Some(dir), None) => Some(crate::output::prepare_dir(dir)?),
        (Some(dir), Some(_)) => Some(crate::output::prepare_shared_dir(dir)?),
        (None, _) => None,
    };
    let job = SimulateRequest {
        subject: Subject::Path(args.scenario.clone()),
        runs: args.runs,
        seed: args.seed,
        duration_s: args.duration,
        rate_hz: args.rate,
        only: args.only.clone(),
        without: args.without.clone(),
        ablation: match (args.ablation, args.no_ablation) {
            (true, _) => Some(true),
            (_, true) => Some(false),
            _ => None,
        },
    }
    .validate()
    .map_err(request_error)?;
    if let Some(p) = &job.sensor_path {
        crate::output::note_inputs([p]);
    }
    let pool = pool(args.threads)?;
    let run = |e: &Experiment, runs: std::ops::Range<u64>, label: &str| {
        Some(pool.install(|| execute(e, runs, label)))
    };
    if let Some(text) = &args.shard {
        return run_shard(&args, text, &job, &run);
    }
    job.check_size(job.exp.runs).map_err(request_error)?;
    let Some(sim) = job::simulate(&job.exp, job.subs(), &run) else {
        bail!("interrupted");
    };
    emit(
        &sim.report,
        &job.exp,
        sim.ablation.as_deref(),
        args.json,
        args.out.as_deref(),
    )
}

/// `--shard i/k`: run the slice of the runs (and of every ablation sub-experiment) and write the
/// shard file `merge` reads.
fn run_shard(args: &Args, text: &str, job: &SimulateJob, run: &job::RunRange<'_>) -> Result<()> {
    let shard = request::simulate::parse_shard(text).map_err(request_error)?;
    let Some(dir) = &args.out else {
        bail!("--shard: expected --out DIR for the shard file");
    };
    let exp = &job.exp;
    job.shard_runs(shard).map_err(request_error)?;
    // The file without its values yet: its experiment is checked against the directory's other
    // shards before any work.
    let mut file = job.empty_shard(shard);
    crate::experiment_run::refuse_other_experiments(dir, &file, exp)?;
    if job::fill_shard(&mut file, exp, job.subs(), run).is_none() {
        bail!("interrupted");
    }
    ensure_dir(dir)?;
    let path = dir.join(format!("shard-{}-of-{}.json", shard.index, shard.count));
    write_atomic(&path, |w| Ok(serde_json::to_writer(w, &file)?))?;
    report_failures(&file.failures);
    tell!(
        "shard {}/{}: runs {:?} of {}, {} finished{}; wrote {}",
        shard.index,
        shard.count,
        shard.runs(exp.runs),
        exp.runs,
        file.matrix.runs(),
        job.subs.as_ref().map_or(String::new(), |subs| format!(
            " (and {} ablation sub-runs)",
            2 * subs.len()
        )),
        path.display()
    );
    Ok(())
}

fn report_failures(failures: &[montecarlo::RunFailure]) {
    for f in failures.iter().take(10) {
        tell!("warning: run {} failed: {}", f.run, f.message);
    }
    if failures.len() > 10 {
        tell!("warning: {} more runs failed", failures.len() - 10);
    }
}

/// Print the table on stderr and write --json / --out outputs (shared with `merge`).
pub fn emit(
    report: &DriftReport,
    exp: &Experiment,
    ablation: Option<&[AblationRow]>,
    json: bool,
    out: Option<&Path>,
) -> Result<()> {
    if let Err(e) = job::check_some_runs(report) {
        report_failures(&report.failed_runs);
        bail!(e);
    }
    crate::experiment_run::check_finite(report)?;
    crate::model_notes::print(&exp.model, Some(exp.scenario.duration_s));
    let reference = reference_out(report, exp);
    report_failures(&report.failed_runs);
    let human = table(report, reference.as_ref(), ablation);
    let value = job::document(report, exp, ablation);
    let text = serde_json::to_string_pretty(&value)? + "\n";
    crate::output::answer(&human, json.then_some(text.as_str()))?;
    if let Some(dir) = out {
        let set = crate::output::begin_out_set(dir)?;
        write_string(&dir.join("drift.json"), &text)?;
        write_atomic(&dir.join("drift.csv"), |w| write_csv(w, report))?;
        write_string(
            &dir.join("drift.svg"),
            &svg(report, NavQuantity::PosHorizontal),
        )?;
        set.commit()?;
        tell!("wrote {}/drift.{{json,csv,svg}}", dir.display());
    }
    Ok(())
}

fn opt(x: Option<f64>) -> String {
    x.map_or_else(String::new, |v| format!("{v:.10e}"))
}

fn write_csv(w: &mut dyn Write, r: &DriftReport) -> Result<()> {
    writeln!(
        w,
        "# imudrift simulate: scenario {} sensor {} seed {} runs {} (ok {})",
        r.scenario, r.sensor, r.seed, r.runs, r.runs_ok
    )?;
    writeln!(w, "t_s,channel,mean,std,rms,p5,p50,p95,law_mean,law_std,law_rms,ratio,ratio_lo,ratio_hi,law_note")?;
    // The heading error is `heading_rad` in every command (docs/cli.md); its row is repeated
    // under the older name `yaw_rad`, as the JSON keeps both keys.
    let rows = NavQuantity::ALL.into_iter().flat_map(|q| {
        let alias = (q.label() != q.name()).then_some(q.name());
        std::iter::once((q, q.label())).chain(alias.map(|a| (q, a)))
    });
    let rows: Vec<(NavQuantity, &str)> = rows.collect();
    for cp in &r.checkpoints {
        for &(q, name) in &rows {
            let c = &cp.quantities[q.name()];
            writeln!(
                w,
                "{},{},{:.10e},{:.10e},{:.10e},{:.10e},{:.10e},{:.10e},{},{},{},{},{},{},{}",
                cp.t_s,
                name,
                c.mean,
                c.std,
                c.rms,
                c.p5,
                c.p50,
                c.p95,
                opt(c.law_mean),
                opt(c.law_std),
                opt(c.law_rms),
                opt(c.ratio),
                opt(c.ratio_lo),
                opt(c.ratio_hi),
                crate::fmt::csv_text(c.law_note.as_deref().unwrap_or(""))
            )?;
        }
    }
    Ok(())
}

/// The text of the ratio flags: how many intervals are outside and how many a correct model
/// marks on average.
trait FlagText {
    /// "2 of 36 intervals are marked *; a correct model marks 0.036 on average (at least one in
    /// at most 3.6 % of seeds)".
    fn text(&self) -> String;
}

impl FlagText for FlagCount {
    fn text(&self) -> String {
        format!(
            "{} of the {} ratio intervals above are marked *; under a correct model each is outside with probability 0.1 %, so {} are expected on average (at least one in at most {} % of seeds, the union bound)",
            self.outside,
            self.intervals,
            crate::fmt::trimmed(self.expected_outside, 3),
            crate::fmt::trimmed((100.0 * self.expected_outside).min(100.0), 3)
        )
    }
}

fn fmt_ratio(c: &montecarlo::report::QuantityReport) -> String {
    match (c.ratio, c.ratio_lo, c.ratio_hi) {
        (Some(r), Some(lo), Some(hi)) => {
            let flag = if lo <= 1.0 && 1.0 <= hi { "" } else { " *" };
            format!("{r:.3} [{lo:.3}, {hi:.3}]{flag}")
        }
        _ => "n/a".into(),
    }
}

fn table(
    r: &DriftReport,
    reference: Option<&ReferenceOut>,
    ablation: Option<&[AblationRow]>,
) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    horizontal_table(&mut s, r);
    last_checkpoint_table(&mut s, r);
    let h = NavQuantity::PosHorizontal.name();
    let shown = r.checkpoints.iter().map(|cp| &cp.quantities[h]).chain(
        r.checkpoints.last().into_iter().flat_map(|cp| {
            NavQuantity::ALL
                .into_iter()
                .filter(|q| *q != NavQuantity::PosHorizontal)
                .map(move |q| &cp.quantities[q.name()])
        }),
    );
    let _ = writeln!(s, "{}", FlagCount::of(shown).text());
    if let Some(rf) = reference {
        reference_line(&mut s, rf);
    }
    if let Some(rows) = ablation {
        ablation_tables(&mut s, r, rows);
    }
    s
}

/// The run's header line and the horizontal position error at every checkpoint beside its law.
fn horizontal_table(s: &mut String, r: &DriftReport) {
    use std::fmt::Write as _;
    let _ = writeln!(
        s,
        "{}: sensor {}, {} runs ({} ok), seed {}, {}, {}, scheme {}; terms: {}",
        r.scenario,
        r.sensor,
        r.runs,
        r.runs_ok,
        r.seed,
        fmt::rate(r.rate_hz),
        fmt::time(r.duration_s),
        r.scheme,
        if r.active_terms.is_empty() {
            "none".to_string()
        } else {
            r.active_terms.join(", ")
        }
    );
    let _ = writeln!(s, "Earth: {}", r.earth.describe());
    let round = r.earth.model == "wgs84";
    let _ = writeln!(
        s,
        "\nhorizontal position error vs time; law = {} of the active terms, ratio = rms/law rms [99.9 % interval], * = outside",
        if round {
            "the round-Earth error model"
        } else {
            "closed form"
        }
    );
    let _ = writeln!(
        s,
        "{:>10} {:>12} {:>12} {:>12} {:>12} {:>12} {:>12}  ratio",
        "t", "mean", "p50", "p95", "rms", "law mean", "law rms"
    );
    let h = NavQuantity::PosHorizontal.name();
    for cp in &r.checkpoints {
        let c = &cp.quantities[h];
        let _ = writeln!(
            s,
            "{:>10} {:>12} {:>12} {:>12} {:>12} {:>12} {:>12}  {}",
            fmt::time(cp.t_s),
            fmt::quantity_value(h, c.mean),
            fmt::quantity_value(h, c.p50),
            fmt::quantity_value(h, c.p95),
            fmt::quantity_value(h, c.rms),
            fmt::quantity_opt(h, c.law_mean),
            fmt::quantity_opt(h, c.law_rms),
            fmt_ratio(c)
        );
    }
    if let Some((cp, flat)) = r
        .checkpoints
        .last()
        .and_then(|cp| Some((cp, cp.quantities[h].flat_law_rms?)))
    {
        let c = &cp.quantities[h];
        let _ = writeln!(
            s,
            "at {}: rms {} on this round Earth (law {}); Woodman's flat Earth's law for the same terms: {}{}",
            fmt::time(cp.t_s),
            fmt::quantity_value(h, c.rms),
            fmt::quantity_opt(h, c.law_rms),
            fmt::quantity_value(h, flat),
            c.law_rms
                .map(|l| format!(" (round / flat {:.3})", l / flat))
                .unwrap_or_default()
        );
    }
}

/// Every navigation-error quantity at the last checkpoint beside its law (or why it has none).
fn last_checkpoint_table(s: &mut String, r: &DriftReport) {
    use std::fmt::Write as _;
    if let Some(last) = r.checkpoints.last() {
        let _ = writeln!(
            s,
            "\nall channels at t = {} (angles in deg)",
            fmt::time(last.t_s)
        );
        let _ = writeln!(
            s,
            "{:>20} {:>12} {:>12} {:>12} {:>12} {:>12} {:>12}  ratio / note",
            "channel", "mean", "std", "rms", "p95", "law mean", "law std"
        );
        for q in NavQuantity::ALL {
            let c = &last.quantities[q.name()];
            let tail = match &c.law_note {
                Some(n) if c.ratio.is_none() => n.clone(),
                _ => fmt_ratio(c),
            };
            let v = |x: f64| fmt::quantity_value(q.name(), x);
            let _ = writeln!(
                s,
                "{:>20} {:>12} {:>12} {:>12} {:>12} {:>12} {:>12}  {}",
                q.label(),
                v(c.mean),
                v(c.std),
                v(c.rms),
                v(c.p95),
                fmt::quantity_opt(q.name(), c.law_mean),
                fmt::quantity_opt(q.name(), c.law_std),
                tail
            );
        }
    }
}

/// The scenario's published reference beside the simulated value.
fn reference_line(s: &mut String, rf: &ReferenceOut) {
    use std::fmt::Write as _;
    let _ = writeln!(
        s,
        "\n{} {} at {}: simulated {}, published {} ({:+.0} %; {})",
        rf.quantity,
        rf.statistic,
        fmt::time(rf.t_s),
        fmt::quantity_value(&rf.quantity, rf.simulated),
        fmt::quantity_value(&rf.quantity, rf.value),
        100.0 * (rf.simulated / rf.value - 1.0),
        rf.source
    );
    if let Some(note) = &rf.note {
        let _ = writeln!(s, "  {note}");
    }
}

/// Which term dominates the horizontal error when, and each term alone / removed at the end.
fn ablation_tables(s: &mut String, r: &DriftReport, rows: &[AblationRow]) {
    use std::fmt::Write as _;
    let spans = ablation::dominant_spans(r, rows);
    let _ = writeln!(
        s,
        "\nlargest contributor to the horizontal error (term alone, mean square) vs time:"
    );
    for (term, from, to) in spans {
        let _ = writeln!(s, "  {from:>9.3} s .. {to:>9.3} s  {term}");
    }
    let _ = writeln!(s, "\nablation at the last checkpoint (horizontal position): each term alone, and the model without it");
    let _ = writeln!(
        s,
        "{:>28} {:>14} {:>16} {:>16}",
        "term", "alone mean m", "alone share ms", "without mean m"
    );
    for row in rows {
        let _ = writeln!(
            s,
            "{:>28} {:>14.3} {:>15.1}% {:>16.3}",
            row.term,
            row.only_mean_m,
            100.0 * row.only_share,
            row.without_mean_m
        );
    }
}

/// Log-log plot of one quantity (shared writer, src/plot.rs): simulated mean and rms, the p5-p95
/// band, and the law's mean and rms.
fn svg(r: &DriftReport, q: NavQuantity) -> String {
    let t: Vec<f64> = r.checkpoints.iter().map(|c| c.t_s).collect();
    let col = |f: &dyn Fn(&montecarlo::report::QuantityReport) -> f64| -> Vec<f64> {
        r.checkpoints
            .iter()
            .map(|c| f(&c.quantities[q.name()]))
            .collect()
    };
    let nan = f64::NAN;
    let plot = LogLogPlot {
        title: format!(
            "{}: {} vs time ({} runs, seed {})",
            r.scenario,
            q.name(),
            r.runs_ok,
            r.seed
        ),
        subtitle: String::new(),
        notes: Vec::new(),
        x_label: "t (s)".into(),
        y_label: q.name().into(),
        series: vec![
            Series::new("simulated mean", t.clone(), col(&|c| c.mean), PALETTE[0]),
            Series::new("simulated rms", t.clone(), col(&|c| c.rms), PALETTE[2]),
            Series::dashed(
                "law mean",
                t.clone(),
                col(&|c| c.law_mean.unwrap_or(nan)),
                PALETTE[1],
            ),
            Series::dashed(
                "law rms",
                t.clone(),
                col(&|c| c.law_rms.unwrap_or(nan)),
                PALETTE[4],
            ),
        ]
        .into_iter()
        .chain(
            // On the round Earth: Woodman's flat-Earth law for the same terms, for comparison.
            r.checkpoints
                .iter()
                .any(|c| c.quantities[q.name()].flat_law_rms.is_some())
                .then(|| {
                    Series::dashed(
                        "flat-Earth law rms",
                        t.clone(),
                        col(&|c| c.flat_law_rms.unwrap_or(nan)),
                        PALETTE[3],
                    )
                }),
        )
        .collect(),
        bands: vec![Band {
            name: "p5-p95".into(),
            x: t.clone(),
            lo: col(&|c| c.p5),
            hi: col(&|c| c.p95),
            color: PALETTE[0].into(),
        }],
    };
    plot.to_svg()
}
