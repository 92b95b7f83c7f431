#![allow(dead_code)] // used by the commands as they land
//! Atomic output files: everything is written to a temporary file in the destination
//! directory and renamed into place only when complete, so an error never leaves a
//! partial output file behind.

use anyhow::{Context, Result};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Write `path` atomically: `fill` writes into a buffered temporary file beside `path`,
/// which replaces `path` only if `fill` and the final flush succeed.
pub fn write_atomic<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> Result<()>,
{
    // A device or FIFO (/dev/null, /dev/stdout, a pipe) is written directly: renaming a
    // temporary file over it would replace the device itself.
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir()) {
        let file = std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .with_context(|| format!("cannot open {}", path.display()))?;
        let mut w = BufWriter::with_capacity(1 << 20, file);
        fill(&mut w).with_context(|| format!("while writing {}", path.display()))?;
        return w
            .flush()
            .with_context(|| format!("cannot write {}", path.display()));
    }
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let tmp = tempfile::NamedTempFile::new_in(&dir)
        .with_context(|| format!("cannot create a temporary file in {}", dir.display()))?;
    {
        let mut w = BufWriter::with_capacity(1 << 20, tmp.as_file());
        fill(&mut w).with_context(|| format!("while writing {}", path.display()))?;
        w.flush()
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    // NamedTempFile creates 0600 files; give the output the mode a plainly created file would
    // have (0666 less the umask, approximated by the common 0644).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let _ = std::fs::set_permissions(tmp.path(), std::fs::Permissions::from_mode(0o644));
    }
    tmp.persist(path)
        .with_context(|| format!("cannot move the finished file to {}", path.display()))?;
    Ok(())
}

/// Write a string atomically.
pub fn write_string(path: &Path, text: &str) -> Result<()> {
    write_atomic(path, |w| Ok(w.write_all(text.as_bytes())?))
}

/// Check an `--out` directory before any work: create it (and parents) and make sure a file can be
/// written there, so a long run does not end in "cannot create directory".
pub fn prepare_dir(dir: &Path) -> Result<()> {
    ensure_dir(dir)?;
    tempfile::NamedTempFile::new_in(dir)
        .map(drop)
        .with_context(|| format!("--out {}: cannot write files there", dir.display()))
}

/// Create the `--out` directory (and parents) if needed.
pub fn ensure_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create directory {}", dir.display()))
}
