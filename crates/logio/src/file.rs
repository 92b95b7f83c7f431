//! A file's bytes (mapped or read) and the memory check made before parsing them.

use crate::error::{byte_size, LogError, Result};
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
            // A device or a pipe (/dev/zero, a FIFO) has no size to check: read it with a bound,
            // its first block checked for NUL bytes before the rest is read.
            let limit = available_memory_bytes()
                .map_or(MAX_STREAM_BYTES, |a| (a / 3).min(MAX_STREAM_BYTES));
            return read_open_capped(&file, &meta, limit, FirstBlock::NoNul).map(FileBytes::Read);
        }
        // A small file is read whole (its memory is checked once read, with its columns'); a
        // large one that cannot be mapped must fit in a third of the memory, as a decompressed
        // log must. The first block is checked by the caller (it may be a bag).
        let limit = match available_memory_bytes() {
            Some(a) if meta.len() >= 1 << 20 => a / 3,
            _ => u64::MAX,
        };
        read_open_capped(&file, &meta, limit, FirstBlock::Any).map(FileBytes::Read)
    }
}

/// A text file's bytes, at most `max_bytes` of them: a regular file larger than that is refused
/// from its size before a byte is read (a sparse 10 GB file allocates nothing); a device or a
/// pipe, which has no size, is read up to the bound and refused past it (`/dev/zero` never
/// ends). Its first block ([`FIRST_BLOCK_BYTES`]) is checked before the rest is read: NUL bytes
/// or bytes that are not UTF-8 there refuse it at once (a binary file, a sparse file, a device of
/// zeros). The error says which, with the bound; the caller names the file and what it is.
pub fn read_capped(path: &Path, max_bytes: u64) -> std::io::Result<Vec<u8>> {
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    read_open_capped(&file, &meta, max_bytes, FirstBlock::Utf8)
}

/// Bytes of a file read and checked (text or not) before the rest is read: 64 KiB.
pub const FIRST_BLOCK_BYTES: u64 = 64 << 10;

/// What the first block of a file read with a bound must be.
#[derive(Clone, Copy, PartialEq, Eq)]
enum FirstBlock {
    /// UTF-8 text without NUL bytes (a config, a shard).
    Utf8,
    /// Without NUL bytes (a CSV log, whose parser names a byte that is not UTF-8).
    NoNul,
    /// Anything (a bag).
    Any,
}

/// Why `block`, the first bytes of a file, cannot be text: NUL bytes (a binary file, a sparse
/// file, a device of zeros) or, when `utf8`, a byte that is not UTF-8 (with its line and column,
/// as `noise::utf8_text` names one). A sequence cut by the block's end is not an error.
pub fn first_block_problem(block: &[u8], utf8: bool) -> Option<String> {
    if let Some(at) = memchr::memchr(0, block) {
        return Some(format!(
            "contains NUL bytes (the first at byte {}): not a text file",
            at + 1
        ));
    }
    if !utf8 {
        return None;
    }
    let e = std::str::from_utf8(block).err()?;
    e.error_len()?;
    let at = e.valid_up_to();
    let before = &block[..at];
    let line = memchr::memchr_iter(b'\n', before).count() + 1;
    let column = at - memchr::memrchr(b'\n', before).map_or(0, |i| i + 1) + 1;
    Some(format!(
        "line {line}, column {column}: byte 0x{:02x} is not UTF-8; save the file as UTF-8 text",
        block[at]
    ))
}

fn read_open_capped(
    file: &std::fs::File,
    meta: &std::fs::Metadata,
    max_bytes: u64,
    first: FirstBlock,
) -> std::io::Result<Vec<u8>> {
    if meta.is_file() && meta.len() > max_bytes {
        return Err(std::io::Error::other(format!(
            "it is {}, more than the {} read at most",
            byte_size(meta.len() as f64),
            byte_size(max_bytes as f64)
        )));
    }
    let capacity = if meta.is_file() { meta.len() + 1 } else { 0 };
    let mut buf = Vec::with_capacity(capacity as usize);
    // A regular file that grows while it is read is bounded too.
    let mut reader = file.take(max_bytes.saturating_add(1));
    (&mut reader)
        .take(FIRST_BLOCK_BYTES)
        .read_to_end(&mut buf)?;
    if first != FirstBlock::Any {
        if let Some(problem) = first_block_problem(&buf, first == FirstBlock::Utf8) {
            let device = if meta.is_file() {
                ""
            } else {
                "not a regular file (a device or a pipe), and it "
            };
            return Err(std::io::Error::other(format!("{device}{problem}")));
        }
    }
    reader.read_to_end(&mut buf)?;
    if buf.len() as u64 > max_bytes {
        let what = if meta.is_file() {
            "it grew while being read"
        } else {
            "not a regular file (a device or a pipe)"
        };
        return Err(std::io::Error::other(format!(
            "{what} and it gives more than {} (the most read from it); save it to a file",
            byte_size(max_bytes as f64)
        )));
    }
    Ok(buf)
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

/// Most bytes read from a file that is not a regular file (a device, a pipe): 1 GiB.
const MAX_STREAM_BYTES: u64 = 1 << 30;

/// Memory the system can still give (Linux `MemAvailable`), bytes, or less when the environment
/// variable `IMUDRIFT_MEMORY_LIMIT` (bytes) says so (a share of a shared machine); `None` when
/// neither is known. A job whose memory grows with its size (a simulation's per-run values) takes
/// what the process holds already ([`resident_bytes`]) from it.
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

/// Bytes of memory this process holds now (Linux `/proc/self/statm`, resident pages), or `None`
/// where that is not known.
pub fn resident_bytes() -> Option<u64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    // SAFETY: sysconf only reads a system constant.
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) };
    Some(pages * u64::try_from(page).ok().filter(|&p| p > 0).unwrap_or(4096))
}

/// Largest ratio of decompressed to compressed size a gzip log may have once
/// [`GZ_RATIO_FROM_BYTES`] are out: CSV logs of real sensors compress 2.4 to 7.3 times
/// (measured with gzip -9 on the ADIS16405, MTi-G and Galaxy S5 logs of docs/validation.md),
/// a log of constant columns some tens of times; deflate reaches 1032 (RFC 1951's longest match
/// of 258 bytes coded in 2 bits), which only a file made to expand (a "gzip bomb") does.
const MAX_GZ_RATIO: u64 = 100;

/// Decompressed bytes below which the ratio is not checked (a small file may compress well).
const GZ_RATIO_FROM_BYTES: u64 = 16 << 20;

/// Decompress a gzip log (RFC 1952, members one after the other), checking while it
/// decompresses, every MiB: the text within a third of the memory available, the ratio within
/// [`MAX_GZ_RATIO`], and the parsed columns' estimate of [`check_fits`] on the rows so far. A
/// file that fails one is refused after at most one MiB past the bound, never after the whole.
pub(crate) fn gunzip(raw: &[u8], source: &str, available: Option<u64>) -> Result<Vec<u8>> {
    const STEP: u64 = 1 << 20;
    let limit = available.map_or(u64::MAX, |a| a / 3);
    let mut decoder = flate2::bufread::MultiGzDecoder::new(raw);
    let mut out = Vec::with_capacity(raw.len().saturating_mul(4).min(limit as usize));
    let mut rows = Rows::default();
    loop {
        let before = out.len();
        let n = (&mut decoder)
            .take(STEP)
            .read_to_end(&mut out)
            .map_err(|e| LogError::content(source, "not a valid gzip file").caused_by(e))?;
        if n == 0 {
            return Ok(out);
        }
        if before == 0 {
            let first = &out[..out.len().min(FIRST_BLOCK_BYTES as usize)];
            if let Some(problem) = first_block_problem(first, false) {
                return Err(LogError::content(
                    source,
                    format!("decompresses to a text that {problem}"),
                ));
            }
        }
        let done = out.len() as u64;
        let consumed = (raw.len() - decoder.get_ref().len()).max(1) as u64;
        let problem = if done > limit {
            format!(
                "decompresses to more than {}, a third of the memory available ({}): split the log or analyse it on a larger machine",
                byte_size(limit as f64),
                byte_size(available.unwrap_or(0) as f64)
            )
        } else if done >= GZ_RATIO_FROM_BYTES && done > MAX_GZ_RATIO * consumed {
            format!(
                "decompresses to more than {MAX_GZ_RATIO} times its compressed size ({} from {}, where logs compress less than 10 times): not a log; if it is one, decompress it (gunzip) and give the CSV",
                byte_size(done as f64),
                byte_size(consumed as f64)
            )
        } else {
            rows.add(&out, before);
            match (rows.cols, available) {
                (Some(cols), Some(a)) if need_bytes(rows.rows, cols) > a => {
                    too_big(rows.rows, cols, need_bytes(rows.rows, cols), a, " at least")
                }
                _ => continue,
            }
        };
        return Err(LogError::content(source, problem));
    }
}

/// The rows and columns of a text seen so far (lines, and fields of the first line).
#[derive(Default)]
struct Rows {
    rows: u64,
    cols: Option<u64>,
}

impl Rows {
    fn add(&mut self, text: &[u8], from: usize) {
        self.rows += memchr::memchr_iter(b'\n', &text[from..]).count() as u64;
        if self.cols.is_none() {
            if let Some(end) = memchr::memchr(b'\n', text) {
                self.cols = Some(columns_of(&text[..end]));
            }
        }
    }
}

/// Bytes `rows` x `cols` parsed values take to analyse: 8 bytes each and as much again for the
/// analyses' working copies (saturating: a count beyond u64 is refused all the same).
fn need_bytes(rows: u64, cols: u64) -> u64 {
    rows.saturating_mul(cols).saturating_mul(16)
}

fn columns_of(first_line: &[u8]) -> u64 {
    first_line.iter().filter(|&&b| b == b',').count() as u64 + 1
}

/// The message of a log too large to analyse (`at_least` when counted before the end).
fn too_big(rows: u64, cols: u64, need: u64, available: u64, at_least: &str) -> String {
    format!(
        "{rows} rows x {cols} columns need{at_least} about {} to analyse, and {} is available: split the log, or drop columns you do not need",
        byte_size(need as f64),
        byte_size(available as f64)
    )
}

/// Refuse a log whose parsed columns (8 bytes per value, and as much again for the analyses'
/// working copies) would not fit in the memory available: before reading past its first MiB when
/// the rows of that MiB, scaled to the file's size, need more than twice the memory (rows of a
/// log are of nearly one length: the margin covers a first MiB of shorter rows), else while the
/// rows are counted, a MiB at a time, refused as soon as those counted need too much.
pub(crate) fn check_fits(bytes: &[u8], source: &str, available: Option<u64>) -> Result<()> {
    const STEP: usize = 1 << 20;
    let Some(available) = available else {
        return Ok(());
    };
    // Values are at least 2 bytes of text each ("0,"): an upper bound without a scan.
    let upper = bytes.len() as u64 / 2 * 16;
    if upper <= available {
        return Ok(());
    }
    let cols = header_columns(bytes);
    let sample = &bytes[..bytes.len().min(STEP)];
    let sample_rows = memchr::memchr_iter(b'\n', sample).count() as u64;
    if sample.len() < bytes.len() && sample_rows >= 2 {
        let rows = (bytes.len() as f64 * sample_rows as f64 / sample.len() as f64) as u64;
        let need = need_bytes(rows, cols);
        if need / 2 > available {
            let problem = format!(
                "about {rows} rows (estimated from its size, {}, and the rows of its first MiB) x {cols} columns need about {} to analyse, and {} is available: split the log, or drop columns you do not need",
                byte_size(bytes.len() as f64),
                byte_size(need as f64),
                byte_size(available as f64)
            );
            return Err(LogError::content(source, problem));
        }
    }
    let mut rows = 0u64;
    for (k, chunk) in bytes.chunks(STEP).enumerate() {
        rows += memchr::memchr_iter(b'\n', chunk).count() as u64;
        let need = need_bytes(rows, cols);
        if need > available {
            let last = (k + 1) * STEP >= bytes.len();
            let at_least = if last { "" } else { " at least" };
            return Err(LogError::content(
                source,
                too_big(rows, cols, need, available, at_least),
            ));
        }
    }
    Ok(())
}

/// The columns of a log's header: fields of its first line that is not a `#` comment.
fn header_columns(bytes: &[u8]) -> u64 {
    let first = bytes
        .split(|&b| b == b'\n')
        .take(1000)
        .find(|l| !l.starts_with(b"#") && !l.starts_with(b"\xef\xbb\xbf#"))
        .unwrap_or(bytes);
    columns_of(&first[..first.len().min(1 << 20)])
}
