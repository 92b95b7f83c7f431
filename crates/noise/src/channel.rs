//! One IMU output channel (a sensor and an axis), and per-channel data.
//!
//! A channel is one of the six outputs of an IMU: the gyro x, y, z rates and the accelerometer
//! x, y, z specific forces, in that order (`gx gy gz ax ay az`, the log column names). Code that
//! holds one value per channel uses [`ImuChannels`] rather than a bare `[T; 6]` or a `usize` index.

use crate::effect::Sensor;
use std::fmt;
use std::ops::{Index, IndexMut};

/// The names of the axes of a triad, in axis order.
pub const AXIS_NAMES: [&str; 3] = ["x", "y", "z"];

/// One output channel of an IMU.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Channel {
    Gx,
    Gy,
    Gz,
    Ax,
    Ay,
    Az,
}

impl Channel {
    /// Every channel in log-column order (gyros first).
    pub const ALL: [Channel; 6] = [
        Channel::Gx,
        Channel::Gy,
        Channel::Gz,
        Channel::Ax,
        Channel::Ay,
        Channel::Az,
    ];

    /// The channel of `sensor`'s axis `axis` (0 = x, 1 = y, 2 = z).
    ///
    /// # Panics
    /// If `axis > 2` (a programming error: axes come from `0..3` loops or [`Channel::axis`]).
    pub fn new(sensor: Sensor, axis: usize) -> Channel {
        assert!(axis < 3, "axis {axis} is not 0, 1 or 2");
        match sensor {
            Sensor::Gyro => Channel::ALL[axis],
            Sensor::Accel => Channel::ALL[3 + axis],
        }
    }

    /// The channel at position `index` of [`Channel::ALL`], if `index < 6`.
    pub fn from_index(index: usize) -> Option<Channel> {
        Channel::ALL.get(index).copied()
    }

    /// The position in [`Channel::ALL`] (0..6): the stream index and the log-column order.
    pub fn index(self) -> usize {
        self as usize
    }

    /// Gyro or accelerometer.
    pub fn sensor(self) -> Sensor {
        if self.index() < 3 {
            Sensor::Gyro
        } else {
            Sensor::Accel
        }
    }

    /// The axis within the triad: 0 = x, 1 = y, 2 = z.
    pub fn axis(self) -> usize {
        self.index() % 3
    }

    /// Is this a gyro channel?
    pub fn is_gyro(self) -> bool {
        self.sensor() == Sensor::Gyro
    }

    /// The log-column name: `gx gy gz ax ay az`.
    pub fn name(self) -> &'static str {
        ["gx", "gy", "gz", "ax", "ay", "az"][self.index()]
    }

    /// The channel named `name` (`gx` ... `az`), if any.
    pub fn from_name(name: &str) -> Option<Channel> {
        Channel::ALL.into_iter().find(|c| c.name() == name)
    }

    /// The three channels of `sensor`, in axis order.
    pub fn of(sensor: Sensor) -> [Channel; 3] {
        [0, 1, 2].map(|axis| Channel::new(sensor, axis))
    }
}

impl fmt::Display for Channel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl serde::Serialize for Channel {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

/// One value per channel, indexed by [`Channel`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImuChannels<T>(pub [T; 6]);

impl<T> ImuChannels<T> {
    /// Build from a function of the channel.
    pub fn from_fn(mut f: impl FnMut(Channel) -> T) -> ImuChannels<T> {
        ImuChannels(Channel::ALL.map(&mut f))
    }

    /// `(channel, &value)` pairs in channel order.
    pub fn iter(&self) -> impl Iterator<Item = (Channel, &T)> {
        Channel::ALL.into_iter().zip(self.0.iter())
    }

    /// `(channel, &mut value)` pairs in channel order.
    pub fn iter_mut(&mut self) -> impl Iterator<Item = (Channel, &mut T)> {
        Channel::ALL.into_iter().zip(self.0.iter_mut())
    }

    /// The values in channel order.
    pub fn values(&self) -> &[T; 6] {
        &self.0
    }

    /// A new per-channel value from each value.
    pub fn map<U>(self, mut f: impl FnMut(Channel, T) -> U) -> ImuChannels<U> {
        let mut i = 0;
        ImuChannels(self.0.map(|v| {
            let c = Channel::ALL[i];
            i += 1;
            f(c, v)
        }))
    }
}

impl<T> Index<Channel> for ImuChannels<T> {
    type Output = T;
    fn index(&self, c: Channel) -> &T {
        &self.0[c.index()]
    }
}

impl<T> IndexMut<Channel> for ImuChannels<T> {
    fn index_mut(&mut self, c: Channel) -> &mut T {
        &mut self.0[c.index()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channel_round_trips() {
        for (i, c) in Channel::ALL.into_iter().enumerate() {
            assert_eq!(c.index(), i);
            assert_eq!(Channel::from_index(i), Some(c));
            assert_eq!(Channel::new(c.sensor(), c.axis()), c);
            assert_eq!(Channel::from_name(c.name()), Some(c));
            assert_eq!(c.is_gyro(), i < 3);
        }
        assert_eq!(Channel::from_index(6), None);
        assert_eq!(Channel::from_name("temp"), None);
        assert_eq!(
            Channel::of(Sensor::Accel),
            [Channel::Ax, Channel::Ay, Channel::Az]
        );
        let v = ImuChannels::from_fn(|c| c.index() * 10);
        assert_eq!(v[Channel::Az], 50);
        assert_eq!(v.map(|c, x| x + c.axis())[Channel::Ay], 41);
    }
}
