//! One home per error effect: each file holds one effect's validated parameters and its closed
//! forms (docs/model.md §2).

pub mod bias_instability;
pub mod gauss_markov;
pub mod outliers;
pub mod output_filter;
pub mod resonance;
pub mod sinusoidal;
pub mod warmup_transient;
