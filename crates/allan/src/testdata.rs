//! Where tests find the real measured data and the reference tables (`shared/data`).
//!
//! Rule (team contract): the directory comes from the environment variable `IMUDRIFT_DATA`
//! (`.ci/run` sets it). If it is unset, `<workspace root>/../shared/data` is used when it exists;
//! otherwise tests print a notice and skip. If it is set, a missing file is a test failure.

use std::path::PathBuf;

/// The data directory, or `None` (after printing a notice) when no data is available.
pub fn data_dir() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os("IMUDRIFT_DATA") {
        let dir = PathBuf::from(dir);
        assert!(
            dir.is_dir(),
            "IMUDRIFT_DATA={} is set but is not a directory",
            dir.display()
        );
        return Some(dir);
    }
    // crates/<name> -> workspace root -> ../shared/data
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    for root in manifest.ancestors() {
        let candidate = root.join("../shared/data");
        if root.join("Cargo.lock").exists() && candidate.is_dir() {
            return Some(candidate);
        }
    }
    eprintln!("notice: IMUDRIFT_DATA is not set and ../shared/data was not found: skipping");
    None
}

/// `data_dir()/relative`, asserting the file exists when the data directory is known.
pub fn data_file(relative: &str) -> Option<PathBuf> {
    let path = data_dir()?.join(relative);
    assert!(path.exists(), "missing reference file {}", path.display());
    Some(path)
}
