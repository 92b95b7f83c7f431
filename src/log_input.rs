//! Reading logs for the commands: the reader's command-line options (shared by every command
//! that reads a log), converted into the `logio` crate's plain settings, and the reader's errors
//! and column mapping told with the flags that set them.

use crate::cli::named;
use anyhow::{anyhow, bail, Result};
use logio::{AccelUnit, GyroUnit, Log, LogError, ReadOptions, Setting, TimeUnit};
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// Command-line options of the log reader (flatten into a command's Args).
#[derive(clap::Args, Clone, Debug)]
pub struct LogArgs {
    /// Sample rate in Hz (required when the log has no `t` column; overrides it otherwise)
    #[arg(long, value_name = "HZ")]
    pub rate: Option<f64>,
    /// Unit of every gyro column whose name does not say it (`gyro_x_dps` does; `gx` defaults to rad/s)
    #[arg(long, value_name = "UNIT", value_parser = named(GyroUnit::ALL, GyroUnit::name))]
    pub gyro_unit: Option<GyroUnit>,
    /// Unit of every accelerometer column whose name does not say it (`acc_x_g` does; `ax` defaults to m/s^2)
    #[arg(long, value_name = "UNIT", value_parser = named(AccelUnit::ALL, AccelUnit::name))]
    pub accel_unit: Option<AccelUnit>,
    /// Unit of the time column when its name does not say it (`t_ms`, `timestamp_ns` do; default s)
    #[arg(long, value_name = "UNIT", value_parser = named(TimeUnit::ALL, TimeUnit::name))]
    pub time_unit: Option<TimeUnit>,
    /// The sensor_msgs/Imu topic to read from a ROS bag or MCAP file (default: the only one)
    #[arg(long, value_name = "TOPIC")]
    pub topic: Option<String>,
    /// Map a file column to a channel by hand, e.g. `--col gx=gyro_meas_x` (repeat or comma-separate); columns are otherwise recognised by name
    #[arg(long = "col", value_name = "NAME=COLUMN", value_delimiter = ',')]
    pub columns: Vec<String>,
}

/// Where a static log was recorded, for the commands that dead-reckon it (flatten into a
/// command's Args): the round, rotating WGS-84 Earth at `--latitude` (height held), or Woodman's
/// flat Earth with `--flat-earth`.
#[derive(clap::Args, Clone, Debug)]
pub struct EarthArgs {
    /// Latitude the logs were recorded at, deg (north positive; -89..89; default 45): the
    /// segments are dead-reckoned on the rotating WGS-84 Earth there, Earth rate kept as signal
    #[arg(long, value_name = "DEG", allow_hyphen_values = true, value_parser = latitude_deg)]
    pub latitude: Option<f64>,
    /// Dead-reckon on Woodman's flat, non-rotating Earth instead (no Earth rate, constant g)
    #[arg(long, conflicts_with = "latitude")]
    pub flat_earth: bool,
}

impl EarthArgs {
    /// Where the logs were recorded, as the request layer takes it.
    pub fn earth(&self) -> request::diagnose::Earth {
        use request::diagnose::Earth;
        match (self.flat_earth, self.latitude) {
            (true, _) => Earth::Flat,
            (false, Some(v)) => Earth::Latitude(v),
            (false, None) => Earth::DefaultLatitude,
        }
    }

    /// A note when the latitude was left at its default and a horizon reaches beyond a few
    /// minutes: a sensor whose attitude errors grow to degrees mixes Earth rate into its heading
    /// there, so such verdicts can depend on where the logs were recorded (docs/drift.md, "The
    /// logs' latitude").
    pub fn note(&self, longest_horizon_s: f64) {
        if self.latitude.is_none() && !self.flat_earth && longest_horizon_s > 300.0 {
            tell!(
                "note: the logs' latitude was not given: they are dead-reckoned on the rotating Earth at {} deg N; \
                 over horizons beyond a few minutes large attitude errors couple Earth rate into the heading, \
                 so give --latitude where the verdicts there matter (docs/drift.md, \"The logs' latitude\")",
                diagnose::protocol::DEFAULT_LATITUDE_DEG
            );
        }
    }
}

/// A latitude in degrees (its range is the request layer's rule, `request::diagnose::Earth`).
fn latitude_deg(text: &str) -> std::result::Result<f64, String> {
    text.trim()
        .parse()
        .map_err(|_| format!("expected a latitude in degrees, e.g. 45 or -33.9, got {text:?}"))
}

/// The flag that sets each reader setting.
pub fn flag(setting: Setting) -> &'static str {
    match setting {
        Setting::Rate => "--rate",
        Setting::Columns => "--col",
        Setting::GyroUnit => "--gyro-unit",
        Setting::AccelUnit => "--accel-unit",
        Setting::TimeUnit => "--time-unit",
        Setting::Topic => "--topic",
    }
}

impl LogArgs {
    /// Validated reader settings.
    pub fn options(&self) -> Result<ReadOptions> {
        let mut map = Vec::new();
        for c in &self.columns {
            let (name, col) = c
                .split_once('=')
                .ok_or_else(|| anyhow!("--col {c:?}: expected NAME=COLUMN, e.g. gx=gyro_x_dps"))?;
            let name = name.trim();
            if !(name == "t" || name == "temp" || noise::Channel::from_name(name).is_some()) {
                bail!("--col {c:?}: {name:?} is not one of t, gx, gy, gz, ax, ay, az, temp");
            }
            map.push((name.to_string(), col.trim().to_string()));
        }
        if let Some(rate_hz) = self.rate.filter(|&r| !logio::valid_rate_hz(r)) {
            bail!(logio::Problem::BadRate { rate_hz }.render(&flag));
        }
        Ok(ReadOptions {
            rate_hz: self.rate,
            units: logio::UnitOptions {
                gyro: self.gyro_unit,
                accel: self.accel_unit,
                time: self.time_unit,
            },
            columns: map,
            topic: self.topic.clone(),
        })
    }

    /// Read the log at `path` with these options.
    pub fn read(&self, path: &Path) -> Result<Log> {
        read_log(path, &self.options()?)
    }

    /// Read the logs at `paths` with these options, several at once (decompressing a gzip log
    /// is one thread's work: six ADIS16405 logs one after the other held `drift` on one core for
    /// its first second), in the order given; the first failing path's error, as read alone.
    /// Each reader refuses a log that would not fit in the memory available when it starts, so
    /// logs read side by side could pass that check together and not fit together: they are read
    /// one after the other unless their files are small beside the memory available
    /// ([`fits_side_by_side`]).
    pub fn read_all(&self, paths: &[PathBuf]) -> Result<Vec<Log>> {
        let opts = self.options()?;
        let logs: Vec<Result<Log>> = if fits_side_by_side(paths, logio::available_memory_bytes()) {
            paths.par_iter().map(|path| read_log(path, &opts)).collect()
        } else {
            // Stop at the first failure, as one after the other always did.
            let mut logs = Vec::with_capacity(paths.len());
            for path in paths {
                logs.push(Ok(read_log(path, &opts)?));
            }
            logs
        };
        logs.into_iter().collect()
    }
}

/// Bytes of memory a log may take while it is read, per byte of its file: real CSV logs compress
/// less than 10 times (2.4 to 7.3 measured, the note on `logio`'s gzip limit), and the reader
/// holds the text and at most 8 bytes of columns per byte of it (a value is at least 2 bytes of
/// text, "0,", and 16 parsed: `logio`'s own bound), 9 bytes per byte of text; 100 covers both.
const READ_BYTES_PER_FILE_BYTE: u64 = 100;

/// Whether the logs at `paths` may be read side by side: their files' sizes together, at
/// [`READ_BYTES_PER_FILE_BYTE`], within half the memory `available` (unknown: as the readers
/// themselves, which then check nothing). A file that cannot be inspected is left to its reader,
/// read one after the other, to report.
fn fits_side_by_side(paths: &[PathBuf], available: Option<u64>) -> bool {
    let Some(available) = available else {
        return true;
    };
    let mut total = 0u64;
    for path in paths {
        // A ROS 2 bag is a directory: its files' sizes.
        let size = if path.is_dir() {
            std::fs::read_dir(path).ok().map(|entries| {
                entries
                    .flatten()
                    .filter_map(|e| e.metadata().ok())
                    .map(|m| m.len())
                    .sum::<u64>()
            })
        } else {
            std::fs::metadata(path).ok().map(|m| m.len())
        };
        let Some(size) = size else {
            return false;
        };
        total = total.saturating_add(size.saturating_mul(READ_BYTES_PER_FILE_BYTE));
    }
    total <= available / 2
}

/// Read a log; a reader error is told with the flags that set what it names.
pub fn read_log(path: &Path, opts: &ReadOptions) -> Result<Log> {
    logio::read_log(path, opts).map_err(|e| anyhow::Error::new(WithFlags(e)))
}

/// A reader error shown with the command line's flags for the settings it names.
#[derive(Debug)]
struct WithFlags(LogError);

impl std::fmt::Display for WithFlags {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0.render(&flag))
    }
}

impl std::error::Error for WithFlags {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        std::error::Error::source(&self.0)
    }
}

/// The column mapping in one line for people (`gyro_x_dps -> gx (deg/s, from the name)`).
pub fn mapping_text(log: &Log) -> String {
    log.mapping_text(&flag)
}

/// `columns[]` and `skipped_columns[]` of the JSON (docs/cli.md, "Log files"), with the flags.
pub fn columns_json(log: &Log) -> (serde_json::Value, serde_json::Value) {
    log.columns_json(&flag)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Side by side only when the files at 100 bytes per byte fit in half the memory; unknown
    /// memory: side by side; a path that cannot be inspected: one after the other.
    #[test]
    fn logs_side_by_side_only_when_they_fit() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.csv");
        let b = dir.path().join("b.csv");
        std::fs::write(&a, vec![b'0'; 1000]).unwrap();
        std::fs::write(&b, vec![b'0'; 3000]).unwrap();
        let both = [a.clone(), b];
        // 4000 bytes x 100 = 400 000: fits in half of 800 000, not in half of 799 999.
        assert!(fits_side_by_side(&both, Some(800_000)));
        assert!(!fits_side_by_side(&both, Some(799_999)));
        assert!(fits_side_by_side(&both, None));
        let missing = [a, dir.path().join("missing.csv")];
        assert!(!fits_side_by_side(&missing, Some(u64::MAX)));
    }
}
