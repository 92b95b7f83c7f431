//! The navigation-error quantities recorded at each checkpoint (docs/cli.md JSON names). Not to be
//! confused with an IMU sensor channel (`noise::Channel`).

/// One recorded navigation-error quantity. The discriminant is the column index.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum NavQuantity {
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

impl NavQuantity {
    pub const ALL: [NavQuantity; 11] = [
        NavQuantity::Roll,
        NavQuantity::Pitch,
        NavQuantity::Yaw,
        NavQuantity::PosNorth,
        NavQuantity::PosEast,
        NavQuantity::PosDown,
        NavQuantity::PosHorizontal,
        NavQuantity::VelNorth,
        NavQuantity::VelEast,
        NavQuantity::VelDown,
        NavQuantity::VelHorizontal,
    ];

    /// The JSON / CSV name (docs/cli.md: these may not be renamed).
    pub fn name(self) -> &'static str {
        match self {
            NavQuantity::Roll => "roll_rad",
            NavQuantity::Pitch => "pitch_rad",
            NavQuantity::Yaw => "yaw_rad",
            NavQuantity::PosNorth => "pos_north_m",
            NavQuantity::PosEast => "pos_east_m",
            NavQuantity::PosDown => "pos_down_m",
            NavQuantity::PosHorizontal => "pos_horizontal_m",
            NavQuantity::VelNorth => "vel_north_mps",
            NavQuantity::VelEast => "vel_east_mps",
            NavQuantity::VelDown => "vel_down_mps",
            NavQuantity::VelHorizontal => "vel_horizontal_mps",
        }
    }

    /// The one name people read for the quantity (tables, messages, requirements): `heading_rad`
    /// for the heading error, whose JSON key stays `yaw_rad` (with `heading_rad` beside it);
    /// the others as [`NavQuantity::name`].
    pub fn label(self) -> &'static str {
        match self {
            NavQuantity::Yaw => "heading_rad",
            q => q.name(),
        }
    }

    /// The quantity of a name: its JSON name or label, and for the heading also `heading` and
    /// `yaw` (scripts written for the older `yaw_rad` keep working).
    pub fn from_name(name: &str) -> Option<NavQuantity> {
        if matches!(name, "heading" | "yaw") {
            return Some(NavQuantity::Yaw);
        }
        NavQuantity::ALL
            .into_iter()
            .find(|c| c.name() == name || c.label() == name)
    }

    /// The quantities' values of one navigation error, in [`NavQuantity::ALL`] order.
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
