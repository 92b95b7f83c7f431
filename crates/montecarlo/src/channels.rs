//! The drift channels recorded at each checkpoint (docs/cli.md JSON names).

/// One recorded navigation-error channel. The discriminant is the column index.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Channel {
    Roll,
    Pitch,
    Yaw,
    PosNorth,
    PosEast,
    PosDown,
    PosHorizontal,
    VelNorth,
    VelEast,
    VelDown,
    VelHorizontal,
}

impl Channel {
    pub const ALL: [Channel; 11] = [
        Channel::Roll,
        Channel::Pitch,
        Channel::Yaw,
        Channel::PosNorth,
        Channel::PosEast,
        Channel::PosDown,
        Channel::PosHorizontal,
        Channel::VelNorth,
        Channel::VelEast,
        Channel::VelDown,
        Channel::VelHorizontal,
    ];

    /// The JSON / CSV name (docs/cli.md: these may not be renamed).
    pub fn name(self) -> &'static str {
        match self {
            Channel::Roll => "roll_rad",
            Channel::Pitch => "pitch_rad",
            Channel::Yaw => "yaw_rad",
            Channel::PosNorth => "pos_north_m",
            Channel::PosEast => "pos_east_m",
            Channel::PosDown => "pos_down_m",
            Channel::PosHorizontal => "pos_horizontal_m",
            Channel::VelNorth => "vel_north_mps",
            Channel::VelEast => "vel_east_mps",
            Channel::VelDown => "vel_down_mps",
            Channel::VelHorizontal => "vel_horizontal_mps",
        }
    }

    pub fn from_name(name: &str) -> Option<Channel> {
        Channel::ALL.into_iter().find(|c| c.name() == name)
    }

    /// Channel values of one navigation error, in [`Channel::ALL`] order.
    pub fn values(e: &strapdown::NavError) -> [f64; 11] {
        [
            e.roll_rad,
            e.pitch_rad,
            e.yaw_rad,
            e.pos_ned_m[0],
            e.pos_ned_m[1],
            e.pos_ned_m[2],
            e.pos_horizontal_m(),
            e.vel_ned_mps[0],
            e.vel_ned_mps[1],
            e.vel_ned_mps[2],
            e.vel_horizontal_mps(),
        ]
    }
}
