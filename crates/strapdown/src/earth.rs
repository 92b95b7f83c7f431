//! The round, rotating Earth: the WGS-84 ellipsoid, its normal gravity, Earth rate and the
//! transport rate of the local-level north-east-down frame, and the closed-form horizontal error
//! of the Schuler loop (the round-Earth counterparts of Woodman's flat growth laws).
//!
//! Sources (each formula cites its own):
//! - NIMA TR8350.2, *Department of Defense World Geodetic System 1984*, 3rd ed. (2000): the
//!   defining constants (Table 3.1), the derived ones (Table 3.3), Somigliana's normal gravity
//!   (eq 4-1) and its height series (eq 4-3).
//! - P. D. Groves, *Principles of GNSS, Inertial, and Multisensor Integrated Navigation Systems*,
//!   2nd ed. (2013): the radii of curvature (eqs 2.105, 2.106), Earth rate and the transport rate
//!   in NED (eqs 2.123, 5.44).
//! - D. H. Titterton, J. L. Weston, *Strapdown Inertial Navigation Technology*, 2nd ed. (2004),
//!   ch. 12: the single-channel Schuler error (constant tilt, gyro bias, accelerometer bias).

use crate::NavVector;

/// WGS-84 semi-major axis a, m (NIMA TR8350.2 Table 3.1).
pub const WGS84_A_M: f64 = 6_378_137.0;
/// WGS-84 flattening f (Table 3.1).
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;
/// WGS-84 first eccentricity squared e^2 = f (2 - f) (Table 3.3: 6.694 379 990 14e-3).
pub const WGS84_E2: f64 = WGS84_F * (2.0 - WGS84_F);
/// Earth's rotation rate omega_ie, rad/s (Table 3.1).
pub const EARTH_RATE_RAD_S: f64 = 7.292_115e-5;
/// Earth's gravitational constant GM, m^3/s^2 (Table 3.1, with the atmosphere).
pub const WGS84_GM_M3_S2: f64 = 3.986_004_418e14;
/// Normal gravity at the equator gamma_e, m/s^2 (Table 3.3).
pub const GAMMA_EQUATOR_MPS2: f64 = 9.780_325_335_9;
/// Somigliana's constant k = (b gamma_p - a gamma_e) / (a gamma_e) (Table 3.3).
pub const SOMIGLIANA_K: f64 = 0.001_931_852_652_41;

/// The radii of curvature at geodetic latitude `lat_rad`: meridian R_N = a (1 - e^2) /
/// (1 - e^2 sin^2 L)^(3/2) and transverse (prime vertical) R_E = a / (1 - e^2 sin^2 L)^(1/2), m
/// (Groves eqs 2.105, 2.106).
pub fn radii_m(lat_rad: f64) -> (f64, f64) {
    radii_sin2(lat_rad.sin().powi(2))
}

/// [`radii_m`] of sin^2 L.
#[inline(always)]
pub(crate) fn radii_sin2(s2: f64) -> (f64, f64) {
    let d = 1.0 - WGS84_E2 * s2;
    let sq = d.sqrt();
    (WGS84_A_M * (1.0 - WGS84_E2) / (d * sq), WGS84_A_M / sq)
}

/// Normal gravity (gravitation plus the centrifugal term: what a static accelerometer reads,
/// negated) at geodetic latitude `lat_rad` and height `height_m` above the ellipsoid, m/s^2:
/// Somigliana's closed form on the ellipsoid, gamma = gamma_e (1 + k sin^2 L) / sqrt(1 - e^2
/// sin^2 L) (NIMA TR8350.2 eq 4-1), times the free-air series 1 - 2/a (1 + f + m - 2 f sin^2 L) h
/// + 3 h^2 / a^2, m = omega^2 a^2 b / GM (eq 4-3, for heights of a few km).
pub fn normal_gravity_mps2(lat_rad: f64, height_m: f64) -> f64 {
    gravity_sin2(lat_rad.sin().powi(2), height_m)
}

/// The free-air series' m = omega^2 a^2 b / GM (NIMA TR8350.2 eq 4-3; Table 3.3: 0.003 449 786 506 84).
const FREE_AIR_M: f64 =
    EARTH_RATE_RAD_S * EARTH_RATE_RAD_S * WGS84_A_M * WGS84_A_M * (WGS84_A_M * (1.0 - WGS84_F))
        / WGS84_GM_M3_S2;

/// [`normal_gravity_mps2`] of sin^2 L and the height.
#[inline(always)]
pub(crate) fn gravity_sin2(s2: f64, h: f64) -> f64 {
    let gamma0 = GAMMA_EQUATOR_MPS2 * (1.0 + SOMIGLIANA_K * s2) / (1.0 - WGS84_E2 * s2).sqrt();
    gamma0
        * (1.0 - 2.0 / WGS84_A_M * (1.0 + WGS84_F + FREE_AIR_M - 2.0 * WGS84_F * s2) * h
            + 3.0 * h * h / (WGS84_A_M * WGS84_A_M))
}

/// Earth rate resolved in NED at latitude `lat_rad`: omega_ie (cos L, 0, -sin L), rad/s (Groves
/// eq 2.123).
pub fn earth_rate_ned(lat_rad: f64) -> NavVector {
    NavVector::new(
        EARTH_RATE_RAD_S * lat_rad.cos(),
        0.0,
        -EARTH_RATE_RAD_S * lat_rad.sin(),
    )
}

/// The transport rate omega_en^n of the NED frame moving at `velocity` (m/s, NED) at latitude
/// `lat_rad` and height `height_m`: (v_E / (R_E + h), -v_N / (R_N + h), -v_E tan L / (R_E + h)),
/// rad/s (Groves eq 5.44).
pub fn transport_rate_ned(lat_rad: f64, height_m: f64, velocity: &NavVector) -> NavVector {
    let (rn, re) = radii_m(lat_rad);
    let (vn, ve) = (velocity.0.x, velocity.0.y);
    NavVector::new(
        ve / (re + height_m),
        -vn / (rn + height_m),
        -ve * lat_rad.tan() / (re + height_m),
    )
}

/// A place on the WGS-84 ellipsoid and what the local-level frame there needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Place {
    /// Geodetic latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad (enters no error law; kept for the outputs).
    pub lon_rad: f64,
    /// Height above the ellipsoid, m.
    pub height_m: f64,
}

impl Place {
    /// A place from degrees and metres.
    pub fn from_deg(lat_deg: f64, lon_deg: f64, height_m: f64) -> Place {
        Place {
            lat_rad: lat_deg.to_radians(),
            lon_rad: lon_deg.to_radians(),
            height_m,
        }
    }

    /// Local normal gravity, m/s^2 ([`normal_gravity_mps2`]).
    pub fn gravity_mps2(&self) -> f64 {
        normal_gravity_mps2(self.lat_rad, self.height_m)
    }

    /// The Schuler loop's radius: the Gaussian mean radius sqrt(R_N R_E) plus the height, m
    /// (the two horizontal channels' radii differ by 0.7 % at most; the closed forms below take one).
    pub fn schuler_radius_m(&self) -> f64 {
        let (rn, re) = radii_m(self.lat_rad);
        (rn * re).sqrt() + self.height_m
    }

    /// The Schuler frequency omega_s = sqrt(g / R), rad/s (period 2 pi / omega_s = 84.4 min).
    pub fn schuler_rad_s(&self) -> f64 {
        (self.gravity_mps2() / self.schuler_radius_m()).sqrt()
    }
}

/// Horizontal position error of one channel after `t_s` seconds from a constant initial tilt
/// `tilt_rad`, Earth-rate coupling neglected: R d (1 - cos w_s t) (Titterton & Weston ch. 12;
/// the flat Earth's g d t^2 / 2 is its limit for w_s t << 1).
pub fn schuler_tilt_m(place: &Place, tilt_rad: f64, t_s: f64) -> f64 {
    place.schuler_radius_m() * tilt_rad * (1.0 - (place.schuler_rad_s() * t_s).cos())
}

/// Horizontal position error of one channel after `t_s` seconds from a constant gyro bias
/// `bias_rad_s` about the horizontal axis normal to it, Earth-rate coupling neglected:
/// R eps (t - sin(w_s t) / w_s) (Titterton & Weston ch. 12; flat: g eps t^3 / 6).
pub fn schuler_gyro_bias_m(place: &Place, bias_rad_s: f64, t_s: f64) -> f64 {
    let ws = place.schuler_rad_s();
    place.schuler_radius_m() * bias_rad_s * (t_s - (ws * t_s).sin() / ws)
}

/// Horizontal position error of one channel after `t_s` seconds from a constant accelerometer
/// bias `bias_mps2`, Earth-rate coupling neglected: (b / w_s^2) (1 - cos w_s t) (Titterton &
/// Weston ch. 12; flat: b t^2 / 2).
pub fn schuler_accel_bias_m(place: &Place, bias_mps2: f64, t_s: f64) -> f64 {
    let ws = place.schuler_rad_s();
    bias_mps2 / (ws * ws) * (1.0 - (ws * t_s).cos())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// NIMA TR8350.2 Table 3.3 and the radii's closed values at the equator and the pole.
    #[test]
    fn wgs84_values() {
        assert!((WGS84_E2 - 6.694_379_990_14e-3).abs() < 1e-14);
        assert!(
            (FREE_AIR_M - 0.003_449_786_506_84).abs() < 1e-14,
            "{FREE_AIR_M}"
        );
        let (rn, re) = radii_m(0.0);
        assert!((re - WGS84_A_M).abs() < 1e-6);
        assert!((rn - WGS84_A_M * (1.0 - WGS84_E2)).abs() < 1e-6);
        // At the pole both radii are a / sqrt(1 - e^2) = a^2 / b = 6 399 593.6259 m (Table 3.3).
        let (rn, re) = radii_m(std::f64::consts::FRAC_PI_2);
        assert!((rn - 6_399_593.625_9).abs() < 1e-3, "{rn}");
        assert!((re - 6_399_593.625_9).abs() < 1e-3, "{re}");
        // Normal gravity at the equator and the pole (Table 3.3: 9.780 325 3359, 9.832 184 9378).
        assert!((normal_gravity_mps2(0.0, 0.0) - 9.780_325_335_9).abs() < 1e-10);
        let gp = normal_gravity_mps2(std::f64::consts::FRAC_PI_2, 0.0);
        assert!((gp - 9.832_184_937_8).abs() < 1e-9, "{gp}");
        // The free-air gradient near the surface: -3.086e-6 s^-2 at mid latitudes (the classic
        // 0.3086 mGal/m), within 0.3 %.
        let lat = 45f64.to_radians();
        let grad = (normal_gravity_mps2(lat, 100.0) - normal_gravity_mps2(lat, 0.0)) / 100.0;
        assert!((grad / -3.086e-6 - 1.0).abs() < 3e-3, "{grad}");
    }

    #[test]
    fn schuler_period_and_flat_limits() {
        let p = Place::from_deg(45.0, 0.0, 0.0);
        let period_min = std::f64::consts::TAU / p.schuler_rad_s() / 60.0;
        assert!((period_min - 84.4).abs() < 0.1, "{period_min}");
        // For w_s t << 1 the round-Earth errors tend to the flat laws (relative error ~ (w_s t)^2 / 12).
        let (g, t) = (p.gravity_mps2(), 10.0);
        let tilt = schuler_tilt_m(&p, 1e-4, t) / (g * 1e-4 * t * t / 2.0);
        let bias = schuler_gyro_bias_m(&p, 1e-6, t) / (g * 1e-6 * t.powi(3) / 6.0);
        let acc = schuler_accel_bias_m(&p, 1e-3, t) / (1e-3 * t * t / 2.0);
        for r in [tilt, bias, acc] {
            assert!((r - 1.0).abs() < 1e-4, "{r}");
        }
        // Theory's check (gnss-ins-sim with its height held, 45 deg N, 0.1 deg/h): 13.54 km at 1 h
        // and 15.66 km at one Schuler period.
        let eps = 0.1f64.to_radians() / 3600.0;
        let at_1h = schuler_gyro_bias_m(&p, eps, 3600.0);
        assert!((at_1h / 13_540.0 - 1.0).abs() < 3e-3, "{at_1h}");
    }
}
