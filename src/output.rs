//! Output files that are never partial, never mixed and never left behind.
//!
//! - Every file is written to a temporary file `.imudrift-partial-<pid>-<n>-<name>` in the
//!   destination directory and renamed into place only when complete, so an error or a kill
//!   never leaves a partial file under the final name. A path that is a symbolic link is written
//!   through (its target is replaced, the link stays), and an existing file keeps its
//!   permissions.
//! - The files of one command (its `--out DIR` files, `--kalibr`, ...) are one set
//!   ([`begin_set`]): each is written to its temporary file, and all are renamed into place only
//!   when every one of them is complete ([`FileSet::commit`]); on an error (a full disk) the
//!   temporaries are removed and no new file appears (the files already there stay as they were).
//! - Temporary files are registered while they exist; SIGINT, SIGTERM and SIGHUP remove them
//!   before the process exits, and wait for a set of output files being moved into place to be
//!   complete. A `kill -9` cannot be caught: it may leave a `.imudrift-partial-*` file (never a
//!   partial output), which the next run writing into that directory removes: a temporary whose
//!   process is gone (no `/proc/<pid>`) and that no process holds locked ([`remove_leftovers`]).
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

/// The files of one command's output set: written into temporaries, moved into place together
/// by [`FileSet::commit`]; dropped without it (an error), the temporaries are removed. A
/// termination signal meanwhile takes effect when the set is done (when this is dropped).
#[must_use = "the files are moved into place only by commit"]
pub struct FileSet(());

/// The finished temporary files of the open set, each with the path it replaces and the path
/// named in messages.
static PENDING: Mutex<Vec<(tempfile::NamedTempFile, PathBuf, PathBuf)>> = Mutex::new(Vec::new());

impl FileSet {
    /// Move every file of the set into place (renames in their own directories: the files are
    /// complete already, so only a rename refused midway could leave part of a set).
    pub fn commit(self) -> Result<()> {
        let pending = std::mem::take(&mut *PENDING.lock().unwrap_or_else(|e| e.into_inner()));
        let mut result = Ok(());
        for (tmp, target, shown) in pending {
            if result.is_ok() {
                let path = tmp.path().to_path_buf();
                result = tmp.persist(&target).map(drop).with_context(|| {
                    format!("cannot move the finished file to {}", shown.display())
                });
                unregister(&path);
            }
            // After a failed rename, the remaining temporaries are dropped (removed) here.
        }
        result
    }
}

impl Drop for FileSet {
    fn drop(&mut self) {
        // Not committed (an error): remove the temporaries, no file of the set appears.
        let pending = std::mem::take(&mut *PENDING.lock().unwrap_or_else(|e| e.into_inner()));
        for (tmp, _, _) in pending {
            let path = tmp.path().to_path_buf();
            drop(tmp);
            unregister(&path);
        }
        if SETS_OPEN.fetch_sub(1, Ordering::SeqCst) == 1 && EXIT_PENDING.load(Ordering::SeqCst) {
            exit_interrupted();
        }
    }
}

/// Start the set of a command's output files: every [`write_atomic`] until the set is committed
/// or dropped writes a temporary file that [`FileSet::commit`] moves into place with the others.
pub fn begin_set() -> FileSet {
    SETS_OPEN.fetch_add(1, Ordering::SeqCst);
    FileSet(())
}

/// Start the set of files of `--out DIR` (creating DIR if needed): [`begin_set`].
pub fn begin_out_set(dir: &Path) -> Result<FileSet> {
    ensure_dir(dir)?;
    Ok(begin_set())
}

/// A registered temporary file: unregistered when dropped.
struct Registered(PathBuf);

impl Registered {
    fn new(path: &Path) -> Registered {
        register(path);
        Registered(path.to_path_buf())
    }
}

fn register(path: &Path) {
    if let Ok(mut list) = TEMPORARIES.lock() {
        list.push(path.to_path_buf());
    }
}

impl Drop for Registered {
    fn drop(&mut self) {
        unregister(&self.0);
    }
}

fn unregister(path: &Path) {
    if let Ok(mut list) = TEMPORARIES.lock() {
        list.retain(|p| p != path);
    }
}

/// The name every temporary output file starts with; then the writing process's id, `-`, a
/// number and `-` and the name of the file it becomes.
const PARTIAL_PREFIX: &str = ".imudrift-partial-";

/// Temporary files made by this process (numbers them, so two never share a name).
static PARTIAL_COUNT: AtomicUsize = AtomicUsize::new(0);

/// Create the temporary file for `target` in `dir`, locked (so another run sees it is in use),
/// removing first the leftovers of dead runs there.
fn create_partial(dir: &Path, target: &Path) -> std::io::Result<tempfile::NamedTempFile> {
    remove_leftovers(dir);
    let name = target.file_name().map_or_else(String::new, |n| {
        // Short enough that the prefix, pid and number keep it within 255 bytes.
        let n = n.to_string_lossy();
        let mut end = n.len().min(200);
        while !n.is_char_boundary(end) {
            end -= 1;
        }
        n[..end].to_string()
    });
    let n = PARTIAL_COUNT.fetch_add(1, Ordering::SeqCst);
    let prefix = format!("{PARTIAL_PREFIX}{}-{n}-{name}", std::process::id());
    let tmp = match tempfile::Builder::new()
        .prefix(&prefix)
        .rand_bytes(0)
        .tempfile_in(dir)
    {
        // The leftover of a dead process that had our id (no file of ours has this number).
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
            let _ = std::fs::remove_file(dir.join(&prefix));
            tempfile::Builder::new()
                .prefix(&prefix)
                .rand_bytes(0)
                .tempfile_in(dir)?
        }
        other => other?,
    };
    // An advisory lock held while the file is open: a run cleaning leftovers skips a locked one
    // (a live writer whose pid it cannot see, in another pid namespace).
    let _ = tmp.as_file().try_lock();
    Ok(tmp)
}

/// Directories whose leftovers this process has removed already.
static CLEANED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Remove from `dir` (once per process) the temporary files of runs that died (`kill -9`, a power
/// loss): regular files named exactly `.imudrift-partial-<pid>-<n>-<name>` whose process no
/// longer exists and that no process holds locked. Anything else is left alone.
pub fn remove_leftovers(dir: &Path) {
    {
        let Ok(mut cleaned) = CLEANED.lock() else {
            return;
        };
        if cleaned.iter().any(|d| d == dir) {
            return;
        }
        cleaned.push(dir.to_path_buf());
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(leftover_pid) else {
            continue;
        };
        if pid == std::process::id() || process_alive(pid) {
            continue;
        }
        let path = entry.path();
        let regular = std::fs::symlink_metadata(&path).is_ok_and(|m| m.file_type().is_file());
        if regular && !locked(&path) {
            let _ = std::fs::remove_file(&path);
        }
    }
}

/// The process id of a temporary file's name `.imudrift-partial-<pid>-<n>-<name>`, if the name
/// is exactly of that form.
fn leftover_pid(name: &str) -> Option<u32> {
    let rest = name.strip_prefix(PARTIAL_PREFIX)?;
    let (pid, rest) = rest.split_once('-')?;
    let (n, rest) = rest.split_once('-')?;
    let digits = |s: &str| !s.is_empty() && s.len() <= 10 && s.bytes().all(|b| b.is_ascii_digit());
    if !digits(pid) || !digits(n) || rest.is_empty() {
        return None;
    }
    pid.parse().ok().filter(|&p| p > 0)
}

/// Whether process `pid` exists (Linux: `/proc/<pid>`; elsewhere assumed, so nothing is removed).
fn process_alive(pid: u32) -> bool {
    if cfg!(target_os = "linux") && Path::new("/proc/self").exists() {
        Path::new("/proc").join(pid.to_string()).exists()
    } else {
        true
    }
}

/// Whether another open file description holds a lock on `path` (a writer still at work).
fn locked(path: &Path) -> bool {
    match std::fs::File::open(path) {
        Ok(f) => matches!(f.try_lock(), Err(std::fs::TryLockError::WouldBlock)),
        Err(_) => true,
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
    let tmp = create_partial(&dir, &target)
        .with_context(|| format!("cannot create a temporary file in {}", dir.display()))?;
    let registered = Registered::new(tmp.path());
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
    if SETS_OPEN.load(Ordering::SeqCst) > 0 {
        // Part of a set: moved into place with the others by `FileSet::commit`, registered
        // until then.
        drop(registered);
        register(tmp.path());
        if let Ok(mut pending) = PENDING.lock() {
            pending.push((tmp, target, path.to_path_buf()));
            return Ok(());
        }
        unregister(tmp.path());
        bail!(
            "cannot write {}: the output set is unusable",
            path.display()
        );
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
    create_partial(dir, Path::new("check"))
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
