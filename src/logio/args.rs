//! The log reader's command-line options, shared by every command that reads a log.

use super::csv::MAX_LOG_RATE_HZ;
use super::{AccelUnit, GyroUnit, ReadOptions};
use anyhow::{anyhow, bail, Result};

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
