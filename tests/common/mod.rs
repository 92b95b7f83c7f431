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

/// The `imudrift` binary as a command to complete, run in the workspace root.
pub fn command() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_imudrift"));
    c.current_dir(root());
    c
}

/// Run `imudrift ARGS...` in the workspace root.
pub fn imudrift(args: &[&str]) -> Output {
    command().args(args).output().expect("run imudrift")
}
