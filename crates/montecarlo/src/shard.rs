//! Shard files: the per-run values of a deterministic slice of the runs (`simulate --shard i/k`),
//! with everything needed to rebuild the experiment, so that `merge` reproduces exactly what a
//! single machine computes. Values are stored as JSON numbers (shortest round-trip form; parsed
//! back exactly with serde_json's `float_roundtrip`).

use crate::runner::{RunFailure, Shard};
use crate::stats::RunMatrix;
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
    pub only: Option<Vec<String>>,
    pub without: Vec<String>,
    pub shard: Shard,
    pub matrix: RunMatrix,
    pub failures: Vec<RunFailure>,
    /// The shard's slices of the ablation sub-experiments, when the run has an ablation table.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ablation: Option<Vec<crate::ablation::TermBatches>>,
}

impl ShardFile {
    /// Whether two shard files belong to the same experiment and split.
    pub fn same_experiment(&self, other: &ShardFile) -> bool {
        self.format == other.format
            && self.scenario_toml == other.scenario_toml
            && self.sensor_toml == other.sensor_toml
            && self.runs == other.runs
            && self.seed == other.seed
            && self.only == other.only
            && self.without == other.without
            && self.shard.count == other.shard.count
            && self.ablation.is_some() == other.ablation.is_some()
    }
}
