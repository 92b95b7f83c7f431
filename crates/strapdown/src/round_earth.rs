//! The round, rotating Earth in the lanes' mechanisation ([`crate::StrapdownLanes`] with a
//! [`RoundEarth`]): local-level north-east-down navigation on the WGS-84 ellipsoid (Groves §5.4,
//! Titterton & Weston §3.5), the per-lane quantities of one step.
//!
//! Per step, from the state at its start (latitude L, height h, velocity v):
//! - the navigation frame turns at omega_in = omega_ie + omega_en (Earth rate and transport rate,
//!   [`crate::earth`]), so after the body rotation C <- exp(-[omega_in dt x]) C (Groves eq 5.45);
//! - dv/dt = C f + g(L, h) - (2 omega_ie + omega_en) x v (eq 5.53), g = (0, 0, gamma(L, h)) normal
//!   gravity (its north component, about 8e-9 h sin 2L m/s^2, is left out);
//! - dL/dt = v_N / (R_N + h), dlambda/dt = v_E / ((R_E + h) cos L), dh/dt = -v_D (eq 5.56).
//!
//! Position is held as latitude, longitude and height; [`crate::NavState`]'s position is
//! reported as north, east, down metres from the start place (latitude and longitude differences
//! times the start place's radii), so a solution minus its truth is the position error in metres
//! to first order in the error over the Earth's radius.
//!
//! The vertical channel is unstable (its error grows as cosh(t sqrt(2 g / R)), time constant
//! about 570 s): [`Vertical::Free`] integrates it as is, [`Vertical::Held`] is a known height (the
//! down velocity and the height kept at their start values: a barometer or a surface vehicle).

use crate::earth::{gravity_sin2, radii_sin2, Place, EARTH_RATE_RAD_S};
use crate::{Attitude, BodyVector, NavVector};

/// How the unaided vertical channel is treated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Vertical {
    /// Integrated freely (it diverges; the error is reported as it grows).
    #[default]
    Free,
    /// A known height: down velocity and height held at their start values.
    Held,
}

/// The Earth a [`crate::StrapdownLanes`] navigates on, beyond Woodman's flat one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoundEarth {
    /// Where the navigation starts (the origin of the reported NED positions).
    pub place: Place,
    /// The vertical channel.
    pub vertical: Vertical,
    /// Earth rate on (default); off gives a round, non-rotating Earth (the Schuler loop alone,
    /// for checking the uncoupled closed forms).
    pub rotating: bool,
}

impl RoundEarth {
    /// A rotating WGS-84 Earth at `place` with a free vertical channel.
    pub fn at(place: Place) -> RoundEarth {
        RoundEarth {
            place,
            vertical: Vertical::Free,
            rotating: true,
        }
    }

    /// Earth rate as used by the mechanisation, rad/s.
    pub fn rate_rad_s(&self) -> f64 {
        if self.rotating {
            EARTH_RATE_RAD_S
        } else {
            0.0
        }
    }

    /// What an ideal IMU at rest at the start place reads in its body frame, its attitude
    /// `attitude` (body to NED): Earth rate omega_ie (cos L, 0, -sin L) and the specific force
    /// (0, 0, -gamma), both resolved in the body frame (theory: a static level IMU facing north at
    /// 45 deg N reads Earth rate on its x and z gyros).
    pub fn static_imu(&self, attitude: &Attitude) -> (BodyVector, BodyVector) {
        let (s, c) = self.place.lat_rad.sin_cos();
        let w = self.rate_rad_s();
        (
            attitude.to_body(&NavVector::new(w * c, 0.0, -w * s)),
            attitude.to_body(&NavVector::new(0.0, 0.0, -self.place.gravity_mps2())),
        )
    }
}

/// The start place's constants the step needs (computed once).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Origin {
    pub earth: RoundEarth,
    pub sin0: f64,
    pub cos0: f64,
    /// (R_N + h0) and (R_E + h0) cos L0: metres per radian of latitude and of longitude there.
    pub m_per_rad_lat: f64,
    pub m_per_rad_lon: f64,
}

impl Origin {
    pub fn new(earth: RoundEarth) -> Origin {
        let p = earth.place;
        let (rn, re) = crate::earth::radii_m(p.lat_rad);
        let (sin0, cos0) = p.lat_rad.sin_cos();
        Origin {
            earth,
            sin0,
            cos0,
            m_per_rad_lat: rn + p.height_m,
            m_per_rad_lon: (re + p.height_m) * cos0,
        }
    }

    /// sin L and cos L near the start latitude: the sum formulas with series of the difference
    /// (to degree 8: below 1e-15 for |L - L0| < 0.05 rad, 320 km), else the library's.
    #[inline(always)]
    pub fn sin_cos(&self, lat: f64) -> (f64, f64) {
        let d = lat - self.earth.place.lat_rad;
        if d.abs() < 0.05 {
            let d2 = d * d;
            let sd = d * (1.0 - d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0)));
            let cd = 1.0 - d2 / 2.0 * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0 * (1.0 - d2 / 56.0)));
            (
                self.sin0 * cd + self.cos0 * sd,
                self.cos0 * cd - self.sin0 * sd,
            )
        } else {
            lat.sin_cos()
        }
    }

    /// At latitude sin L and height h: (R_N + h, R_E + h, gamma(L, h)) (crate::earth).
    #[inline(always)]
    pub fn radii_gravity(&self, sin: f64, h: f64) -> (f64, f64, f64) {
        let s2 = sin * sin;
        let (rn, re) = radii_sin2(s2);
        (rn + h, re + h, gravity_sin2(s2, h))
    }

    /// NED metres from the start place of (latitude, longitude, height).
    pub fn ned_of(&self, lat: f64, lon: f64, h: f64) -> [f64; 3] {
        let p = &self.earth.place;
        [
            (lat - p.lat_rad) * self.m_per_rad_lat,
            (lon - p.lon_rad) * self.m_per_rad_lon,
            -(h - p.height_m),
        ]
    }

    /// (latitude, longitude, height) of NED metres from the start place.
    pub fn geodetic_of(&self, ned: [f64; 3]) -> [f64; 3] {
        let p = &self.earth.place;
        [
            p.lat_rad + ned[0] / self.m_per_rad_lat,
            p.lon_rad + ned[1] / self.m_per_rad_lon,
            p.height_m - ned[2],
        ]
    }
}
