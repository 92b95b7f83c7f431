//! Where tests find the real measured data and the reference tables: the directory named by the
//! environment variable `IMUDRIFT_DATA` (`.ci/run` sets it). Tests that need it are marked
//! `#[cfg_attr(imudrift_no_data, ignore = ...)]` (the build script sets that cfg when the variable
//! is unset), so without the data they show as ignored in the test summary. Run anyway (e.g.
//! `--include-ignored`) without the data, they fail with this explanation instead of passing.

use std::path::PathBuf;

/// The data directory named by `IMUDRIFT_DATA`.
pub fn data_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("IMUDRIFT_DATA").map(PathBuf::from);
    match dir {
        Some(dir) if dir.is_dir() => Some(dir),
        Some(dir) => panic!(
            "IMUDRIFT_DATA={} is set but is not a directory",
            dir.display()
        ),
        None => panic!(
            "this test needs the real IMU logs and reference tables: set IMUDRIFT_DATA to their directory"
        ),
    }
}

/// `data_dir()/relative`, asserting the file exists.
pub fn data_file(relative: &str) -> Option<PathBuf> {
    let path = data_dir()?.join(relative);
    assert!(path.exists(), "missing reference file {}", path.display());
    Some(path)
}
