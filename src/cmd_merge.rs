//! `imudrift merge SHARD...`: combine the shard files of `simulate --shard i/k` into exactly the
//! result a single `simulate` computes (same per-run values, merged in run-index order).

use crate::cli::request_error;
use crate::cmd_simulate::emit;
use anyhow::Result;
use request::simulate::{MergeRequest, ShardInput};
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
    let job = MergeRequest {
        shards: args.shards.iter().cloned().map(ShardInput::Path).collect(),
    }
    .validate()
    .map_err(request_error)?;
    let exp = job.exp.clone();
    let sim = job.merge().map_err(request_error)?;
    emit(
        &sim.report,
        &exp,
        sim.ablation.as_deref(),
        args.json,
        args.out.as_deref(),
    )
}
