//! Issue 46, item 8: `IMUDRIFT_MEMORY_LIMIT` bounds the whole process. With a limit of 60 MB,
//! `simulate` of 27 000 runs peaked at 72.3 MB (the limit was compared with the per-run values
//! alone, which grew by doubling); with `--ablation` and a 20 MB limit, at 65.6 MB. Now a
//! simulation the limit cannot hold is refused up front, and one it can stays below it.
//! Its own test binary, so that the peak of its children (`getrusage(RUSAGE_CHILDREN)`) is
//! only theirs. Against another build: `IMUDRIFT_TEST_BIN=... cargo test --release --test
//! memory_bound`.

mod common;
use common::command;

/// Peak resident memory of this process's finished children, bytes (Linux: ru_maxrss in KiB).
fn children_peak_bytes() -> u64 {
    // SAFETY: getrusage fills the struct it is given.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    assert_eq!(
        unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut usage) },
        0
    );
    usage.ru_maxrss as u64 * 1024
}

#[test]
fn the_memory_limit_bounds_the_whole_process() {
    let run = |limit: &str, extra: &[&str]| {
        command()
            .args(["simulate", "configs/sensors/mtx.toml", "--duration", "1"])
            .args(extra)
            .env("IMUDRIFT_MEMORY_LIMIT", limit)
            .output()
            .expect("run imudrift")
    };
    for (limit, extra) in [
        ("60000000", &["--runs", "27000"][..]),
        ("20000000", &["--runs", "9000", "--ablation"][..]),
        ("20000000", &["--runs", "3000"][..]),
    ] {
        let out = run(limit, extra);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{extra:?}: {err}");
        assert!(err.contains("the memory available"), "{extra:?}: {err}");
    }
    // What the limit can hold runs, and its peak stays below the limit (the smaller limit first:
    // the peak is the largest of every child's so far).
    for (limit, extra) in [
        (20_000_000u64, &["--runs", "150", "--ablation"][..]),
        // 18 000 runs keep 37.8 MiB of per-run values, 4 MiB inside the 41.9 MiB the 60 MB limit
        // leaves; 20 000 (42.0 MiB) sat on the edge and was refused where the process held a
        // little more at the check (a fresh clone's test run).
        (60_000_000, &["--runs", "18000"][..]),
    ] {
        let out = run(&limit.to_string(), extra);
        assert!(
            out.status.success(),
            "{extra:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let peak = children_peak_bytes();
        assert!(
            peak < limit,
            "{extra:?}: peak {peak} bytes above the limit {limit}"
        );
    }
}
