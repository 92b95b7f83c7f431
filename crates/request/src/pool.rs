//! The one worker pool of a request: `threads` workers (absent or 0: one per core). Results never
//! depend on the count; a count beyond [`max_threads`] is refused rather than started. A front
//! end builds the pool per call (Python: dropped when the call returns, so a process forked
//! afterwards inherits no pool).

use crate::error::{RequestError, Result};

/// Most worker threads a request may start: four per core, and at least 64.
pub fn max_threads() -> usize {
    (cores() * 4).max(64)
}

fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// The pool of `threads` workers (None or 0: one per core).
pub fn pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    let n = threads.unwrap_or(0);
    if n > max_threads() {
        return Err(RequestError::Threads {
            n,
            max: max_threads(),
            cores: cores(),
        });
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map_err(|e| RequestError::PoolStart(e.to_string()))
}
