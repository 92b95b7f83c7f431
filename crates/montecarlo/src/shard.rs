//! Shard files: the per-run values of a deterministic slice of the runs (`simulate --shard i/k`),
//! with everything needed to rebuild the experiment, so that `merge` reproduces exactly what a
//! single machine computes. Values are stored as JSON numbers (shortest round-trip form; parsed
//! back exactly with serde_json's `float_roundtrip`).

use crate::runner::{RunFailure, Shard};
use crate::stats::RunMatrix;
use noise::TermSelector;
use serde::{Deserialize, Serialize};

/// Format tag written into every shard file.
pub const SHARD_FORMAT: &str = "imudrift-shard/1";

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShardFile {
    pub format: String,
    /// Scenario file as given and its full text.
    pub scenario_source: String,
    pub scenario_toml: String,
    /// Sensor file as resolved and its full text.
    pub sensor_source: String,
    pub sensor_toml: String,
    /// Overrides in effect (the experiment identity together with the two texts).
    pub runs: Option<u64>,
    pub seed: Option<u64>,
    pub only: Option<Vec<TermSelector>>,
    pub without: Vec<TermSelector>,
    pub shard: Shard,
    pub matrix: RunMatrix,
    pub failures: Vec<RunFailure>,
    /// The shard's slices of the ablation sub-experiments, when the run has an ablation table.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ablation: Option<Vec<crate::ablation::TermBatches>>,
}

/// A shard file that cannot be merged, and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct ShardError(pub String);

impl ShardFile {
    /// Whether the file is consistent in itself and with its experiment (`runs` runs, `checkpoints`
    /// checkpoints, `quantities` navigation-error quantities): a valid split, well-formed matrices of that shape, and
    /// only runs of its own slice (ablation sub-runs included).
    pub fn check(
        &self,
        runs: u64,
        checkpoints: usize,
        quantities: usize,
    ) -> Result<(), ShardError> {
        let fail = |what: String| Err(ShardError(what));
        if self.shard.count == 0 || self.shard.index >= self.shard.count {
            return fail(format!(
                "key `shard`: expected 0 <= index < count, got {}/{}",
                self.shard.index, self.shard.count
            ));
        }
        let slice = self.shard.runs(runs);
        let batches = std::iter::once(("matrix", &self.matrix, &self.failures)).chain(
            self.ablation.iter().flatten().flat_map(|t| {
                [
                    ("ablation (term alone)", &t.only.matrix, &t.only.failures),
                    (
                        "ablation (term removed)",
                        &t.without.matrix,
                        &t.without.failures,
                    ),
                ]
            }),
        );
        for (what, m, failures) in batches {
            m.check().or_else(|e| fail(format!("key `{what}`: {e}")))?;
            if (m.checkpoints, m.quantities) != (checkpoints, quantities) {
                return fail(format!(
                    "key `{what}`: {} checkpoints x {} quantities, but the experiment has {checkpoints} x {quantities}",
                    m.checkpoints, m.quantities
                ));
            }
            let ids = m
                .run_ids
                .iter()
                .copied()
                .chain(failures.iter().map(|f| f.run));
            if let Some(r) = ids.clone().find(|r| !slice.contains(r)) {
                return fail(format!(
                    "key `{what}`: run {r} is outside this shard's runs {slice:?}"
                ));
            }
            if ids.count() as u64 != slice.end - slice.start {
                return fail(format!(
                    "key `{what}`: {} runs and {} failures, but shard {}/{} holds {} runs",
                    m.runs(),
                    failures.len(),
                    self.shard.index,
                    self.shard.count,
                    slice.end - slice.start
                ));
            }
        }
        Ok(())
    }

    /// Whether two shard files belong to the same experiment texts, terms and split (the runs
    /// and seed are compared by the caller after resolving them against the scenario, so an
    /// explicit `--seed` equal to the scenario's own seed is the same experiment).
    pub fn same_experiment(&self, other: &ShardFile) -> bool {
        self.format == other.format
            && self.scenario_toml == other.scenario_toml
            && self.sensor_toml == other.sensor_toml
            && self.only == other.only
            && self.without == other.without
            && self.shard.count == other.shard.count
            && self.ablation.is_some() == other.ablation.is_some()
    }
}
