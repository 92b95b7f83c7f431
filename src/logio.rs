#![allow(dead_code)] // shared reader: parts are used by diagnose and simulate
//! IMU log reader shared by `allan`, `diagnose` and `simulate`: CSV or gzip-compressed CSV,
//! `#` comment lines, a header row, columns found by name, units mapped to SI.
//!
//! Canonical columns (docs/cli.md): `t` (s), `gx gy gz` (rad/s), `ax ay az` (m/s^2), `temp` (degC).
//! `--col gx=gyro_x_dps` maps a file column to a canonical name; `--gyro-unit deg/s` and
//! `--accel-unit g` convert; `--rate HZ` gives the sample rate when there is no time column.
//! Other numeric columns are kept under their own names, unconverted.
//! Errors name the file, the line and the column, and say what was expected.

use anyhow::{anyhow, bail, Context, Result};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

/// Standard gravity for `g` units (m/s^2), the CGPM 1901 conventional value.
pub const STANDARD_GRAVITY_MPS2: f64 = 9.806_65;

/// Canonical gyro channel names.
pub const GYRO_CHANNELS: [&str; 3] = [
    noise::CHANNEL_NAMES[0],
    noise::CHANNEL_NAMES[1],
    noise::CHANNEL_NAMES[2],
];
/// Canonical accelerometer channel names.
pub const ACCEL_CHANNELS: [&str; 3] = [
    noise::CHANNEL_NAMES[3],
    noise::CHANNEL_NAMES[4],
    noise::CHANNEL_NAMES[5],
];

/// A log in SI units.
#[derive(Clone, Debug)]
pub struct Log {
    /// Where it came from (file name), for messages.
    pub source: String,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Time column, s (if the file had one).
    pub t_s: Option<Vec<f64>>,
    /// Channels by name (canonical where mapped), SI units for gyro and accel channels.
    pub channels: BTreeMap<String, Vec<f64>>,
    /// Channel names in file order (without `t`).
    pub order: Vec<String>,
}

impl Log {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.channels.values().next().map_or(0, Vec::len)
    }

    /// Whether the log has no samples (never true for a log `read_log` returns).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Sample interval, s.
    pub fn dt_s(&self) -> f64 {
        1.0 / self.rate_hz
    }

    /// SI unit of a channel, for tables and plots.
    pub fn unit_of(name: &str) -> &'static str {
        if GYRO_CHANNELS.contains(&name) {
            "rad/s"
        } else if ACCEL_CHANNELS.contains(&name) {
            "m/s^2"
        } else if name == "temp" {
            "degC"
        } else {
            "1"
        }
    }
}

/// Gyro units accepted on the command line.
#[derive(Clone, Copy, Debug, PartialEq, clap::ValueEnum)]
pub enum GyroUnit {
    #[value(name = "rad/s")]
    RadPerS,
    #[value(name = "deg/s")]
    DegPerS,
    #[value(name = "deg/h")]
    DegPerH,
}

impl GyroUnit {
    fn to_si(self) -> f64 {
        match self {
            GyroUnit::RadPerS => 1.0,
            GyroUnit::DegPerS => std::f64::consts::PI / 180.0,
            GyroUnit::DegPerH => std::f64::consts::PI / 180.0 / 3600.0,
        }
    }
}

/// Accelerometer units accepted on the command line.
#[derive(Clone, Copy, Debug, PartialEq, clap::ValueEnum)]
pub enum AccelUnit {
    #[value(name = "m/s^2")]
    MPerS2,
    #[value(name = "g")]
    G,
    #[value(name = "mg")]
    MilliG,
}

impl AccelUnit {
    fn to_si(self) -> f64 {
        match self {
            AccelUnit::MPerS2 => 1.0,
            AccelUnit::G => STANDARD_GRAVITY_MPS2,
            AccelUnit::MilliG => STANDARD_GRAVITY_MPS2 * 1e-3,
        }
    }
}

/// Command-line options of the log reader (flatten into a command's Args).
#[derive(clap::Args, Clone, Debug)]
pub struct LogArgs {
    /// Sample rate in Hz (required when the log has no `t` column; overrides it otherwise)
    #[arg(long, value_name = "HZ")]
    pub rate: Option<f64>,
    /// Unit of the gyro columns
    #[arg(long, value_enum, default_value = "rad/s", value_name = "UNIT")]
    pub gyro_unit: GyroUnit,
    /// Unit of the accelerometer columns
    #[arg(long, value_enum, default_value = "m/s^2", value_name = "UNIT")]
    pub accel_unit: AccelUnit,
    /// Map a file column to a canonical name, e.g. `--col gx=gyro_x_dps` (repeat or comma-separate)
    #[arg(long = "col", value_name = "NAME=COLUMN", value_delimiter = ',')]
    pub columns: Vec<String>,
}

impl LogArgs {
    /// Validated reader options.
    pub fn options(&self) -> Result<ReadOptions> {
        let mut map = Vec::new();
        for c in &self.columns {
            let (name, col) = c
                .split_once('=')
                .ok_or_else(|| anyhow!("--col {c:?}: expected NAME=COLUMN, e.g. gx=gyro_x_dps"))?;
            let name = name.trim();
            if !(name == "t" || name == "temp" || noise::CHANNEL_NAMES.contains(&name)) {
                bail!("--col {c:?}: {name:?} is not one of t, gx, gy, gz, ax, ay, az, temp");
            }
            map.push((name.to_string(), col.trim().to_string()));
        }
        if let Some(r) = self.rate {
            if !(r.is_finite() && r > 0.0 && r <= MAX_LOG_RATE_HZ) {
                bail!(
                    "--rate {}: expected the log's sample rate in Hz, above 0 and at most {MAX_LOG_RATE_HZ:e}",
                    crate::fmt::sig(r, 6)
                );
            }
        }
        Ok(ReadOptions {
            rate_hz: self.rate,
            gyro_unit: self.gyro_unit,
            accel_unit: self.accel_unit,
            columns: map,
        })
    }
}

/// Reader options.
#[derive(Clone, Debug)]
pub struct ReadOptions {
    pub rate_hz: Option<f64>,
    pub gyro_unit: GyroUnit,
    pub accel_unit: AccelUnit,
    /// (canonical name, file column) pairs.
    pub columns: Vec<(String, String)>,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            rate_hz: None,
            gyro_unit: GyroUnit::RadPerS,
            accel_unit: AccelUnit::MPerS2,
            columns: Vec::new(),
        }
    }
}

/// Read a CSV or gzip-compressed CSV log file.
pub fn read_log(path: &Path, opts: &ReadOptions) -> Result<Log> {
    let source = path.display().to_string();
    let raw = FileBytes::open(path).with_context(|| format!("cannot read {source}"))?;
    // What the machine can hold: a log and its parsed columns must fit, or the read is refused
    // before it starts rather than ending in an out-of-memory kill.
    let available = available_memory_bytes();
    if raw.starts_with(&[0x1f, 0x8b]) {
        let limit = available.map_or(u64::MAX, |a| a / 3);
        let mut out = Vec::with_capacity(raw.len().saturating_mul(4).min(limit as usize));
        flate2::read::MultiGzDecoder::new(&raw[..])
            .take(limit)
            .read_to_end(&mut out)
            .with_context(|| format!("{source}: not a valid gzip file"))?;
        if out.len() as u64 == limit {
            bail!(
                "{source}: decompresses to more than {:.1} GiB, a third of the memory available ({:.1} GiB): split the log or analyse it on a larger machine",
                limit as f64 / GIB,
                available.unwrap_or(0) as f64 / GIB
            );
        }
        check_fits(&out, &source, available)?;
        parse_log(&out, &source, opts)
    } else {
        check_fits(&raw, &source, available)?;
        parse_log(&raw, &source, opts)
    }
}

/// A file's bytes: mapped read-only from the page cache on Linux (`memmap2`) (no copy into a fresh buffer:
/// for a 22 MB log that copy and the zeroing of its pages cost more than parsing half of it;
/// pages are faulted in by the parsing threads, in parallel),
/// else read into memory.
enum FileBytes {
    Mapped(memmap2::Mmap),
    Read(Vec<u8>),
}

impl FileBytes {
    fn open(path: &Path) -> std::io::Result<FileBytes> {
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
fn advise_huge_pages<T>(buf: &[T]) {
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

/// Parse log text (already decompressed).
pub fn parse_log(bytes: &[u8], source: &str, opts: &ReadOptions) -> Result<Log> {
    // Old Mac line endings (CR only) would make the whole file one line: read them as newlines.
    if !bytes.contains(&b'\n') && bytes.contains(&b'\r') {
        let unix: Vec<u8> = bytes
            .iter()
            .map(|&b| if b == b'\r' { b'\n' } else { b })
            .collect();
        return parse_log(&unix, source, opts);
    }
    // A UTF-8 byte-order mark (spreadsheet exports) is not part of the first column's name.
    let mut pos = if bytes.starts_with(&[0xef, 0xbb, 0xbf]) {
        3
    } else {
        0
    };
    // A binary file (NUL bytes) or one without a line end for megabytes is not a CSV log: say so
    // before reading gigabytes into one "header".
    if bytes[pos..bytes.len().min(pos + 4096)].contains(&0) {
        bail!("{source}: contains NUL bytes: not a CSV text file (expected a header such as `t,gx,gy,gz,ax,ay,az`)");
    }
    // Header: the first line that is neither blank nor a comment.
    let mut line_no = 0usize;
    let header = loop {
        if pos >= bytes.len() {
            bail!("{source}: no header line (expected a CSV header such as `t,gx,gy,gz,ax,ay,az`)");
        }
        let end = memchr(b'\n', &bytes[pos..]).map_or(bytes.len(), |i| pos + i);
        line_no += 1;
        if end - pos > MAX_HEADER_BYTES {
            bail!(
                "{source}:{line_no}: a line of more than {} MiB before the header: not a CSV log",
                MAX_HEADER_BYTES >> 20
            );
        }
        let line = trim_ascii(&bytes[pos..end]);
        pos = (end + 1).min(bytes.len());
        if !line.is_empty() && line[0] != b'#' {
            break std::str::from_utf8(line)
                .with_context(|| format!("{source}:{line_no}: header is not UTF-8"))?;
        }
    };
    let header_line = line_no;
    let names: Vec<String> = header.split(',').map(|s| s.trim().to_string()).collect();
    // Map file column names to channel names.
    let mut channel_names = names.clone();
    for (canon, col) in &opts.columns {
        let idx = names.iter().position(|n| n == col).ok_or_else(|| {
            anyhow!("{source}:{header_line}: --col {canon}={col}: no column {col:?} in the header (columns: {})", names.join(", "))
        })?;
        channel_names[idx] = canon.clone();
    }
    for (i, n) in channel_names.iter().enumerate() {
        if n.is_empty() {
            bail!("{source}:{header_line}: column {} has an empty name", i + 1);
        }
        if channel_names[..i].contains(n) {
            bail!("{source}:{header_line}: column name {n:?} appears twice");
        }
    }
    let columns = parse_body(bytes, pos, header_line, names.len(), source, &names)?;
    let n_rows = columns.first().map_or(0, Vec::len);
    if n_rows < 2 {
        bail!("{source}: {n_rows} data rows; at least 2 are needed");
    }
    let mut channels = BTreeMap::new();
    let mut order = Vec::new();
    let mut t_s = None;
    for (name, mut data) in channel_names.into_iter().zip(columns) {
        if name == "t" {
            t_s = Some(data);
            continue;
        }
        let scale = if GYRO_CHANNELS.contains(&name.as_str()) {
            opts.gyro_unit.to_si()
        } else if ACCEL_CHANNELS.contains(&name.as_str()) {
            opts.accel_unit.to_si()
        } else {
            1.0
        };
        if scale != 1.0 {
            data.iter_mut().for_each(|v| *v *= scale);
        }
        order.push(name.clone());
        channels.insert(name, data);
    }
    if channels.is_empty() {
        bail!("{source}:{header_line}: no data columns besides `t`");
    }
    if let Some(t) = &t_s {
        for (k, w) in t.windows(2).enumerate() {
            if w[1] <= w[0] || !w[1].is_finite() {
                let line = line_of_row(bytes, pos, header_line, k + 1);
                bail!(
                    "{source}:{line}: time t = {} does not increase (previous {}); expected strictly increasing times in s",
                    w[1], w[0]
                );
            }
        }
    }
    let rate_hz = match (opts.rate_hz, &t_s) {
        (Some(r), Some(t)) => {
            check_uniform(t, bytes, pos, header_line, source)?;
            let from_t = (n_rows - 1) as f64 / (t[n_rows - 1] - t[0]);
            if ((from_t - r) / r).abs() > RATE_TOLERANCE {
                bail!(
                    "{source}: --rate {} Hz disagrees with the `t` column ({} Hz); give the rate the log was sampled at, or leave --rate out to use `t`",
                    crate::fmt::sig(r, 6),
                    crate::fmt::sig(from_t, 6)
                );
            }
            r
        }
        (Some(r), None) => r,
        (None, Some(t)) => {
            check_uniform(t, bytes, pos, header_line, source)?;
            (n_rows - 1) as f64 / (t[n_rows - 1] - t[0])
        }
        (None, None) => bail!(
            "{source}: no `t` column: give the sample rate with --rate HZ (or map a time column with --col t=NAME)"
        ),
    };
    Ok(Log {
        source: source.to_string(),
        rate_hz,
        t_s,
        channels,
        order,
    })
}

const GIB: f64 = (1u64 << 30) as f64;

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
fn check_fits(bytes: &[u8], source: &str, available: Option<u64>) -> Result<()> {
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
        bail!(
            "{source}: {rows} rows x {cols} columns need about {:.1} GiB to analyse, and {:.1} GiB is available: split the log, or drop columns you do not need",
            need as f64 / GIB,
            available as f64 / GIB
        );
    }
    Ok(())
}

/// Longest comment or header line accepted, bytes.
const MAX_HEADER_BYTES: usize = 1 << 20;
/// Relative difference allowed between `--rate` and the rate of the `t` column.
const RATE_TOLERANCE: f64 = 1e-3;
/// Steps of `t` farther than this fraction from the median step are a gap (or a burst):
/// timestamps jitter, but a missing sample doubles the step.
const STEP_TOLERANCE: f64 = 0.5;
/// Highest sample rate a log may have, Hz.
const MAX_LOG_RATE_HZ: f64 = 1e9;

/// A uniformly sampled `t`: every step within [`STEP_TOLERANCE`] of the median step, and a rate
/// that is a number. Analyses assume uniform sampling; a gap would silently change the rate.
fn check_uniform(
    t: &[f64],
    bytes: &[u8],
    pos: usize,
    header_line: usize,
    source: &str,
) -> Result<()> {
    // The median by selection (linear time; a full sort of millions of steps costs 0.1 s).
    let median = {
        let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        let mid = steps.len() / 2;
        *steps.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    if !(median.is_normal() && 1.0 / median <= MAX_LOG_RATE_HZ) {
        bail!(
            "{source}: the `t` column's median step is {median:e} s; expected a sample rate of at most {MAX_LOG_RATE_HZ:e} Hz (is `t` in seconds?)"
        );
    }
    if let Some(k) = t
        .windows(2)
        .position(|w| ((w[1] - w[0]) - median).abs() > STEP_TOLERANCE * median)
    {
        let line = line_of_row(bytes, pos, header_line, k + 1);
        bail!(
            "{source}:{line}: t steps from {} to {} s ({:.4} s) where the log's median step is {median:.4} s: a gap or irregular sampling; imudrift analyses uniformly sampled logs: cut the log at the gap, or resample it",
            t[k],
            t[k + 1],
            t[k + 1] - t[k]
        );
    }
    Ok(())
}

/// Parse the data rows from `start` in parallel chunks; each chunk ends at a newline.
fn parse_body(
    bytes: &[u8],
    start: usize,
    header_line: usize,
    n_cols: usize,
    source: &str,
    names: &[String],
) -> Result<Vec<Vec<f64>>> {
    let body = &bytes[start.min(bytes.len())..];
    let n_chunks = (rayon::current_num_threads() * 4).clamp(1, 64);
    let target = body.len() / n_chunks + 1;
    let mut bounds = vec![0usize];
    while *bounds.last().unwrap() < body.len() {
        let s = *bounds.last().unwrap();
        let e = (s + target).min(body.len());
        let e = if e == body.len() {
            e
        } else {
            memchr(b'\n', &body[e..]).map_or(body.len(), |i| e + i + 1)
        };
        bounds.push(e);
    }
    // Lines per chunk (an upper bound on its rows): the columns are allocated once and every
    // chunk parses straight into its own disjoint part of them, in parallel.
    let line_counts: Vec<usize> = bounds
        .par_windows(2)
        .map(|w| lines_in(&body[w[0]..w[1]]))
        .collect();
    let total: usize = line_counts.iter().sum();
    // One spare element: the allan command turns a column into its phase (one value longer)
    // in place.
    let mut columns: Vec<Vec<f64>> = (0..n_cols)
        .map(|_| {
            let mut c = vec![0.0f64; total + 1];
            advise_huge_pages(&c);
            c.truncate(total);
            c
        })
        .collect();
    let mut parts: Vec<Vec<&mut [f64]>> = (0..line_counts.len()).map(|_| Vec::new()).collect();
    for col in columns.iter_mut() {
        let mut rest: &mut [f64] = col;
        for (part, &cnt) in parts.iter_mut().zip(&line_counts) {
            let (head, tail) = rest.split_at_mut(cnt);
            part.push(head);
            rest = tail;
        }
    }
    let results: Vec<(usize, ChunkRows)> = bounds
        .par_windows(2)
        .zip(parts.par_iter_mut())
        .map(|(w, part)| parse_chunk_into(&body[w[0]..w[1]], part, names))
        .collect();
    // Errors in file order; then close the gaps left by comment and blank lines.
    let mut line_offset = header_line;
    for (lines, res) in &results {
        if let Err((local, msg)) = res {
            bail!("{source}:{}: {msg}", line_offset + local);
        }
        line_offset += lines;
    }
    for col in columns.iter_mut() {
        let (mut src, mut dst) = (0usize, 0usize);
        for ((_, res), &cnt) in results.iter().zip(&line_counts) {
            let rows = *res.as_ref().unwrap_or(&0);
            if src != dst {
                col.copy_within(src..src + rows, dst);
            }
            src += cnt;
            dst += rows;
        }
        col.truncate(dst);
    }
    Ok(columns)
}

/// Rows parsed in one chunk, or (1-based line within the chunk, message).
type ChunkRows = std::result::Result<usize, (usize, String)>;

/// Number of lines of a chunk (a last line without newline counts).
fn lines_in(b: &[u8]) -> usize {
    memchr::memchr_iter(b'\n', b).count() + usize::from(!b.ends_with(b"\n") && !b.is_empty())
}

/// Test helper: parse a chunk into fresh columns.
#[cfg(test)]
fn parse_chunk(chunk: &[u8], n_cols: usize, names: &[String]) -> (usize, Result<Vec<Vec<f64>>>) {
    let cap = lines_in(chunk);
    let mut cols: Vec<Vec<f64>> = (0..n_cols).map(|_| vec![0.0; cap]).collect();
    let mut out: Vec<&mut [f64]> = cols.iter_mut().map(|c| c.as_mut_slice()).collect();
    let (lines, res) = parse_chunk_into(chunk, &mut out, names);
    match res {
        Ok(rows) => {
            cols.iter_mut().for_each(|c| c.truncate(rows));
            (lines, Ok(cols))
        }
        Err((l, m)) => (lines, Err(anyhow!("line {l}: {m}"))),
    }
}

/// Parse one chunk into `out` (one slice per column, at least as long as the chunk has lines):
/// (number of lines, rows written or error), in one scan over the bytes: plain lines by
/// [`fast_line`], anything unusual field by field, through the standard parser if need be.
fn parse_chunk_into(chunk: &[u8], out: &mut [&mut [f64]], names: &[String]) -> (usize, ChunkRows) {
    let n_cols = out.len();
    let mut row = 0usize;
    let n = chunk.len();
    let mut i = 0usize;
    let mut lines = 0usize;
    let is_blank = |b: u8| b == b' ' || b == b'\t' || b == b'\r';
    while i < n {
        lines += 1;
        if let Some(next) = fast_line(chunk, i, out, row) {
            i = next;
            row += 1;
            continue;
        }
        // Leading blanks; comment or empty line.
        while i < n && is_blank(chunk[i]) {
            i += 1;
        }
        if i >= n {
            break;
        }
        if chunk[i] == b'\n' {
            i += 1;
            continue;
        }
        if chunk[i] == b'#' {
            i = memchr::memchr(b'\n', &chunk[i..]).map_or(n, |p| i + p + 1);
            continue;
        }
        let mut k = 0usize;
        loop {
            // One field starting at i (leading blanks skipped).
            while i < n && is_blank(chunk[i]) {
                i += 1;
            }
            let (value, after) = match fast_f64(&chunk[i..]) {
                Some((v, used)) => (Some(v), i + used),
                None => (None, i),
            };
            // The field must end here (blanks, then ',' or end of line).
            let mut j = after;
            while j < n && is_blank(chunk[j]) {
                j += 1;
            }
            let ends_field = j >= n || chunk[j] == b',' || chunk[j] == b'\n';
            let (value, field_end) = if value.is_some() && ends_field {
                (value, j)
            } else {
                // Slow path: the whole field, standard parser.
                let end = chunk[i..]
                    .iter()
                    .position(|&b| b == b',' || b == b'\n')
                    .map_or(n, |p| i + p);
                let text = std::str::from_utf8(&chunk[i..end])
                    .unwrap_or("\u{fffd}")
                    .trim();
                (text.parse::<f64>().ok(), end)
            };
            if k < n_cols {
                match value {
                    Some(v) if v.is_finite() => out[k][row] = v,
                    _ => {
                        let end = chunk[i..]
                            .iter()
                            .position(|&b| b == b',' || b == b'\n')
                            .map_or(n, |p| i + p);
                        let text = String::from_utf8_lossy(&chunk[i..end]).trim().to_string();
                        let msg =
                            format!("column {:?}: cannot read {text:?} as a number", names[k]);
                        return (lines_in(chunk), Err((lines, msg)));
                    }
                }
            }
            k += 1;
            i = field_end;
            if i < n && chunk[i] == b',' {
                i += 1;
                continue;
            }
            // end of line
            if i < n {
                i += 1;
            }
            break;
        }
        if k != n_cols {
            let msg = format!("{k} fields, expected {n_cols} (as in the header)");
            return (lines_in(chunk), Err((lines, msg)));
        }
        row += 1;
    }
    (lines, Ok(row))
}

/// Powers of ten exactly representable in f64 (10^0 .. 10^22).
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Decimal numbers `[+-]digits[.digits][(e|E)[+-]digits]` in one scan. With at most 19 digits
/// in all (leading zeros included, so the integer significand w cannot overflow), w below 2^53
/// and a net power of ten within +-22, the value is w * 10^e or w / 10^-e with both operands
/// exact, so the one IEEE operation rounds it correctly (Clinger 1990, the fast path of every
/// correct parser); otherwise the scanned text goes straight to the standard parser (e.g. the
/// 17 significant digits of a double printed exactly). Returns (value, bytes used), or `None`
/// when there is no number (no digits): same values as the standard parser.
#[inline(always)]
fn fast_f64(s: &[u8]) -> Option<(f64, usize)> {
    let mut i = 0;
    let first = *s.first()?;
    let neg = first == b'-';
    if neg || first == b'+' {
        i = 1;
    }
    // The digits from s[i..] appended to w: (index after them, w).
    let scan = |mut i: usize, mut w: u64| {
        while let Some(&c) = s.get(i) {
            let d = c.wrapping_sub(b'0');
            if d > 9 {
                break;
            }
            w = w.wrapping_mul(10).wrapping_add(u64::from(d));
            i += 1;
        }
        (i, w)
    };
    let int_start = i;
    let (after, mut w) = scan(i, 0);
    i = after;
    let mut digits = i - int_start;
    let mut exp10: i32 = 0;
    if s.get(i) == Some(&b'.') {
        let frac_start = i + 1;
        (i, w) = scan(frac_start, w);
        digits += i - frac_start;
        exp10 = -((i - frac_start) as i32);
    }
    if digits == 0 {
        return None;
    }
    if let Some(b'e' | b'E') = s.get(i) {
        i += 1;
        let eneg = match s.get(i) {
            Some(b'-') => {
                i += 1;
                true
            }
            Some(b'+') => {
                i += 1;
                false
            }
            _ => false,
        };
        let mut e: i32 = 0;
        let e_start = i;
        while let Some(&c) = s.get(i) {
            let d = c.wrapping_sub(b'0');
            if d > 9 {
                break;
            }
            e = e.saturating_mul(10).saturating_add(i32::from(d));
            i += 1;
        }
        if i == e_start {
            return None;
        }
        exp10 = exp10.saturating_add(if eneg { -e } else { e });
    }
    // Longer significands (more than 19 digits: w may have wrapped) or larger exponents: the
    // standard parser (Eisel-Lemire) on the text just scanned, which is a valid decimal.
    if digits > 19 || !(-22..=22).contains(&exp10) || w >= 1u64 << 53 {
        // SAFETY: s[..i] was scanned above: ASCII digits, sign, point and exponent letter only,
        // hence valid UTF-8 (this check cost 12 % of a 17-digit CSV's whole run).
        let text = unsafe { std::str::from_utf8_unchecked(&s[..i]) };
        return Some((text.parse().ok()?, i));
    }
    // Clinger: both operands exact, one correctly rounded operation.
    let v = w as f64;
    let v = if exp10 >= 0 {
        v * POW10[exp10 as usize]
    } else {
        v / POW10[(-exp10) as usize]
    };
    Some((if neg { -v } else { v }, i))
}

/// Branch-light parse of the short numbers IMU logs are made of: `[-]digits[.digits]` with at
/// most 7 digits in all, the field ending within the 8 bytes after the sign (at `,`, `\n` or
/// `\r`). The digits are gathered into one 64-bit word and converted with three multiplies
/// (the SWAR "eight digits" step of simdjson and fast_float, Lemire 2021, "Number parsing at a
/// gigabyte per second", Software: Practice and Experience 51(8)); the value is then
/// w / 10^f with w < 10^7 and f <= 6, both exact, so the one division rounds correctly
/// (Clinger 1990), the same value as the standard parser. `None` sends the field to
/// [`fast_f64`]. The sign, the length and the position of the point are selected without
/// branches: random signs and lengths would otherwise cost a mispredicted branch each.
#[inline(always)]
fn swar_f64(s: &[u8]) -> Option<(f64, usize)> {
    let neg = *s.first()? == b'-';
    let start = usize::from(neg);
    let bytes: [u8; 8] = s.get(start..start + 8)?.try_into().ok()?;
    // Digit values in the bytes ('0'..'9' -> 0..9); a byte is not a digit when its value
    // (with the high bit cleared, so the add cannot carry into the next byte) is >= 10.
    let v = u64::from_le_bytes(bytes) ^ 0x3030_3030_3030_3030;
    let high = 0x8080_8080_8080_8080u64;
    let nondigit = (((v & 0x7f7f_7f7f_7f7f_7f7f) + 0x7676_7676_7676_7676) | v) & high;
    let p1 = (nondigit.trailing_zeros() / 8) as usize; // integer digits (8: none found)
    let rest = nondigit & nondigit.wrapping_sub(1); // the non-digits after the first
    let p2 = (rest.trailing_zeros() / 8) as usize;
    let dot = p1 < 8 && bytes[p1] == b'.';
    let end = if dot { p2 } else { p1 }; // the terminator's position
    if end >= 8 || !matches!(bytes[end], b',' | b'\n' | b'\r') {
        return None;
    }
    let frac = end - p1 - usize::from(dot);
    let digits = p1 + frac;
    if digits == 0 {
        return None;
    }
    // Integer digits, then the fraction digits after the point, right-aligned in 8 bytes
    // (leading zero digits), most significant digit first (lowest address).
    let int = v & ((1u64 << (8 * p1)) - 1);
    let frac_digits = (v >> (8 * (p1 + usize::from(dot)))) & ((1u64 << (8 * frac)) - 1);
    let mut w = (int | (frac_digits << (8 * p1))) << (8 * (8 - digits));
    w = w.wrapping_mul(10).wrapping_add(w >> 8);
    let mask = 0x0000_00ff_0000_00ffu64;
    let mul1 = 100 + (1_000_000u64 << 32);
    let mul2 = 1 + (10_000u64 << 32);
    let w = ((w & mask)
        .wrapping_mul(mul1)
        .wrapping_add(((w >> 16) & mask).wrapping_mul(mul2))
        >> 32) as u32;
    let value = f64::from(w) / POW10[frac];
    let value = f64::from_bits(value.to_bits() | (u64::from(neg) << 63));
    Some((value, start + end))
}

/// A number in the common formats, exactly as the standard parser reads it: [`swar_f64`], else
/// [`fast_f64`]; `None` for the standard parser.
#[inline(always)]
fn number(s: &[u8]) -> Option<(f64, usize)> {
    swar_f64(s).or_else(|| fast_f64(s))
}

/// The common line: exactly `out.len()` plain numbers separated by single commas, ending at
/// `\n`, `\r\n` or the end of the chunk. Writes row `row` and returns the index after the
/// line, or `None` (the caller then reads the line with the general path, which rewrites the
/// row or reports the error).
#[inline(always)]
fn fast_line(chunk: &[u8], mut i: usize, out: &mut [&mut [f64]], row: usize) -> Option<usize> {
    let n_cols = out.len();
    if n_cols == 0 {
        return None;
    }
    for (k, col) in out.iter_mut().enumerate() {
        let (v, used) = number(chunk.get(i..)?)?;
        if !v.is_finite() {
            return None; // the general path reports it
        }
        i += used;
        match chunk.get(i) {
            Some(b',') if k + 1 < n_cols => i += 1,
            Some(b'\n') if k + 1 == n_cols => i += 1,
            Some(b'\r') if k + 1 == n_cols && chunk.get(i + 1) == Some(&b'\n') => i += 2,
            None if k + 1 == n_cols => {}
            _ => return None,
        }
        col[row] = v;
    }
    Some(i)
}

/// The 1-based file line of data row `row` (0-based), for error messages (slow path).
fn line_of_row(bytes: &[u8], start: usize, header_line: usize, row: usize) -> usize {
    let mut seen = 0usize;
    for (i, raw) in bytes[start..].split(|&b| b == b'\n').enumerate() {
        let line = trim_ascii(raw);
        if line.is_empty() || line[0] == b'#' {
            continue;
        }
        if seen == row {
            return header_line + i + 1;
        }
        seen += 1;
    }
    header_line
}

fn trim_ascii(s: &[u8]) -> &[u8] {
    s.trim_ascii()
}

fn memchr(needle: u8, hay: &[u8]) -> Option<usize> {
    memchr::memchr(needle, hay)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts() -> ReadOptions {
        ReadOptions::default()
    }

    #[test]
    fn reads_comments_units_and_mapping() {
        let text = b"# a comment\n# another\ngyro_x_dps,acc_z_g,other\n1.0,-1.0,5\n# mid comment\n2.0,-0.5,6\n\n3.0,0,7\n";
        let o = ReadOptions {
            rate_hz: Some(100.0),
            gyro_unit: GyroUnit::DegPerS,
            accel_unit: AccelUnit::G,
            columns: vec![
                ("gx".into(), "gyro_x_dps".into()),
                ("az".into(), "acc_z_g".into()),
            ],
        };
        let log = parse_log(text, "x.csv", &o).unwrap();
        assert_eq!(log.len(), 3);
        assert_eq!(log.order, vec!["gx", "az", "other"]);
        assert!((log.channels["gx"][1] - 2.0f64.to_radians()).abs() < 1e-15);
        assert!((log.channels["az"][0] + STANDARD_GRAVITY_MPS2).abs() < 1e-12);
        assert_eq!(log.channels["other"], vec![5.0, 6.0, 7.0]);
        assert_eq!(log.rate_hz, 100.0);
    }

    #[test]
    fn rate_from_time_column() {
        let log = parse_log(b"t,gx\n0.0,1\n0.01,2\n0.02,3\n", "x", &opts()).unwrap();
        assert!((log.rate_hz - 100.0).abs() < 1e-9);
    }

    #[test]
    fn errors_name_file_line_and_column() {
        let e = parse_log(b"# c\nt,gx\n0,1\n0.01,abc\n", "f.csv", &opts()).unwrap_err();
        let msg = format!("{e:#}");
        assert!(
            msg.contains("f.csv:4") && msg.contains("\"gx\"") && msg.contains("abc"),
            "{msg}"
        );
        let e = parse_log(b"t,gx\n0,1\n0.01\n", "f.csv", &opts()).unwrap_err();
        assert!(
            format!("{e:#}").contains("f.csv:3: 1 fields, expected 2"),
            "{e:#}"
        );
        let e = parse_log(b"t,gx\n0,1\n0,2\n", "f.csv", &opts()).unwrap_err();
        assert!(format!("{e:#}").contains("f.csv:3: time"), "{e:#}");
        let e = parse_log(b"gx\n1\n2\n", "f.csv", &opts()).unwrap_err();
        assert!(format!("{e:#}").contains("--rate"), "{e:#}");
    }

    #[test]
    fn fast_path_agrees_with_std_parser_bit_for_bit() {
        // Random doubles printed in the formats logs use, plus hand-picked edge cases.
        let mut st = 0x1234_5678_9abc_def0u64;
        let mut next = || {
            st ^= st << 13;
            st ^= st >> 7;
            st ^= st << 17;
            st
        };
        let mut texts: Vec<String> = [
            "0",
            "-0",
            "0.0",
            "1",
            "-1.5",
            "0.05",
            "-.5",
            ".",
            "-",
            "-.",
            "1234567",
            "12345678",
            "-9999999",
            "999999.9",
            ".0000001",
            "0.000001",
            "-1.",
            "12.5e1",
            "1-2",
            "1.2.3",
            "-0.35",
            "1e3",
            "1.5E-3",
            "-2.5e+10",
            "9007199254740991",
            "9007199254740993",
            "123456789012345678901",
            "1e22",
            "1e23",
            "1e-22",
            "1e-23",
            ".5",
            "5.",
            "0.1",
            "3.14159265358979",
            "00012.5000",
            "1e400",
            "4.9e-324",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        for _ in 0..20_000 {
            let v = f64::from_bits(next() >> 2) * if next() % 2 == 0 { 1.0 } else { -1.0 };
            let small = (next() % 2_000_001) as f64 / 1000.0 - 1000.0;
            texts.push(format!("{v:e}"));
            texts.push(format!("{small}"));
            texts.push(format!("{:.2}", small / 10.0));
            texts.push(format!("{}", (next() % 4001) as f64 * 0.05 - 100.0));
            texts.push(format!("{:.6}", small / 7.0));
            texts.push(format!("{:.17e}", small / 3.0));
        }
        let mut swar_read = 0usize;
        for t in &texts {
            let want: Option<f64> = t.parse().ok();
            // A fast path reads a valid number whole and exactly, or declines, or reads a
            // prefix of an invalid field (the caller then finds no terminator).
            let check = |got: Option<(f64, usize)>| {
                if let Some((got, used)) = got {
                    if used == t.len() {
                        assert_eq!(Some(got.to_bits()), want.map(f64::to_bits), "{t}");
                    } else {
                        assert!(want.is_none(), "{t}: read {used} bytes");
                    }
                }
            };
            check(fast_f64(t.as_bytes()));
            // the word-at-a-time path needs a terminator and 8 bytes after the sign
            for end in [",", "\n", "\r\n"] {
                check(number(format!("{t}{end}xxxxxxxx").as_bytes()));
                let got = swar_f64(format!("{t}{end}xxxxxxxx").as_bytes());
                swar_read += usize::from(got.is_some());
                check(got);
            }
        }
        // the short formats (most of the "{small}" and "{:.2}" texts) went the SWAR way
        assert!(swar_read > 3 * 20_000, "{swar_read}");
        // and through the chunk parser (fast or slow path per field)
        let body: String = texts
            .iter()
            .filter(|t| t.parse::<f64>().is_ok_and(f64::is_finite))
            .map(|t| format!("{t}\n"))
            .collect();
        let names = vec!["x".to_string()];
        let (_, cols) = parse_chunk(body.as_bytes(), 1, &names);
        let cols = cols.unwrap();
        for (v, t) in cols[0].iter().zip(body.lines()) {
            assert_eq!(v.to_bits(), t.parse::<f64>().unwrap().to_bits(), "{t}");
        }
    }

    #[test]
    fn error_line_numbers_across_parallel_chunks() {
        // Many rows so the body is split into several chunks; the bad row is near the end.
        let mut s = String::from("# header comment\ngx\n");
        for i in 0..50_000 {
            if i == 43_210 {
                s.push_str("oops\n");
            } else {
                s.push_str(&format!("{}\n", i as f64 * 0.5));
            }
        }
        let o = ReadOptions {
            rate_hz: Some(1.0),
            ..opts()
        };
        let e = parse_log(s.as_bytes(), "big.csv", &o).unwrap_err();
        // line 1 comment, line 2 header, row i on line i + 3
        assert!(
            format!("{e:#}").contains(&format!("big.csv:{}:", 43_210 + 3)),
            "{e:#}"
        );
        let good = s.replace("oops", "1.0");
        let log = parse_log(good.as_bytes(), "big.csv", &o).unwrap();
        assert_eq!(log.len(), 50_000);
        assert_eq!(log.channels["gx"][49_999], 49_999.0 * 0.5);
    }

    #[test]
    fn large_file_is_mapped_and_reads_as_parsed() {
        // Over 1 MiB: read_log maps the file instead of reading it; same log either way.
        let mut s = String::from("t,gx\n");
        for i in 0..120_000 {
            s.push_str(&format!(
                "{},{}\n",
                i as f64 * 0.01,
                (i % 97) as f64 * -0.05
            ));
        }
        assert!(s.len() > 1 << 20);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("big.csv");
        std::fs::write(&path, &s).unwrap();
        let read = read_log(&path, &opts()).unwrap();
        let parsed = parse_log(s.as_bytes(), "big.csv", &opts()).unwrap();
        assert_eq!(read.len(), 120_000);
        assert_eq!(read.channels, parsed.channels);
        assert_eq!(read.t_s, parsed.t_s);
        assert_eq!(read.channels["gx"][96], 96.0 * -0.05);
    }

    #[test]
    fn comments_and_blank_lines_inside_large_chunks() {
        // Every parallel chunk holds comment, blank and irregular lines: rows stay in file
        // order with no gaps; an error deep in the file names its line.
        let mut s = String::from("t,gx\n");
        let mut want = Vec::new();
        for i in 0..60_000 {
            match i % 997 {
                5 => s.push_str("# note\n"),
                9 => s.push('\n'),
                _ => {}
            }
            let v = (i % 41) as f64 * 0.25 - 3.0;
            if i % 1013 == 7 {
                s.push_str(&format!(" {} , {v:e}\r\n", i as f64 * 0.01));
            } else {
                s.push_str(&format!("{},{v}\n", i as f64 * 0.01));
            }
            want.push(v);
        }
        let log = parse_log(s.as_bytes(), "c.csv", &opts()).unwrap();
        assert_eq!(log.channels["gx"], want);
        let lines: Vec<&str> = s.lines().collect();
        let bad = lines.len() - 1234;
        let broken: String = lines
            .iter()
            .enumerate()
            .map(|(k, l)| {
                if k == bad {
                    "1,zz\n".to_string()
                } else {
                    format!("{l}\n")
                }
            })
            .collect();
        let e = parse_log(broken.as_bytes(), "c.csv", &opts()).unwrap_err();
        assert!(
            format!("{e:#}").contains(&format!("c.csv:{}:", bad + 1)),
            "{e:#}"
        );
    }
}
