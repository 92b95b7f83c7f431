//! CSV text to columns: the header, the body parsed in parallel chunks (a fast path for plain
//! lines, a general path that names the line and column of anything wrong), the time column's
//! checks and the units mapped to SI.

use crate::columns::{map_header, Quantity};
use crate::error::{At, LogError, Problem, Result};
use crate::file::advise_huge_pages;
use crate::float::{fast_f64, number};
use crate::limits::{
    quote_prefix, valid_rate_hz, valid_value, MAX_ABS_VALUE, MAX_LOG_RATE_HZ, MIN_LOG_RATE_HZ,
};
use crate::log::{Log, ReadOptions};
use noise::ImuChannels;
use rayon::prelude::*;

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
    let pos = if bytes.starts_with(&[0xef, 0xbb, 0xbf]) {
        3
    } else {
        0
    };
    // A binary file (NUL bytes) or one without a line end for megabytes is not a CSV log: say so
    // before reading gigabytes into one "header".
    if bytes[pos..bytes.len().min(pos + 4096)].contains(&0) {
        return Err(LogError::content(source, "contains NUL bytes: not a CSV text file (expected a header such as `t,gx,gy,gz,ax,ay,az`)"));
    }
    let (header, header_line, pos) = find_header(bytes, pos, source)?;
    let names = header_names(&header, header_line, source, opts)?;
    // Which channel and unit each column holds (docs/cli.md, "Log files").
    let (uses, skipped) = map_header(&names, &opts.columns, opts.units)
        .map_err(|p| LogError::new(source, p).at_line(header_line))?;
    // Skipped columns may hold anything (a frame_id, a status word); they are not read.
    let skip: Vec<bool> = uses.iter().map(Option::is_none).collect();
    let columns = parse_body(bytes, pos, header_line, source, &names, &skip)?;
    let n_rows = columns.first().map_or(0, Vec::len);
    if n_rows < 2 {
        return Err(LogError::content(
            source,
            format!("{n_rows} data rows; at least 2 are needed"),
        ));
    }
    let mut channels = ImuChannels::<Option<Vec<f64>>>::default();
    let mut temperature_c = None;
    let mut order = Vec::new();
    let mut t_s = None;
    let mut used = Vec::new();
    for (u, mut data) in uses.into_iter().zip(columns) {
        let Some(u) = u else { continue };
        if u.to_si != 1.0 {
            data.iter_mut().for_each(|v| *v *= u.to_si);
        }
        match u.quantity {
            Quantity::Time => t_s = Some(data),
            Quantity::Imu(c) => channels[c] = Some(data),
            Quantity::Temperature => temperature_c = Some(data),
        }
        if u.quantity != Quantity::Time {
            order.push(u.quantity);
        }
        used.push(u);
    }
    if channels.iter().all(|(_, v)| v.is_none()) {
        let problem = Problem::NoImuColumn { header: names };
        return Err(LogError::new(source, problem).at_line(header_line));
    }
    let locate = |row: usize| At::Line(line_of_row(bytes, pos, header_line, row));
    let rate_hz = rate_of(t_s.as_deref(), opts.rate_hz, source, &locate)?;
    Ok(Log {
        source: source.to_string(),
        rate_hz,
        t_s,
        channels,
        temperature_c,
        order,
        columns: used,
        skipped,
        topic: None,
    })
}

/// The header: the first line from `pos` that is neither blank nor a comment; or, when that line
/// holds only numbers, the comment line before it with as many fields (EuRoC and TUM-VI write their
/// header as `#timestamp [ns],w_RS_S_x [rad s^-1],...`). Returns the header, its line number and
/// where the data start.
fn find_header(bytes: &[u8], mut pos: usize, source: &str) -> Result<(String, usize, usize)> {
    let mut line_no = 0usize;
    let mut last_comment: Option<String> = None;
    let (header, header_line) = loop {
        if pos >= bytes.len() {
            return Err(LogError::content(
                source,
                "no header line (expected a CSV header such as `t,gx,gy,gz,ax,ay,az`)",
            ));
        }
        let end = memchr(b'\n', &bytes[pos..]).map_or(bytes.len(), |i| pos + i);
        line_no += 1;
        if end - pos > MAX_HEADER_BYTES {
            return Err(LogError::content(
                source,
                format!(
                    "a line of more than {} MiB before the header: not a CSV log",
                    MAX_HEADER_BYTES >> 20
                ),
            )
            .at_line(line_no));
        }
        let line = trim_ascii(&bytes[pos..end]);
        let line_start = pos;
        pos = (end + 1).min(bytes.len());
        if line.first() == Some(&b'#') {
            last_comment = std::str::from_utf8(&line[1..])
                .ok()
                .map(|c| c.trim().to_string());
            continue;
        }
        if !line.is_empty() {
            let text = std::str::from_utf8(line).map_err(|e| {
                LogError::content(source, "header is not UTF-8")
                    .at_line(line_no)
                    .caused_by(e)
            })?;
            let fields = text.split(',').count();
            let numeric = text.split(',').all(|f| f.trim().parse::<f64>().is_ok());
            match last_comment {
                Some(c) if numeric && fields > 1 && c.split(',').count() == fields => {
                    pos = line_start;
                    break (c, line_no - 1);
                }
                _ => break (text.to_string(), line_no),
            }
        }
    };
    Ok((header, header_line, pos))
}

/// The column names of the header, checked: none empty, none twice, every mapped column present.
fn header_names(
    header: &str,
    header_line: usize,
    source: &str,
    opts: &ReadOptions,
) -> Result<Vec<String>> {
    let names: Vec<String> = header.split(',').map(|s| s.trim().to_string()).collect();
    for (i, n) in names.iter().enumerate() {
        let problem = if n.is_empty() {
            format!("column {} has an empty name", i + 1)
        } else if names[..i].contains(n) {
            format!("column name {n:?} appears twice")
        } else {
            continue;
        };
        return Err(LogError::content(source, problem).at_line(header_line));
    }
    for (canon, col) in &opts.columns {
        if !names.contains(col) {
            let problem = Problem::MappedColumnMissing {
                channel: canon.clone(),
                column: col.clone(),
                header: names.clone(),
            };
            return Err(LogError::new(source, problem).at_line(header_line));
        }
    }
    Ok(names)
}

/// Longest comment or header line accepted, bytes.
const MAX_HEADER_BYTES: usize = 1 << 20;
/// Relative difference allowed between the rate setting and the rate of the `t` column.
const RATE_TOLERANCE: f64 = 1e-3;
/// Steps of `t` farther than this fraction from the median step are a gap (or a burst):
/// timestamps jitter, but a missing sample doubles the step.
const STEP_TOLERANCE: f64 = 0.5;
/// The log's sample rate from its times `t` (s) and the rate setting, after checking the times
/// increase and are uniform. `locate(row)` names where data row `row` is (a line, a message).
pub(crate) fn rate_of(
    t: Option<&[f64]>,
    rate_hz: Option<f64>,
    source: &str,
    locate: &dyn Fn(usize) -> At,
) -> Result<f64> {
    if let Some(rate_hz) = rate_hz.filter(|&r| !valid_rate_hz(r)) {
        return Err(LogError::new(source, Problem::BadRate { rate_hz }));
    }
    if let Some(t) = t {
        for (k, w) in t.windows(2).enumerate() {
            if w[1] <= w[0] || !w[1].is_finite() {
                let problem = format!(
                    "time t = {} does not increase (previous {}); expected strictly increasing times in s",
                    w[1], w[0]
                );
                return Err(LogError::content(source, problem).at(locate(k + 1)));
            }
        }
    }
    Ok(match (rate_hz, t) {
        (Some(r), Some(t)) => {
            let n = t.len();
            check_uniform(t, source, locate)?;
            let from_t = (n - 1) as f64 / (t[n - 1] - t[0]);
            if ((from_t - r) / r).abs() > RATE_TOLERANCE {
                let problem = Problem::RateDisagrees {
                    rate_hz: r,
                    from_t_hz: from_t,
                };
                return Err(LogError::new(source, problem));
            }
            r
        }
        (Some(r), None) => r,
        (None, Some(t)) => {
            let n = t.len();
            check_uniform(t, source, locate)?;
            (n - 1) as f64 / (t[n - 1] - t[0])
        }
        (None, None) => return Err(LogError::new(source, Problem::NoRate)),
    })
}

/// A uniformly sampled `t`: every step within [`STEP_TOLERANCE`] of the median step, and a rate
/// that is a number. Analyses assume uniform sampling; a gap would silently change the rate.
fn check_uniform(t: &[f64], source: &str, locate: &dyn Fn(usize) -> At) -> Result<()> {
    // The median by selection (linear time; a full sort of millions of steps costs 0.1 s).
    let median = {
        let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        let mid = steps.len() / 2;
        *steps.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    if !(median.is_normal() && 1.0 / median <= MAX_LOG_RATE_HZ) {
        let problem = Problem::TimeStepTooSmall { median_s: median };
        return Err(LogError::new(source, problem));
    }
    if 1.0 / median < MIN_LOG_RATE_HZ {
        let problem = format!(
            "the `t` column's median step is {median:e} s; expected a sample rate of at least {MIN_LOG_RATE_HZ:e} Hz (is `t` in seconds?)"
        );
        return Err(LogError::content(source, problem));
    }
    if let Some(k) = t
        .windows(2)
        .position(|w| ((w[1] - w[0]) - median).abs() > STEP_TOLERANCE * median)
    {
        let problem = format!(
            "t steps from {} to {} s ({:.4} s) where the log's median step is {median:.4} s: a gap or irregular sampling; imudrift analyses uniformly sampled logs: cut the log at the gap, or resample it",
            t[k],
            t[k + 1],
            t[k + 1] - t[k]
        );
        return Err(LogError::content(source, problem).at(locate(k + 1)));
    }
    Ok(())
}

/// Parse the data rows from `start` in parallel chunks; each chunk ends at a newline.
fn parse_body(
    bytes: &[u8],
    start: usize,
    header_line: usize,
    source: &str,
    names: &[String],
    skip: &[bool],
) -> Result<Vec<Vec<f64>>> {
    let n_cols = names.len();
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
        .map(|(w, part)| parse_chunk_into(&body[w[0]..w[1]], part, skip))
        .collect();
    // Errors in file order; then close the gaps left by comment and blank lines.
    let mut line_offset = header_line;
    for (lines, res) in &results {
        if let Err(bad) = res {
            let mut e =
                LogError::content(source, bad.problem.clone()).at_line(line_offset + bad.line);
            if let Some(k) = bad.column {
                e = e.in_column(&names[k]);
            }
            return Err(e);
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

/// Rows parsed in one chunk, or what is wrong where.
type ChunkRows = std::result::Result<usize, BadRow>;

/// A row that cannot be read: its 1-based line within the chunk, the column (index) if the
/// problem is in one, and the problem.
#[derive(Debug)]
struct BadRow {
    line: usize,
    column: Option<usize>,
    problem: String,
}

/// Number of lines of a chunk (a last line without newline counts).
fn lines_in(b: &[u8]) -> usize {
    memchr::memchr_iter(b'\n', b).count() + usize::from(!b.ends_with(b"\n") && !b.is_empty())
}

/// Test helper: parse a chunk into fresh columns.
#[cfg(test)]
pub(crate) fn parse_chunk(
    chunk: &[u8],
    n_cols: usize,
    names: &[String],
) -> (usize, std::result::Result<Vec<Vec<f64>>, String>) {
    let cap = lines_in(chunk);
    let mut cols: Vec<Vec<f64>> = (0..n_cols).map(|_| vec![0.0; cap]).collect();
    let mut out: Vec<&mut [f64]> = cols.iter_mut().map(|c| c.as_mut_slice()).collect();
    let (lines, res) = parse_chunk_into(chunk, &mut out, &vec![false; n_cols]);
    match res {
        Ok(rows) => {
            cols.iter_mut().for_each(|c| c.truncate(rows));
            (lines, Ok(cols))
        }
        Err(bad) => {
            let column = bad
                .column
                .map_or(String::new(), |k| format!("column {:?}: ", names[k]));
            (
                lines,
                Err(format!("line {}: {column}{}", bad.line, bad.problem)),
            )
        }
    }
}

/// Parse one chunk into `out` (one slice per column, at least as long as the chunk has lines):
/// (number of lines, rows written or error), in one scan over the bytes: plain lines by
/// [`fast_line`], anything unusual field by field, through the standard parser if need be.
fn parse_chunk_into(chunk: &[u8], out: &mut [&mut [f64]], skip: &[bool]) -> (usize, ChunkRows) {
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
                    Some(v) if valid_value(v) => out[k][row] = v,
                    _ if skip[k] => out[k][row] = f64::NAN,
                    _ => {
                        let end = chunk[i..]
                            .iter()
                            .position(|&b| b == b',' || b == b'\n')
                            .map_or(n, |p| i + p);
                        let text = String::from_utf8_lossy(&chunk[i..end]);
                        let text = quote_prefix(text.trim());
                        let problem = match value {
                            Some(v) if v.is_finite() => format!("{text} is {}; expected a magnitude below {MAX_ABS_VALUE:e} (squares of larger values overflow)", crate::error::sig(v, 3)),
                            _ => format!("cannot read {text} as a number"),
                        };
                        let bad = BadRow {
                            line: lines,
                            column: Some(k),
                            problem,
                        };
                        return (lines_in(chunk), Err(bad));
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
            let bad = BadRow {
                line: lines,
                column: None,
                problem: format!("{k} fields, expected {n_cols} (as in the header)"),
            };
            return (lines_in(chunk), Err(bad));
        }
        row += 1;
    }
    (lines, Ok(row))
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
        if !valid_value(v) {
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
