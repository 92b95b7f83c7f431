//! `--kalibr FILE`: the IMU noise file (Kalibr, OpenVINS or VINS-Fusion keys) that `allan` and
//! `diagnose` write, from the Allan fit of a log or from a corrected model. The format and the
//! meaning of each value are in docs/noise-files.md; the writer is `noise::noise_file`.

use anyhow::{bail, Result};
use noise::noise_file::{write_noise_file, AxisValue, Flavor, Inflation, NoiseValues};
use std::path::PathBuf;

/// `--noise-format`: whose keys the noise file uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum NoiseFormat {
    Kalibr,
    Openvins,
    VinsFusion,
}

impl NoiseFormat {
    fn flavor(self) -> Flavor {
        match self {
            NoiseFormat::Kalibr => Flavor::Kalibr,
            NoiseFormat::Openvins => Flavor::OpenVins,
            NoiseFormat::VinsFusion => Flavor::VinsFusion,
        }
    }

    /// As written on the command line.
    fn name(self) -> &'static str {
        match self {
            NoiseFormat::Kalibr => "kalibr",
            NoiseFormat::Openvins => "openvins",
            NoiseFormat::VinsFusion => "vins-fusion",
        }
    }
}

/// The noise-file options, shared by `allan` and `diagnose`.
#[derive(clap::Args, Clone, Debug)]
pub struct NoiseFileArgs {
    /// Write the IMU noise file visual-inertial tools read (Kalibr imu.yaml keys by default):
    /// continuous-time noise density and random walk, worst axis, per-axis values in comments
    #[arg(long, value_name = "FILE")]
    pub kalibr: Option<PathBuf>,
    /// Keys of the noise file: kalibr (imu.yaml), openvins (kalibr_imu_chain.yaml), vins-fusion
    #[arg(long, value_name = "FORMAT", value_enum, default_value = "kalibr")]
    pub noise_format: NoiseFormat,
    /// Multiply the written values by this margin (e.g. 10 for the random walk is common in VIO
    /// tuning); the measured values stay in the file's comments
    #[arg(long, value_name = "FACTOR", default_value_t = 1.0)]
    pub inflate: f64,
    /// `rostopic` written into the noise file (default: the bag's IMU topic, else /imu0)
    #[arg(long, value_name = "TOPIC")]
    pub rostopic: Option<String>,
}

impl NoiseFileArgs {
    /// Refuse a noise file path that is one of the command's inputs (noted before).
    pub fn refuse_inputs(&self) -> Result<()> {
        match &self.kalibr {
            Some(path) => crate::output::refuse_input_as_output("--kalibr", path),
            None => Ok(()),
        }
    }

    /// Check the options before any work.
    pub fn check(&self) -> Result<()> {
        if !(self.inflate.is_finite() && self.inflate >= 1.0) {
            bail!(
                "--inflate {}: expected a factor of at least 1 (1 = the measured values)",
                self.inflate
            );
        }
        Ok(())
    }

    /// Write the file if asked. `per_channel[c]` = (noise density, random walk) of channel c,
    /// `None` where the log has no such channel.
    pub fn write(
        &self,
        per_channel: &noise::ImuChannels<Option<(AxisValue, AxisValue)>>,
        update_rate_hz: f64,
        origin: &str,
        log_topic: Option<&str>,
    ) -> Result<()> {
        let Some(path) = &self.kalibr else {
            return Ok(());
        };
        let missing: Vec<&str> = per_channel
            .iter()
            .filter(|(_, v)| v.is_none())
            .map(|(c, _)| c.name())
            .collect();
        if !missing.is_empty() {
            bail!(
                "--kalibr {}: a noise file needs the three gyro and three accelerometer channels; the log has no {}",
                path.display(),
                missing.join(", ")
            );
        }
        let values = NoiseValues::from_channels(
            |c| per_channel[c].clone().expect("checked above"),
            self.rostopic
                .clone()
                .or(log_topic.map(str::to_string))
                .unwrap_or_else(|| "/imu0".into()),
            update_rate_hz,
            origin.to_string(),
        );
        let inflation = Inflation {
            factor: self.inflate,
            setting: "--inflate",
        };
        let text = write_noise_file(&values, self.noise_format.flavor(), inflation);
        crate::output::write_string(path, &text)?;
        tell!(
            "wrote {} ({} keys{})",
            path.display(),
            self.noise_format.name(),
            if self.inflate != 1.0 {
                format!(", inflated x{}", self.inflate)
            } else {
                String::new()
            }
        );
        Ok(())
    }
}
