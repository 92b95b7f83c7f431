//! Units of the time, gyro and accelerometer columns and their factors to SI.

use noise::units::STANDARD_GRAVITY_MPS2;

/// Gyro units.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GyroUnit {
    RadPerS,
    DegPerS,
    DegPerH,
}

impl GyroUnit {
    /// Every gyro unit.
    pub const ALL: [GyroUnit; 3] = [GyroUnit::RadPerS, GyroUnit::DegPerS, GyroUnit::DegPerH];

    /// As written in messages and outputs (and in the column mapping).
    pub fn name(self) -> &'static str {
        match self {
            GyroUnit::RadPerS => "rad/s",
            GyroUnit::DegPerS => "deg/s",
            GyroUnit::DegPerH => "deg/h",
        }
    }

    pub(crate) fn to_si(self) -> f64 {
        match self {
            GyroUnit::RadPerS => 1.0,
            GyroUnit::DegPerS => std::f64::consts::PI / 180.0,
            GyroUnit::DegPerH => std::f64::consts::PI / 180.0 / 3600.0,
        }
    }
}

/// Accelerometer units.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccelUnit {
    MPerS2,
    G,
    MilliG,
}

impl AccelUnit {
    /// Every accelerometer unit.
    pub const ALL: [AccelUnit; 3] = [AccelUnit::MPerS2, AccelUnit::G, AccelUnit::MilliG];

    /// As written in messages and outputs (and in the column mapping).
    pub fn name(self) -> &'static str {
        match self {
            AccelUnit::MPerS2 => "m/s^2",
            AccelUnit::G => "g",
            AccelUnit::MilliG => "mg",
        }
    }

    pub(crate) fn to_si(self) -> f64 {
        match self {
            AccelUnit::MPerS2 => 1.0,
            AccelUnit::G => STANDARD_GRAVITY_MPS2,
            AccelUnit::MilliG => STANDARD_GRAVITY_MPS2 * 1e-3,
        }
    }
}

/// Units of the time column.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeUnit {
    S,
    Ms,
    Us,
    Ns,
}

impl TimeUnit {
    /// Every time unit (seconds first).
    pub const ALL: [TimeUnit; 4] = [TimeUnit::S, TimeUnit::Ms, TimeUnit::Us, TimeUnit::Ns];

    /// As written in messages and outputs (and in the column mapping).
    pub fn name(self) -> &'static str {
        match self {
            TimeUnit::S => "s",
            TimeUnit::Ms => "ms",
            TimeUnit::Us => "us",
            TimeUnit::Ns => "ns",
        }
    }

    pub(crate) fn to_si(self) -> f64 {
        match self {
            TimeUnit::S => 1.0,
            TimeUnit::Ms => 1e-3,
            TimeUnit::Us => 1e-6,
            TimeUnit::Ns => 1e-9,
        }
    }
}
