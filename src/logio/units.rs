//! Units of the gyro and accelerometer columns and their factors to SI.

use super::STANDARD_GRAVITY_MPS2;

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
    pub(super) fn to_si(self) -> f64 {
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
    pub(super) fn to_si(self) -> f64 {
        match self {
            AccelUnit::MPerS2 => 1.0,
            AccelUnit::G => STANDARD_GRAVITY_MPS2,
            AccelUnit::MilliG => STANDARD_GRAVITY_MPS2 * 1e-3,
        }
    }
}
