//! Output files that are never partial, never mixed and never left behind.
//!
//! - Every file is written to a temporary file in the destination directory and renamed into
//!   place only when complete, so an error or a kill never leaves a partial file under the final
//!   name. A path that is a symbolic link is written through (its target is replaced, the link
//!   stays), and an existing file keeps its permissions.
//! - Temporary files are registered while they exist; SIGINT, SIGTERM and SIGHUP remove them
//!   before the process exits, and wait for a set of output files being moved into place to be
//!   complete (a `kill -9` cannot be caught: it may leave a `.tmp*` file, never a partial output).
//! - `--out DIR` is created, checked writable and locked (`DIR/.imudrift.lock`) before any work,
//!   so two runs writing the same directory cannot interleave their files.
//! - No output replaces one of the command's inputs: the inputs are noted ([`note_inputs`]) and an
//!   output path that is the same file (same device and inode, through links; else the same
//!   canonical path) is refused before any work ([`refuse_input_as_output`], and for `--out`
//!   the names every command writes there), and again by [`write_atomic`] before it writes.

use anyhow::{bail, Context, Result};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;

/// The files the command reads, with their identity.
static INPUTS: Mutex<Vec<(PathBuf, FileId)>> = Mutex::new(Vec::new());

/// What makes two paths the same file: device and inode on Unix, else the canonical path.
#[derive(Clone, Debug, PartialEq, Eq)]
enum FileId {
    #[cfg(unix)]
    Inode(u64, u64),
    #[cfg(not(unix))]
    Canonical(PathBuf),
}

fn file_id(path: &Path) -> Option<FileId> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let m = std::fs::metadata(path).ok()?;
        Some(FileId::Inode(m.dev(), m.ino()))
    }
    #[cfg(not(unix))]
    {
        std::fs::canonicalize(path).ok().map(FileId::Canonical)
    }
}

/// Note the files the command reads (a path that does not exist yet is not noted: reading it
/// fails on its own).
pub fn note_inputs<P: AsRef<Path>>(paths: impl IntoIterator<Item = P>) {
    if let Ok(mut list) = INPUTS.lock() {
        for p in paths {
            let p = p.as_ref();
            if let Some(id) = file_id(p) {
                list.push((p.to_path_buf(), id));
            }
        }
    }
}

/// The noted input that `path` is the same file as, if any.
fn input_at(path: &Path) -> Option<PathBuf> {
    let id = file_id(path)?;
    let list = INPUTS.lock().ok()?;
    list.iter().find(|(_, i)| *i == id).map(|(p, _)| p.clone())
}

/// Refuse an output `path` (set by `setting`, e.g. `-o`) that is one of the noted inputs:
/// writing it would replace what the command reads (`allan log.csv --kalibr log.csv`).
pub fn refuse_input_as_output(setting: &str, path: &Path) -> Result<()> {
    if let Some(input) = input_at(path) {
        bail!(
            "{setting} {}: is the same file as the input {}: writing it would replace the input; choose another output path",
            path.display(),
            input.display()
        );
    }
    Ok(())
}

/// The file names the commands write into `--out DIR` (and every `.svg`).
const OUT_NAMES: [&str; 9] = [
    "allan.csv",
    "allan.json",
    "diagnose.json",
    "report.md",
    "drift.json",
    "drift.csv",
    "spec.json",
    "spec.csv",
    "drift.svg",
];

/// Refuse an `--out DIR` holding an input under a name the commands write there.
fn refuse_inputs_in_out_dir(dir: &Path) -> Result<()> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let written = OUT_NAMES.contains(&name.as_str()) || name.ends_with(".svg");
        if written {
            refuse_input_as_output("--out", &entry.path())?;
        }
    }
    Ok(())
}

/// Temporary files that exist now (removed on a termination signal).
static TEMPORARIES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
/// Output sets being written now (a signal waits until they are complete).
static SETS_OPEN: AtomicUsize = AtomicUsize::new(0);
/// A termination signal arrived while a set was being written.
static EXIT_PENDING: AtomicBool = AtomicBool::new(false);

/// The stop flag of the libraries' long loops (`montecarlo::run_range_until`,
/// `diagnose::diagnose_until`, `diagnose::drift_check::check_drift_until`): set by the signal
/// handler, so that a run whose exit waits for an output set stops its work meanwhile.
pub static STOP: AtomicBool = AtomicBool::new(false);

/// The `--out` lock files held now (removed on a termination signal, as on a normal exit).
static HELD_LOCKS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn exit_interrupted() -> ! {
    for list in [&TEMPORARIES, &HELD_LOCKS] {
        if let Ok(list) = list.lock() {
            for p in list.iter() {
                let _ = std::fs::remove_file(p);
            }
        }
    }
    tell!("interrupted");
    std::process::exit(130);
}

/// Remove the registered temporary files and the `--out` lock files held (the lock is released
/// by the exit itself) when SIGINT, SIGTERM or SIGHUP arrives, then exit with
/// 128 + 2 as a shell does for an interrupt; while a set of output files is being moved into
/// place, the exit waits until the set is complete, so `--out` never holds files of two runs.
/// Called once at start-up.
pub fn clean_up_on_signals() {
    let _ = ctrlc::set_handler(|| {
        STOP.store(true, Ordering::SeqCst);
        if SETS_OPEN.load(Ordering::SeqCst) > 0 {
            EXIT_PENDING.store(true, Ordering::SeqCst);
        } else {
            exit_interrupted();
        }
    });
}

/// The files of one `--out` set being written: a termination signal meanwhile takes effect when
/// the set is complete (when this is dropped).
#[must_use = "the set is protected only while this value lives"]
pub struct FileSet(());

impl Drop for FileSet {
    fn drop(&mut self) {
        if SETS_OPEN.fetch_sub(1, Ordering::SeqCst) == 1 && EXIT_PENDING.load(Ordering::SeqCst) {
            exit_interrupted();
        }
    }
}

/// Start writing the set of files of `--out DIR` (creating DIR if needed).
pub fn begin_set(dir: &Path) -> Result<FileSet> {
    ensure_dir(dir)?;
    SETS_OPEN.fetch_add(1, Ordering::SeqCst);
    Ok(FileSet(()))
}

/// A registered temporary file: unregistered when dropped.
struct Registered(PathBuf);

impl Registered {
    fn new(path: &Path) -> Registered {
        if let Ok(mut list) = TEMPORARIES.lock() {
            list.push(path.to_path_buf());
        }
        Registered(path.to_path_buf())
    }
}

impl Drop for Registered {
    fn drop(&mut self) {
        if let Ok(mut list) = TEMPORARIES.lock() {
            list.retain(|p| p != &self.0);
        }
    }
}

/// The file a write to `path` must replace: the target of a symbolic link, else `path`.
fn destination(path: &Path) -> PathBuf {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => {
            std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
        }
        _ => path.to_path_buf(),
    }
}

/// Write `path` atomically: `fill` writes into a buffered temporary file beside `path`,
/// which replaces `path` only if `fill` and the final flush succeed.
pub fn write_atomic<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> Result<()>,
{
    if let Some(input) = input_at(path) {
        bail!(
            "{}: is the same file as the input {}: refusing to replace an input with an output; choose another output path",
            path.display(),
            input.display()
        );
    }
    if path.is_dir() {
        bail!(
            "{}: is a directory; give the name of a file to write",
            path.display()
        );
    }
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
    let target = destination(path);
    let dir = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let tmp = tempfile::NamedTempFile::new_in(&dir)
        .with_context(|| format!("cannot create a temporary file in {}", dir.display()))?;
    let _registered = Registered::new(tmp.path());
    {
        let mut w = BufWriter::with_capacity(1 << 20, tmp.as_file());
        fill(&mut w).with_context(|| format!("while writing {}", path.display()))?;
        w.flush()
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    // An existing file keeps its permissions; a new one gets those a plainly created file has
    // (NamedTempFile makes 0600 files; 0644 approximates 0666 less the usual umask).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(&target).map_or(0o644, |m| m.permissions().mode());
        let _ = std::fs::set_permissions(tmp.path(), std::fs::Permissions::from_mode(mode));
    }
    tmp.persist(&target)
        .with_context(|| format!("cannot move the finished file to {}", path.display()))?;
    Ok(())
}

/// Print `text` on standard output, flushed: a closed pipe (`| head -c 10`) or a full disk is
/// an error the command reports (status 1), never a panic as `print!` gives.
pub fn print_stdout(text: &str) -> Result<()> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .context("cannot write to standard output")
}

/// A command's answer, by the one convention of every command (docs/cli.md, "Conventions shared
/// by every command"): the human text on stdout, or with `--json` the JSON document on stdout and
/// the text on stderr (so a person watching still reads it). Progress, notes and warnings go to
/// stderr elsewhere.
pub fn answer(text: &str, json: Option<&str>) -> Result<()> {
    match json {
        Some(doc) => {
            let _ = std::io::stderr().lock().write_all(text.as_bytes());
            print_stdout(doc)
        }
        None => print_stdout(text),
    }
}

/// Write a string atomically.
pub fn write_string(path: &Path, text: &str) -> Result<()> {
    write_atomic(path, |w| Ok(w.write_all(text.as_bytes())?))
}

/// The lock on an `--out` directory, held until dropped (the end of the command); `None` inside
/// for directories shared on purpose (shards of one job write distinct files into one directory).
#[must_use = "the directory is locked only while this value lives"]
pub struct OutLock {
    _file: Option<std::fs::File>,
    /// The lock file, removed when the lock is dropped (no `.imudrift.lock` is left behind).
    path: Option<std::path::PathBuf>,
}

impl Drop for OutLock {
    /// Remove the lock file while still holding the lock: a run waiting on the same file finds,
    /// once it holds it, that the path no longer names it, and starts over ([`prepare_dir`]).
    fn drop(&mut self) {
        if let Some(path) = self.path.take() {
            if let Ok(mut list) = HELD_LOCKS.lock() {
                list.retain(|p| p != &path);
            }
            let _ = std::fs::remove_file(path);
        }
    }
}

/// Check a directory shared by design (shard files): create it and make sure a file can be
/// written there, without locking it.
pub fn prepare_shared_dir(dir: &Path) -> Result<OutLock> {
    ensure_dir(dir)?;
    refuse_inputs_in_out_dir(dir)?;
    tempfile::NamedTempFile::new_in(dir)
        .map(drop)
        .with_context(|| format!("--out {}: cannot write files there", dir.display()))?;
    Ok(OutLock {
        _file: None,
        path: None,
    })
}

/// Check an `--out` directory before any work: create it (and parents), make sure a file can be
/// written there, and lock it against another imudrift writing the same directory.
pub fn prepare_dir(dir: &Path) -> Result<OutLock> {
    ensure_dir(dir)?;
    refuse_inputs_in_out_dir(dir)?;
    let path = dir.join(".imudrift.lock");
    // A lock file another run removed after we opened it locks nothing: retry on a fresh one
    // (a few times: each retry means another run finished in between).
    for _ in 0..100 {
        let file = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
            .with_context(|| format!("--out {}: cannot write files there", dir.display()))?;
        match file.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => bail!(
                "--out {}: another imudrift is writing to this directory; wait for it or choose another --out",
                dir.display()
            ),
            Err(std::fs::TryLockError::Error(e)) => {
                return Err(e).with_context(|| {
                    format!("--out {}: cannot lock the directory", dir.display())
                })
            }
        }
        if same_file(&file, &path) {
            if let Ok(mut list) = HELD_LOCKS.lock() {
                list.push(path.clone());
            }
            return Ok(OutLock {
                _file: Some(file),
                path: Some(path),
            });
        }
    }
    bail!(
        "--out {}: cannot lock the directory (its lock file keeps being replaced)",
        dir.display()
    )
}

/// Whether the open `file` is the one `path` names now (same device and inode).
fn same_file(file: &std::fs::File, path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (file.metadata(), std::fs::metadata(path)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = (file, path);
        true
    }
}

/// Create the `--out` directory (and parents) if needed.
pub fn ensure_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create directory {}", dir.display()))
}
