//! imudrift-montecarlo: the deterministic parallel Monte Carlo runner of the drift laboratory.
//!
//! From a sensor model and a scenario (trajectory, duration, rate, runs, seed, checkpoints) it runs
//! many strapdown dead-reckoning solutions, each with its own random stream, and collects the
//! navigation error at checkpoints into per-run value vectors ([`stats::RunMatrix`]) from which the
//! drift statistics are computed in run order: bit-identical for any thread count or shard split.
//! [`laws`] pairs each navigation-error quantity ([`NavQuantity`]) with the closed-form growth law
//! of its active error terms.
//!
//! Modules: [`scenario`] (the scenario TOML, validated), [`experiment`] (scenario + sensor +
//! overrides), [`job`] (a `simulate` job from its texts: shards, merge, the JSON document, shared by the
//! CLI and the Python package), [`drift`] (the per-run kernel and the active terms), [`runner`] (parallel blocks,
//! ordered merge, shards, failed runs), [`stats`] (run matrix, Welford moments, exact quantiles,
//! ratio intervals), [`laws`], [`report`] (the `simulate` JSON), [`shard`] (shard files for
//! `merge`), [`spec`] (spec-sheet readback and drift table), [`nav_quantity`] (the
//! navigation-error quantities and their docs/cli.md names).
//! The only parallelism is rayon inside [`runner::run_range`] and [`spec::gyro_readback`]; no I/O.
//!
//! Units are SI (rad, m, m/s, s). Frames: navigation NED, body forward-right-down; a static level
//! IMU reads specific force (0, 0, -g).

pub mod ablation;
pub mod drift;
pub mod earth_laws;
pub mod experiment;
pub mod job;
pub mod laws;
pub mod nav_quantity;
pub mod report;
pub mod requirement;
pub mod runner;
pub mod scenario;
pub mod shard;
pub mod spec;
pub mod spec_job;
pub mod stats;

pub use nav_quantity::NavQuantity;
pub use runner::{run_range, run_range_until, BatchResult, RunError, RunFailure, RunKernel, Shard};
pub use stats::{RunMatrix, Summary};
