//! Units of the time, gyro and accelerometer columns and their factors to SI.

use super::STANDARD_GRAVITY_MPS2;

/// Gyro units accepted on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum GyroUnit {
    #[value(name = "rad/s")]
    RadPerS,
    #[value(name = "deg/s")]
    DegPerS,
    #[value(name = "deg/h")]
    DegPerH,
}

impl GyroUnit {
    /// As written on the command line and in outputs.
    pub fn name(self) -> &'static str {
        match self {
            GyroUnit::RadPerS => "rad/s",
            GyroUnit::DegPerS => "deg/s",
            GyroUnit::DegPerH => "deg/h",
        }
    }

    pub(super) fn to_si(self) -> f64 {
        match self {
            GyroUnit::RadPerS => 1.0,
            GyroUnit::DegPerS => std::f64::consts::PI / 180.0,
            GyroUnit::DegPerH => std::f64::consts::PI / 180.0 / 3600.0,
        }
    }
}

/// Accelerometer units accepted on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum AccelUnit {
    #[value(name = "m/s^2")]
    MPerS2,
    #[value(name = "g")]
    G,
    #[value(name = "mg")]
    MilliG,
}

impl AccelUnit {
    /// As written on the command line and in outputs.
    pub fn name(self) -> &'static str {
        match self {
            AccelUnit::MPerS2 => "m/s^2",
            AccelUnit::G => "g",
            AccelUnit::MilliG => "mg",
        }
    }

    pub(super) fn to_si(self) -> f64 {
        match self {
            AccelUnit::MPerS2 => 1.0,
            AccelUnit::G => STANDARD_GRAVITY_MPS2,
            AccelUnit::MilliG => STANDARD_GRAVITY_MPS2 * 1e-3,
        }
    }
}

/// Units of the time column.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum TimeUnit {
    #[value(name = "s")]
    S,
    #[value(name = "ms")]
    Ms,
    #[value(name = "us")]
    Us,
    #[value(name = "ns")]
    Ns,
}

impl TimeUnit {
    /// As written on the command line and in outputs.
    pub fn name(self) -> &'static str {
        match self {
            TimeUnit::S => "s",
            TimeUnit::Ms => "ms",
            TimeUnit::Us => "us",
            TimeUnit::Ns => "ns",
        }
    }

    pub(super) fn to_si(self) -> f64 {
        match self {
            TimeUnit::S => 1.0,
            TimeUnit::Ms => 1e-3,
            TimeUnit::Us => 1e-6,
            TimeUnit::Ns => 1e-9,
        }
    }
}
