//! The modules of the `imudrift` command (see `main.rs`), as a library so that the fuzz targets
//! (`fuzz/`) and the property tests reach the same log reader, config loaders and shard checks the
//! command uses. Not a stable API: the stable interfaces are the command line and its JSON.

pub mod cli;
pub mod cmd_allan;
pub mod cmd_diagnose;
pub mod cmd_drift;
pub mod cmd_generate;
pub mod cmd_merge;
pub mod cmd_plan;
pub mod cmd_simulate;
pub mod cmd_spec;
pub mod experiment_run;
pub mod fmt;
pub mod logio;
pub mod noise_out;
pub mod output;
pub mod plot;
pub mod progress;
