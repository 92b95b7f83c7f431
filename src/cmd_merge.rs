//! `imudrift merge SHARD...`: combine the shard files of `simulate --shard i/k` into exactly the
//! result a single `simulate` computes (same per-run values, merged in run-index order).

use crate::cmd_simulate::{emit, experiment_from, Inputs};
use anyhow::{bail, Context, Result};
use montecarlo::experiment::Overrides;
use montecarlo::shard::{ShardFile, SHARD_FORMAT};
use montecarlo::RunMatrix;
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
    let mut files = Vec::new();
    for path in &args.shards {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read shard {}", path.display()))?;
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
    let (first_path, first) = &files[0];
    for (path, f) in &files[1..] {
        if !first.same_experiment(f) {
            bail!(
                "{} and {} belong to different experiments or splits (scenario, sensor, runs, seed, terms and k must match)",
                first_path.display(),
                path.display()
            );
        }
    }
    let k = first.shard.count;
    let mut seen = vec![None; k as usize];
    for (path, f) in &files {
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
    let inputs = Inputs {
        scenario_source: first.scenario_source.clone(),
        scenario_toml: first.scenario_toml.clone(),
        sensor_source: first.sensor_source.clone(),
        sensor_toml: first.sensor_toml.clone(),
    };
    let overrides = Overrides {
        runs: first.runs,
        seed: first.seed,
        only: first.only.clone(),
        without: first.without.clone(),
    };
    let exp = experiment_from(&inputs, &overrides)?;
    let mut failures: Vec<_> = files.iter().flat_map(|(_, f)| f.failures.clone()).collect();
    failures.sort_by_key(|f| f.run);
    let matrix = RunMatrix::merge(files.into_iter().map(|(_, f)| f.matrix).collect())
        .context("shard matrices have different shapes or overlapping runs")?;
    let report = exp.report(&matrix, &failures);
    emit(&report, &exp, None, args.json, args.out.as_deref())
}
