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
//!
//! A tiny experiment from its texts: a gyro with white rate noise lying still for 2 s on
//! Woodman's flat Earth, 64 runs.
//! Its heading error is a random walk, of rms N sqrt(t) (Woodman eq 29); the report puts each
//! quantity's rms over the runs beside that law with a 99.9 % interval of their ratio.
//!
//! ```
//! use imudrift_montecarlo::experiment::{Experiment, Overrides};
//! use imudrift_montecarlo::scenario::Scenario;
//!
//! let scenario = Scenario::from_toml_str(
//!     "name = \"tiny\"\nsensor = \"gyro.toml\"\nduration_s = 2.0\nrate_hz = 100.0\nruns = 64\nseed = 1\n[earth]\nmodel = \"flat\"\n",
//!     "tiny.toml",
//! )
//! .unwrap();
//! let model = noise::SensorModel::from_toml_str(
//!     "name = \"gyro\"\n[gyro.z]\nwhite_noise = \"0.1 deg/sqrt(s)\"\n",
//!     "gyro.toml",
//! )
//! .unwrap();
//! let exp = Experiment::new(scenario, &model, &Overrides::default()).unwrap();
//! let batch = imudrift_montecarlo::run_range(&exp.kernel(), 0..exp.runs, &|_| {});
//! let report = exp.report(&batch.matrix, &batch.failures);
//! assert_eq!(report.runs_ok, 64);
//! let last = report.checkpoints.last().unwrap();
//! assert_eq!(last.t_s, 2.0);
//! let yaw = &last.quantities["yaw_rad"];
//! let law = 0.1f64.to_radians() * 2f64.sqrt();
//! assert!((yaw.law_rms.unwrap() / law - 1.0).abs() < 1e-6);
//! let (lo, hi) = (yaw.ratio_lo.unwrap(), yaw.ratio_hi.unwrap());
//! assert!(lo < 1.0 && 1.0 < hi, "law outside the runs' interval {lo} .. {hi}");
//! ```

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
