//! Helpers shared by the end-to-end tests of the `imudrift` binary.

#![allow(dead_code)] // each test file uses a part

use std::path::PathBuf;
use std::process::{Command, Output};

/// The workspace root (where `configs/` lives).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Assert the command succeeded, showing its stderr if not.
pub fn ok(out: Output) -> Output {
    assert!(
        out.status.success(),
        "imudrift failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The `imudrift` binary under test: the one cargo built with the tests, or the one the
/// environment variable `IMUDRIFT_TEST_BIN` names (to run the same tests against another build,
/// e.g. an older commit's, and see which fail there: `IMUDRIFT_TEST_BIN=/path/to/imudrift cargo
/// test --release --test bad_inputs`).
pub fn binary() -> PathBuf {
    match std::env::var_os("IMUDRIFT_TEST_BIN") {
        Some(path) => PathBuf::from(path),
        None => PathBuf::from(env!("CARGO_BIN_EXE_imudrift")),
    }
}

/// The `imudrift` binary as a command to complete, run in the workspace root.
pub fn command() -> Command {
    let mut c = Command::new(binary());
    c.current_dir(root());
    c
}

/// Run `imudrift ARGS...` in the workspace root.
pub fn imudrift(args: &[&str]) -> Output {
    command().args(args).output().expect("run imudrift")
}
