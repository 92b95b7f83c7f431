//! Deterministic parallel runner: runs are computed in parallel in fixed-size blocks, each block
//! collected in index order and appended to the [`RunMatrix`] in index order (docs/cli.md,
//! Randomness). Nothing reported is summed across threads, so the result is bit-identical for any
//! thread count. A failing (or panicking) run is recorded and skipped, never the whole batch.

use crate::stats::RunMatrix;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::ops::Range;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};

/// Runs per parallel block. Any value gives the same result; this one keeps both cores busy and
/// the progress callback frequent.
pub const BLOCK_RUNS: u64 = 64;

/// One Monte Carlo run: given its index, fill `out[checkpoint * quantities + quantity]`, the values
/// the kernel records at each checkpoint (the navigation-error quantities, [`crate::NavQuantity`],
/// for the drift kernel).
/// Implementations draw all randomness from streams derived from (seed, run), never shared state.
pub trait RunKernel: Sync {
    fn checkpoints(&self) -> usize;
    fn quantities(&self) -> usize;
    /// Simulate run `run`; the error says what went wrong (e.g. a non-finite state).
    fn run(&self, run: u64, out: &mut [f64]) -> Result<(), RunError>;
    /// How many runs [`RunKernel::run_lanes`] advances together (1: one at a time).
    fn lanes(&self) -> usize {
        1
    }
    /// Simulate runs `first .. first + results.len()` (at most [`RunKernel::lanes`]) together:
    /// run `first + i` writes row i of `out` (checkpoints x quantities values per row) and its
    /// outcome in `results[i]`. Each run's numbers must be exactly those of [`RunKernel::run`],
    /// so results do not depend on how runs are grouped. The default runs them one by one.
    fn run_lanes(&self, first: u64, out: &mut [f64], results: &mut [Result<(), RunError>]) {
        let width = out.len() / results.len().max(1);
        for (i, (row, result)) in out.chunks_mut(width).zip(results).enumerate() {
            *result = self.run(first + i as u64, row);
        }
    }
}

/// Why a run did not finish (recorded as a [`RunFailure`], never the end of the batch).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RunError {
    /// A state variable of the kernel became NaN or infinite.
    #[error("run {run}: {quantity} is not finite at t = {t_s} s")]
    NonFinite {
        run: u64,
        quantity: String,
        t_s: f64,
    },
    /// The kernel wrote a non-finite output value.
    #[error("non-finite value at checkpoint {checkpoint} quantity {quantity}")]
    NonFiniteOutput { checkpoint: usize, quantity: usize },
    /// The kernel panicked (the payload's message, when it has one).
    #[error("run panicked{}", .0.as_ref().map(|m| format!(": {m}")).unwrap_or_default())]
    Panicked(Option<String>),
    /// A reason of the kernel's own.
    #[error("{0}")]
    Kernel(String),
}

/// A run that did not finish.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunFailure {
    pub run: u64,
    pub message: String,
}

/// Output of [`run_range`].
#[derive(Debug, Clone, PartialEq)]
pub struct BatchResult {
    pub matrix: RunMatrix,
    pub failures: Vec<RunFailure>,
}

/// A run's values (checkpoints x quantities), or why it failed.
type RunRow = Result<Vec<f64>, RunError>;

/// A run's row, or why it failed: a kernel error, a non-finite output value.
fn checked_row<K: RunKernel>(
    kernel: &K,
    result: Result<(), RunError>,
    row: Vec<f64>,
) -> Result<Vec<f64>, RunError> {
    result?;
    match row.iter().position(|v| !v.is_finite()) {
        None => Ok(row),
        Some(i) => Err(RunError::NonFiniteOutput {
            checkpoint: i / kernel.quantities().max(1),
            quantity: i % kernel.quantities().max(1),
        }),
    }
}

fn panicked(panic: Box<dyn std::any::Any + Send>) -> RunError {
    RunError::Panicked(
        panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned()),
    )
}

fn run_one<K: RunKernel>(kernel: &K, run: u64, width: usize) -> Result<Vec<f64>, RunError> {
    let mut out = vec![f64::NAN; width];
    match catch_unwind(AssertUnwindSafe(|| kernel.run(run, &mut out))) {
        Ok(result) => checked_row(kernel, result, out),
        Err(panic) => Err(panicked(panic)),
    }
}

/// Runs `runs` through [`RunKernel::run_lanes`]; if that panics, each run again alone (so a
/// panic is charged to its own run only).
fn run_group<K: RunKernel>(
    kernel: &K,
    runs: Range<u64>,
    width: usize,
) -> Vec<Result<Vec<f64>, RunError>> {
    let count = (runs.end - runs.start) as usize;
    if count == 1 {
        return vec![run_one(kernel, runs.start, width)];
    }
    let mut out = vec![f64::NAN; width * count];
    let mut results: Vec<Result<(), RunError>> = vec![Ok(()); count];
    match catch_unwind(AssertUnwindSafe(|| {
        kernel.run_lanes(runs.start, &mut out, &mut results)
    })) {
        Ok(()) => results
            .into_iter()
            .zip(out.chunks(width.max(1)))
            .map(|(result, row)| checked_row(kernel, result, row.to_vec()))
            .collect(),
        Err(_) => runs.map(|run| run_one(kernel, run, width)).collect(),
    }
}

/// Run `runs` (a range of run indices) on the current rayon pool. `progress(done)` is called after
/// each block with the number of runs finished so far in this range.
pub fn run_range<K: RunKernel>(
    kernel: &K,
    runs: Range<u64>,
    progress: &(dyn Fn(u64) + Sync),
) -> BatchResult {
    let never = AtomicBool::new(false);
    run_range_until(kernel, runs, progress, &never).unwrap_or_else(|| BatchResult {
        matrix: RunMatrix::new(kernel.checkpoints(), kernel.quantities()),
        failures: Vec::new(),
    })
}

/// [`run_range`] that a front end can stop (an interrupt): once `stop` is set, no further run
/// starts, the runs under way finish, and the result is `None` (a partial batch is never
/// reported). The same runs give the same values as [`run_range`].
pub fn run_range_until<K: RunKernel>(
    kernel: &K,
    runs: Range<u64>,
    progress: &(dyn Fn(u64) + Sync),
    stop: &AtomicBool,
) -> Option<BatchResult> {
    let width = kernel.checkpoints() * kernel.quantities();
    let mut matrix = RunMatrix::with_capacity(
        kernel.checkpoints(),
        kernel.quantities(),
        (runs.end - runs.start) as usize,
    );
    let mut failures = Vec::new();
    let mut start = runs.start;
    while start < runs.end {
        let end = (start + BLOCK_RUNS).min(runs.end);
        // Ordered collect: element i of the block is run start + i whatever thread computed it.
        // Groups of `lanes` runs from the block's start (each run's numbers are the same in any
        // group, RunKernel::run_lanes); a group not started before `stop` is `None`.
        let lanes = kernel.lanes().max(1) as u64;
        let groups: Vec<Vec<Option<RunRow>>> = (0..(end - start).div_ceil(lanes))
            .into_par_iter()
            .map(|g| {
                let first = start + g * lanes;
                let last = (first + lanes).min(end);
                if stop.load(Ordering::Relaxed) {
                    return vec![None; (last - first) as usize];
                }
                run_group(kernel, first..last, width)
                    .into_iter()
                    .map(Some)
                    .collect()
            })
            .collect();
        let block = groups.into_iter().flatten();
        for (run, result) in (start..end).zip(block) {
            match result? {
                Ok(row) => matrix.push(run, &row),
                Err(e) => failures.push(RunFailure {
                    run,
                    message: e.to_string(),
                }),
            }
        }
        if stop.load(Ordering::Relaxed) {
            return None;
        }
        progress(end - runs.start);
        start = end;
    }
    Some(BatchResult { matrix, failures })
}

/// A deterministic slice `index/count` of the runs (0 <= index < count): contiguous ranges whose
/// union over all indices is `0..runs` exactly.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: u64,
    pub count: u64,
}

/// A shard specification that is not `i/k` with 0 <= i < k.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("shard `{0}`: expected `i/k` with integers 0 <= i < k (e.g. `0/4`, as Slurm's SLURM_ARRAY_TASK_ID/array size)")]
pub struct ShardSpecError(pub String);

impl Shard {
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Parse "i/k". Errors say what was expected.
    pub fn parse(text: &str) -> Result<Shard, ShardSpecError> {
        let bad = || ShardSpecError(text.to_string());
        let (i, k) = text.split_once('/').ok_or_else(bad)?;
        let index: u64 = i.trim().parse().map_err(|_| bad())?;
        let count: u64 = k.trim().parse().map_err(|_| bad())?;
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }

    /// The run indices of this shard out of `runs`.
    pub fn runs(&self, runs: u64) -> Range<u64> {
        let cut = |i: u64| ((i as u128 * runs as u128) / self.count as u128) as u64;
        cut(self.index)..cut(self.index + 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A toy kernel with per-run streams: a random walk observed at checkpoints, and run 5 fails.
    struct Walk;
    impl RunKernel for Walk {
        fn checkpoints(&self) -> usize {
            3
        }
        fn quantities(&self) -> usize {
            2
        }
        fn run(&self, run: u64, out: &mut [f64]) -> Result<(), RunError> {
            if run == 5 {
                return Err(RunError::Kernel("diverged".into()));
            }
            if run == 7 {
                panic!("boom");
            }
            // A SplitMix64 stream keyed by run: an independent toy stream per run.
            let mut rng = testkit::SplitMix64::new(run.wrapping_mul(0xD1B5_4A32_D192_ED03));
            let mut x = 0.0;
            for cp in 0..3 {
                for _ in 0..100 {
                    x += rng.centred();
                }
                out[cp * 2] = x;
                out[cp * 2 + 1] = x.abs();
            }
            Ok(())
        }
    }

    /// The walk, with a panic at run 9 as well, advanced in groups of `lanes` (the trait's
    /// default `run_lanes`, so the panic leaves the group's other runs unfinished).
    struct GroupedWalk {
        lanes: usize,
    }
    impl RunKernel for GroupedWalk {
        fn checkpoints(&self) -> usize {
            Walk.checkpoints()
        }
        fn quantities(&self) -> usize {
            Walk.quantities()
        }
        fn run(&self, run: u64, out: &mut [f64]) -> Result<(), RunError> {
            if run == 9 {
                panic!("boom 9");
            }
            Walk.run(run, out)
        }
        fn lanes(&self) -> usize {
            self.lanes
        }
    }

    #[test]
    fn a_panicking_group_is_run_again_one_by_one() {
        // Groups of four: run 9 panics inside the group 8..12, whose runs are then run alone.
        let grouped = run_range(&GroupedWalk { lanes: 4 }, 0..30, &|_| {});
        let single = run_range(&GroupedWalk { lanes: 1 }, 0..30, &|_| {});
        assert_eq!(grouped, single);
        let failed: Vec<u64> = grouped.failures.iter().map(|f| f.run).collect();
        assert_eq!(failed, vec![5, 7, 9]);
        assert_eq!(grouped.failures[2].message, "run panicked: boom 9");
        assert_eq!(grouped.matrix.runs(), 27);
    }

    fn with_threads<T: Send>(n: usize, f: impl FnOnce() -> T + Send) -> T {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
            .install(f)
    }

    #[test]
    fn thread_count_and_shards_do_not_change_results() {
        let one = with_threads(1, || run_range(&Walk, 0..300, &|_| {}));
        let four = with_threads(4, || run_range(&Walk, 0..300, &|_| {}));
        assert_eq!(one, four);
        let parts: Vec<BatchResult> = (0..4)
            .map(|i| {
                let shard = Shard { index: i, count: 4 };
                run_range(&Walk, shard.runs(300), &|_| {})
            })
            .collect();
        let merged = RunMatrix::merge(parts.iter().map(|p| p.matrix.clone()).collect()).unwrap();
        assert_eq!(merged, one.matrix);
        let bits = |m: &RunMatrix| -> Vec<u64> {
            (0..3)
                .flat_map(|c| (0..2).map(move |h| (c, h)))
                .flat_map(|(c, h)| {
                    m.series(c, h)
                        .iter()
                        .map(|v| v.to_bits())
                        .collect::<Vec<_>>()
                })
                .collect()
        };
        assert_eq!(bits(&merged), bits(&one.matrix));
    }

    #[test]
    fn a_stopped_range_reports_nothing() {
        let stop = AtomicBool::new(false);
        let whole = run_range_until(&Walk, 0..200, &|_| {}, &stop);
        assert_eq!(whole, Some(run_range(&Walk, 0..200, &|_| {})));
        // Stopped from the progress callback after the first block: no partial result.
        let stopped = run_range_until(
            &Walk,
            0..200,
            &|_| stop.store(true, Ordering::Relaxed),
            &stop,
        );
        assert_eq!(stopped, None);
    }

    #[test]
    fn failed_runs_are_reported_not_fatal() {
        let r = run_range(&Walk, 0..10, &|_| {});
        assert_eq!(r.matrix.runs(), 8);
        assert_eq!(r.failures.len(), 2);
        assert_eq!(r.failures[0].run, 5);
        assert_eq!(r.failures[0].message, "diverged");
        assert_eq!(r.failures[1].run, 7);
        assert!(r.failures[1].message.contains("boom"));
    }

    #[test]
    fn shards_partition_runs() {
        for runs in [0u64, 1, 7, 100, 2001] {
            for k in 1..9u64 {
                let mut next = 0;
                for i in 0..k {
                    let r = Shard { index: i, count: k }.runs(runs);
                    assert_eq!(r.start, next);
                    next = r.end;
                }
                assert_eq!(next, runs);
            }
        }
        assert_eq!(Shard::parse("2/4").unwrap(), Shard { index: 2, count: 4 });
        for bad in ["4/4", "1", "a/2", "0/0", "-1/3"] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
    }
}
