//! Helpers shared by the end-to-end tests of the `imudrift` binary.

use std::path::PathBuf;
use std::process::Output;

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

/// Run `imudrift ARGS...` in the workspace root.
#[allow(dead_code)] // not every test file runs the binary this way
pub fn imudrift(args: &[&str]) -> Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_imudrift"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("run imudrift")
}
