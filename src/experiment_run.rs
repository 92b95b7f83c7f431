//! Running a Monte Carlo experiment on the command line, shared by `simulate`, `spec` and
//! `merge`: the runs with progress, and the checks only a command line has (a shard directory
//! holds one experiment). What a run is and every rule before it is the request layer's
//! (`request::simulate`).

use crate::cli::request_error;
use crate::files;
use anyhow::{bail, Result};
use montecarlo::experiment::Experiment;
use montecarlo::job;
use montecarlo::report::DriftReport;
use montecarlo::runner::{run_range, BatchResult};
use montecarlo::shard::ShardFile;
use std::path::Path;

/// Refuse to write shard `file` (of experiment `exp`) into `dir` when the directory holds a
/// shard of another experiment (scenario, sensor, runs, seed, terms, ablation or k differ): a
/// shard directory holds the shards of one experiment, and `merge` needs them all alike.
pub fn refuse_other_experiments(dir: &Path, file: &ShardFile, exp: &Experiment) -> Result<()> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if !(name.starts_with("shard-") && name.ends_with(".json")) {
            continue;
        }
        let path = entry.path();
        let text = files::read_text(
            &path,
            "an imudrift shard file (in the --out directory)",
            files::shard_bytes(),
        )?
        .text;
        let Ok(other) = serde_json::from_str::<ShardFile>(&text) else {
            continue;
        };
        let same = file.same_experiment(&other)
            && job::shard_experiment(&other)
                .is_ok_and(|(_, _, e)| (e.runs, e.seed) == (exp.runs, exp.seed));
        if !same {
            bail!(
                "--out {}: {} is a shard of another experiment or split (scenario, sensor, runs, seed, terms, ablation and k must match); a shard directory holds the shards of one experiment: choose another --out or remove it",
                dir.display(),
                path.display()
            );
        }
    }
    Ok(())
}

/// Refuse `runs` runs of `exp` whose per-run values would not fit or whose work is beyond the
/// limit (`request::simulate`), before they are simulated.
pub fn check_size(exp: &Experiment, runs: u64) -> Result<()> {
    request::simulate::check_experiment(exp, runs, runs).map_err(request_error)
}

/// Run `exp` over `runs`, with progress on stderr (`crate::progress`).
pub fn execute(exp: &Experiment, runs: std::ops::Range<u64>, label: &str) -> BatchResult {
    let kernel = exp.kernel();
    let progress = crate::progress::Progress::new(label, "runs", runs.end - runs.start);
    let result = run_range(&kernel, runs, &|done| progress.set(done));
    progress.finish();
    result
}

/// Refuse a report with a statistic that is not a number (`montecarlo::job::check_finite`): an
/// error naming the statistic, the navigation-error quantity and the time.
pub fn check_finite(report: &DriftReport) -> Result<()> {
    Ok(job::check_finite(report)?)
}
