//! A file's bytes (mapped or read) and the memory check made before parsing them.

use crate::error::{LogError, Result};
use std::io::Read;
use std::path::Path;

/// A file's bytes: mapped read-only from the page cache on Linux (`memmap2`) (no copy into a fresh buffer:
/// for a 22 MB log that copy and the zeroing of its pages cost more than parsing half of it;
/// pages are faulted in by the parsing threads, in parallel),
/// else read into memory.
pub(crate) enum FileBytes {
    Mapped(memmap2::Mmap),
    Read(Vec<u8>),
}

impl FileBytes {
    pub(crate) fn open(path: &Path) -> std::io::Result<FileBytes> {
        let file = std::fs::File::open(path)?;
        let meta = file.metadata()?;
        if cfg!(target_os = "linux") && meta.is_file() && meta.len() >= 1 << 20 {
            // SAFETY: a read-only private mapping of a regular file this process holds open;
            // the bytes are only read. If another process truncates the file during the read,
            // access past the new end raises SIGBUS: the hazard every mmap-based reader accepts.
            if let Ok(map) = unsafe { memmap2::Mmap::map(&file) } {
                return Ok(FileBytes::Mapped(map));
            }
        }
        if !meta.is_file() {
            // A device or a pipe (/dev/zero, a FIFO) has no size to check: read it with a bound.
            let limit = available_memory_bytes()
                .map_or(MAX_STREAM_BYTES, |a| (a / 3).min(MAX_STREAM_BYTES));
            let mut buf = Vec::new();
            (&file).take(limit + 1).read_to_end(&mut buf)?;
            if buf.len() as u64 > limit {
                return Err(std::io::Error::other(format!(
                    "not a regular file (a device or a pipe) and it gives more than {:.2} GiB (the most read from a stream, at most a third of the memory available); save the log to a file",
                    limit as f64 / GIB
                )));
            }
            return Ok(FileBytes::Read(buf));
        }
        let mut buf = Vec::with_capacity(meta.len() as usize + 1);
        (&file).read_to_end(&mut buf)?;
        Ok(FileBytes::Read(buf))
    }
}

impl std::ops::Deref for FileBytes {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        match self {
            FileBytes::Mapped(map) => map,
            FileBytes::Read(v) => v,
        }
    }
}

/// Ask Linux for transparent huge pages on a large buffer not yet written to (a hint: fewer
/// page faults, and cheaper ones, when it is first filled; measured 13 ms of kernel time per
/// 35 MB column with 4 KiB pages). Does nothing elsewhere, for small buffers, or if refused.
pub(crate) fn advise_huge_pages<T>(buf: &[T]) {
    #[cfg(target_os = "linux")]
    {
        const HUGE: usize = 2 << 20;
        let start = buf.as_ptr() as usize;
        let end = start + std::mem::size_of_val(buf);
        let first = (start + HUGE - 1) & !(HUGE - 1);
        if end >= first + HUGE {
            // SAFETY: the range lies inside `buf`'s allocation (whole 2 MiB units from the
            // first aligned address); MADV_HUGEPAGE changes no contents, only how the pages
            // are backed.
            unsafe {
                libc::madvise(
                    first as *mut libc::c_void,
                    (end - first) & !(HUGE - 1),
                    libc::MADV_HUGEPAGE,
                );
            }
        }
    }
}

pub(crate) const GIB: f64 = (1u64 << 30) as f64;

/// Most bytes read from a file that is not a regular file (a device, a pipe): 1 GiB.
const MAX_STREAM_BYTES: u64 = 1 << 30;

/// Memory the system can still give (Linux `MemAvailable`), bytes, or less when the environment
/// variable `IMUDRIFT_MEMORY_LIMIT` (bytes) says so (a share of a shared machine); `None` when
/// neither is known.
pub fn available_memory_bytes() -> Option<u64> {
    let system = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|info| {
            let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
            let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(kib * 1024)
        });
    let limit = std::env::var("IMUDRIFT_MEMORY_LIMIT")
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok());
    match (system, limit) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// Refuse a log whose parsed columns (8 bytes per value, and as much again for the analyses'
/// working copies) would not fit in the memory available.
pub(crate) fn check_fits(bytes: &[u8], source: &str, available: Option<u64>) -> Result<()> {
    let Some(available) = available else {
        return Ok(());
    };
    // Values are at least 2 bytes of text each ("0,"): an upper bound without a scan.
    let upper = bytes.len() as u64 / 2 * 16;
    if upper <= available {
        return Ok(());
    }
    let rows = bytes.iter().filter(|&&b| b == b'\n').count() as u64;
    let first = bytes
        .iter()
        .position(|&b| b == b'\n')
        .unwrap_or(bytes.len());
    let cols = bytes[..first].iter().filter(|&&b| b == b',').count() as u64 + 1;
    let need = rows * cols * 16;
    if need > available {
        let problem = format!(
            "{rows} rows x {cols} columns need about {:.1} GiB to analyse, and {:.1} GiB is available: split the log, or drop columns you do not need",
            need as f64 / GIB,
            available as f64 / GIB
        );
        return Err(LogError::content(source, problem));
    }
    Ok(())
}
