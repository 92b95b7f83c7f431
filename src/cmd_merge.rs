//! `imudrift merge SHARD...`: combine the shard files of `simulate --shard i/k` into exactly the
//! result a single `simulate` computes (same per-run values, merged in run-index order).

use crate::cmd_simulate::emit;
use crate::experiment_run::{ablation_experiments, check_memory, Inputs};
use anyhow::{bail, Context, Result};
use montecarlo::experiment::{Experiment, Overrides};
use montecarlo::report::DriftReport;
use montecarlo::runner::RunFailure;
use montecarlo::shard::{ShardFile, SHARD_FORMAT};
use montecarlo::RunMatrix;

/// Number of ablation terms a shard carries.
fn a_len(f: &ShardFile) -> usize {
    f.ablation.as_ref().map_or(0, Vec::len)
}
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Shard files written by `imudrift simulate --shard i/k --out DIR` (all k of them)
    #[arg(required = true)]
    pub shards: Vec<PathBuf>,
    /// Print one JSON document on stdout
    #[arg(long)]
    pub json: bool,
    /// Write drift.csv, drift.json and drift.svg into DIR
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    crate::output::note_inputs(&args.shards);
    let _out_lock = args
        .out
        .as_deref()
        .map(crate::output::prepare_dir)
        .transpose()?;
    let files = read_shards(&args.shards)?;
    let (first_path, first) = &files[0];
    let (inputs, overrides, exp) = experiment_of(first)
        .with_context(|| format!("{}: the stored scenario", first_path.display()))?;
    // The merged values must fit, as for `simulate` itself (which would have asked for shards).
    check_memory(&exp, exp.runs * (1 + 2 * a_len(first) as u64))?;
    check_shards(&files, &exp)?;
    let ablation = match &first.ablation {
        None => None,
        Some(_) => Some(merged_ablation(&files, &inputs, &overrides)?),
    };
    let (matrix, failures) = merge(
        files
            .into_iter()
            .map(|(_, f)| (f.matrix, f.failures))
            .collect(),
        "simulate",
    )?;
    let report = exp.report(&matrix, &failures);
    let rows = ablation.map(|per_term| montecarlo::ablation::rows(&report, &per_term));
    emit(
        &report,
        &exp,
        rows.as_deref(),
        args.json,
        args.out.as_deref(),
    )
}

/// Read every shard file; each must be one (its `format` key). Together they are read with one
/// bound (`files::shard_bytes`): each file's size is checked before it is read.
fn read_shards(paths: &[PathBuf]) -> Result<Vec<(&PathBuf, ShardFile)>> {
    let mut files = Vec::new();
    let mut left = crate::files::shard_bytes();
    for path in paths {
        let text = crate::files::read_text(
            path,
            "an imudrift shard file (the shards together at most a third of the memory available)",
            left,
        )?
        .text;
        left = left.saturating_sub(text.len() as u64);
        let file: ShardFile = serde_json::from_str(&text)
            .with_context(|| format!("{}: not an imudrift shard file", path.display()))?;
        if file.format != SHARD_FORMAT {
            bail!(
                "{}: key `format`: expected `{SHARD_FORMAT}`, got `{}`",
                path.display(),
                file.format
            );
        }
        files.push((path, file));
    }
    Ok(files)
}

/// A shard file's experiment, resolved against its stored scenario (runs and seed compare by
/// value).
fn experiment_of(f: &ShardFile) -> Result<(Inputs, Overrides, Experiment)> {
    crate::experiment_run::shard_experiment(f)
}

/// Every shard belongs to the first one's experiment and split, is consistent in itself, and
/// each of the k shards is given once (checked in the order their errors are reported).
fn check_shards(files: &[(&PathBuf, ShardFile)], exp: &Experiment) -> Result<()> {
    let (first_path, first) = &files[0];
    for (path, f) in files {
        let (_, _, e) =
            experiment_of(f).with_context(|| format!("{}: the stored scenario", path.display()))?;
        if !first.same_experiment(f) || (e.runs, e.seed) != (exp.runs, exp.seed) {
            bail!(
                "{} and {} belong to different experiments or splits (scenario, sensor, runs, seed, terms, ablation and k must match)",
                first_path.display(),
                path.display()
            );
        }
        f.check(
            exp.runs,
            exp.scenario.checkpoint_steps.len(),
            montecarlo::nav_quantity::NavQuantity::ALL.len(),
        )
        .with_context(|| format!("{}: not a consistent shard file", path.display()))?;
    }
    let k = first.shard.count;
    let mut seen = vec![None; k as usize];
    for (path, f) in files {
        if let Some(other) = seen[f.shard.index as usize].replace(*path) {
            bail!(
                "shard {}/{k} given twice: {} and {}",
                f.shard.index,
                other.display(),
                path.display()
            );
        }
    }
    if let Some(i) = seen.iter().position(Option::is_none) {
        bail!("shard {i}/{k} is missing: all {k} shards are needed");
    }
    Ok(())
}

/// Per-run values of one experiment from every shard, merged in run-index order.
fn merge(
    parts: Vec<(RunMatrix, Vec<RunFailure>)>,
    what: &str,
) -> Result<(RunMatrix, Vec<RunFailure>)> {
    let mut failures: Vec<_> = parts.iter().flat_map(|(_, f)| f.clone()).collect();
    failures.sort_by_key(|f| f.run);
    let matrix =
        RunMatrix::merge(parts.into_iter().map(|(m, _)| m).collect()).with_context(|| {
            format!("{what}: shard matrices have different shapes or overlapping runs")
        })?;
    Ok((matrix, failures))
}

/// The ablation sub-experiments' reports (each term alone, the model without it) from every
/// shard's slices of them.
fn merged_ablation(
    files: &[(&PathBuf, ShardFile)],
    inputs: &Inputs,
    overrides: &Overrides,
) -> Result<Vec<(String, DriftReport, DriftReport)>> {
    let subs = ablation_experiments(inputs, overrides)?;
    let names: Vec<&String> = subs.iter().map(|t| &t.term).collect();
    let mut per_term = Vec::new();
    for (i, sub) in subs.iter().enumerate() {
        let mut only = Vec::new();
        let mut without = Vec::new();
        for (path, f) in files {
            let t = f
                .ablation
                .as_ref()
                .and_then(|a| a.get(i))
                .filter(|t| t.term == sub.term && a_len(f) == subs.len())
                .with_context(|| {
                    format!(
                        "{}: key `ablation`: expected the terms {names:?} (in that order)",
                        path.display()
                    )
                })?;
            only.push((t.only.matrix.clone(), t.only.failures.clone()));
            without.push((t.without.matrix.clone(), t.without.failures.clone()));
        }
        let (m, f) = merge(only, &sub.term)?;
        let only_report = sub.only.report(&m, &f);
        let (m, f) = merge(without, &sub.term)?;
        let without_report = sub.without.report(&m, &f);
        per_term.push((sub.term.clone(), only_report, without_report));
    }
    Ok(per_term)
}
