//! `imudrift merge SHARD...`: combine the shard files of `simulate --shard i/k` into exactly the
//! result a single `simulate` computes (same per-run values, merged in run-index order).

use crate::cmd_simulate::emit;
use crate::experiment_run::check_memory;
use anyhow::{bail, Context, Result};
use montecarlo::job;
use montecarlo::shard::{ShardFile, SHARD_FORMAT};
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
    let (inputs, overrides, exp) = crate::experiment_run::shard_experiment(first)
        .with_context(|| format!("{}: the stored scenario", first_path.display()))?;
    // The merged values must fit, as for `simulate` itself (which would have asked for shards).
    let a_len = first.ablation.as_ref().map_or(0, Vec::len);
    check_memory(&exp, exp.runs * (1 + 2 * a_len as u64))?;
    let named = files
        .into_iter()
        .map(|(path, f)| (path.display().to_string(), f))
        .collect();
    let sim = job::merge(named, &inputs, &overrides, &exp).map_err(|e| match e {
        job::MergeError::Job(e) => crate::experiment_run::with_flag(*e),
        other => anyhow::Error::new(other),
    })?;
    emit(
        &sim.report,
        &exp,
        sim.ablation.as_deref(),
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
