//! Progress on long work, on stderr only: a bar when stderr is a terminal, and otherwise (a
//! batch log, a pipe) a plain line every few seconds, so a Slurm log shows where a job is.

use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Longest progress interval `IMUDRIFT_PROGRESS_INTERVAL_S` may set (a day), s.
pub const MAX_INTERVAL_S: f64 = 86_400.0;

/// Seconds between plain progress lines when stderr is not a terminal (environment variable
/// `IMUDRIFT_PROGRESS_INTERVAL_S` overrides it; 0 prints at every update).
const DEFAULT_INTERVAL_S: f64 = 10.0;

/// Progress of one job of `total` units (runs, samples).
pub struct Progress {
    label: String,
    unit: &'static str,
    total: u64,
    started: Instant,
    bar: Option<indicatif::ProgressBar>,
    /// When stderr is not a terminal: the interval and the time of the last line.
    lines: Option<(Duration, Mutex<Instant>)>,
}

impl Progress {
    pub fn new(label: &str, unit: &'static str, total: u64) -> Progress {
        let started = Instant::now();
        if std::io::stderr().is_terminal() {
            let b = indicatif::ProgressBar::new(total);
            b.set_style(
                indicatif::ProgressStyle::with_template(&format!(
                    "{{msg}} [{{bar:40}}] {{pos}}/{{len}} {unit}, {{eta}} left"
                ))
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            b.set_message(label.to_string());
            return Progress {
                label: label.into(),
                unit,
                total,
                started,
                bar: Some(b),
                lines: None,
            };
        }
        let interval_s = std::env::var("IMUDRIFT_PROGRESS_INTERVAL_S")
            .ok()
            .and_then(|v| v.parse::<f64>().ok())
            .filter(|v| (0.0..=MAX_INTERVAL_S).contains(v))
            .unwrap_or(DEFAULT_INTERVAL_S);
        Progress {
            label: label.into(),
            unit,
            total,
            started,
            bar: None,
            lines: Some((Duration::from_secs_f64(interval_s), Mutex::new(started))),
        }
    }

    /// `done` units are finished (callable from any thread).
    pub fn set(&self, done: u64) {
        if let Some(b) = &self.bar {
            b.set_position(done);
            return;
        }
        if done >= self.total {
            return;
        }
        let Some(elapsed) = self.line_due() else {
            return;
        };
        let left = if done > 0 {
            elapsed * (self.total - done) as f64 / done as f64
        } else {
            f64::NAN
        };
        tell!(
            "{}: {done}/{} {} ({:.0} %), {elapsed:.0} s elapsed, ~{left:.0} s left",
            self.label,
            self.total,
            self.unit,
            100.0 * done as f64 / self.total.max(1) as f64,
        );
    }

    /// A job without a count (diagnose): a spinner with the current stage on a terminal,
    /// otherwise the stage as a plain line at most every interval.
    pub fn stages(label: &str) -> Progress {
        let mut p = Progress::new(label, "", 0);
        if let Some(b) = p.bar.take() {
            let spinner = indicatif::ProgressBar::new_spinner();
            spinner.enable_steady_tick(Duration::from_millis(200));
            drop(b);
            p.bar = Some(spinner);
        }
        p
    }

    /// The stage now running (for [`Progress::stages`]).
    pub fn stage(&self, what: &str) {
        if let Some(b) = &self.bar {
            b.set_message(what.to_string());
            return;
        }
        if let Some(elapsed) = self.line_due() {
            tell!("{}: {what} ({elapsed:.0} s elapsed)", self.label);
        }
    }

    /// When stderr is not a terminal and a line is due (an interval since the last one): the
    /// seconds elapsed since the start, and the line counts as printed.
    fn line_due(&self) -> Option<f64> {
        let (interval, last) = self.lines.as_ref()?;
        let mut last = last.lock().ok()?;
        let now = Instant::now();
        if now.duration_since(*last) < *interval {
            return None;
        }
        *last = now;
        Some(now.duration_since(self.started).as_secs_f64())
    }

    /// The job is done: clear the bar.
    pub fn finish(self) {
        if let Some(b) = self.bar {
            b.finish_and_clear();
        }
    }
}
