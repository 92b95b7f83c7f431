//! The log reader's command-line options, shared by every command that reads a log.

use super::csv::MAX_LOG_RATE_HZ;
use super::{AccelUnit, GyroUnit, ReadOptions, TimeUnit};
use anyhow::{anyhow, bail, Result};

/// Command-line options of the log reader (flatten into a command's Args).
#[derive(clap::Args, Clone, Debug)]
pub struct LogArgs {
    /// Sample rate in Hz (required when the log has no `t` column; overrides it otherwise)
    #[arg(long, value_name = "HZ")]
    pub rate: Option<f64>,
    /// Unit of every gyro column whose name does not say it (`gyro_x_dps` does; `gx` defaults to rad/s)
    #[arg(long, value_enum, value_name = "UNIT")]
    pub gyro_unit: Option<GyroUnit>,
    /// Unit of every accelerometer column whose name does not say it (`acc_x_g` does; `ax` defaults to m/s^2)
    #[arg(long, value_enum, value_name = "UNIT")]
    pub accel_unit: Option<AccelUnit>,
    /// Unit of the time column when its name does not say it (`t_ms`, `timestamp_ns` do; default s)
    #[arg(long, value_enum, value_name = "UNIT")]
    pub time_unit: Option<TimeUnit>,
    /// The sensor_msgs/Imu topic to read from a ROS bag or MCAP file (default: the only one)
    #[arg(long, value_name = "TOPIC")]
    pub topic: Option<String>,
    /// Map a file column to a channel by hand, e.g. `--col gx=gyro_meas_x` (repeat or comma-separate); columns are otherwise recognised by name
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
            units: super::UnitOptions {
                gyro: self.gyro_unit,
                accel: self.accel_unit,
                time: self.time_unit,
            },
            columns: map,
            topic: self.topic.clone(),
        })
    }
}
