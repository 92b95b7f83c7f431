//! The ideal readings of a static, level IMU: what every channel reads without error when the IMU
//! stands still and level (body frame forward-right-down, z down; the Earth's rotation neglected).
//! The gyros read zero; the accelerometers read the specific force (0, 0, -g) that holds the IMU
//! up against gravity.

use crate::channel::{Channel, ImuChannels};
use crate::effect::Sensor;
use crate::units::STANDARD_GRAVITY_MPS2;
use nalgebra::Vector3;

/// A static, level IMU under a given gravity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StaticLevel {
    gravity_mps2: f64,
}

impl StaticLevel {
    /// Under standard gravity ([`STANDARD_GRAVITY_MPS2`]).
    pub const STANDARD: StaticLevel = StaticLevel {
        gravity_mps2: STANDARD_GRAVITY_MPS2,
    };

    /// Under gravity `gravity_mps2` (m/s^2, the magnitude; a scenario's local value).
    pub fn with_gravity(gravity_mps2: f64) -> StaticLevel {
        StaticLevel { gravity_mps2 }
    }

    /// The ideal reading of `sensor`'s triad: rad/s for the gyros, m/s^2 for the accelerometers.
    pub fn triad(self, sensor: Sensor) -> Vector3<f64> {
        match sensor {
            Sensor::Gyro => Vector3::zeros(),
            Sensor::Accel => Vector3::new(0.0, 0.0, -self.gravity_mps2),
        }
    }

    /// The ideal reading of one channel.
    pub fn reading(self, channel: Channel) -> f64 {
        self.triad(channel.sensor())[channel.axis()]
    }

    /// Every channel's ideal triad input (its sensor's triad), as `ChannelErrors::fill_static`
    /// takes it.
    pub fn inputs(self) -> ImuChannels<Vector3<f64>> {
        ImuChannels::from_fn(|c| self.triad(c.sensor()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_az_reads_minus_g() {
        for c in Channel::ALL {
            let want = if c == Channel::Az {
                -STANDARD_GRAVITY_MPS2
            } else {
                0.0
            };
            assert_eq!(StaticLevel::STANDARD.reading(c), want, "{c}");
        }
        assert_eq!(StaticLevel::with_gravity(9.78).reading(Channel::Az), -9.78);
        let inputs = StaticLevel::STANDARD.inputs();
        assert_eq!(
            inputs[Channel::Ay],
            StaticLevel::STANDARD.triad(Sensor::Accel)
        );
        assert_eq!(inputs[Channel::Gz], Vector3::zeros());
    }
}
