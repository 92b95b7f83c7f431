//! Where a navigation runs ([`EarthModel`]: Woodman's flat Earth or the round, rotating WGS-84
//! one) and a trajectory's truth and ideal IMU there ([`EarthTrajectory`]).
//!
//! A trajectory ([`crate::trajectory`]) describes a motion relative to the local-level
//! north-east-down frame: its attitude is the body's relative to that frame, its velocity is
//! north, east, down. On the flat Earth that frame is inertial and the trajectory's ideal IMU is
//! exact as it stands. On the round, rotating Earth the same motion is read as (Groves, *Principles
//! of GNSS, Inertial, and Multisensor Integrated Navigation Systems*, 2nd ed., §5.4):
//! - attitude C(t) and velocity v(t) the trajectory's, relative to the local NED frame at the
//!   current place;
//! - place: latitude, longitude and height integrated from the velocity, dL/dt = v_N / (R_N + h),
//!   dlambda/dt = v_E / ((R_E + h) cos L), dh/dt = -v_D (eq 5.56), reported as NED metres from the
//!   start place as the round-Earth mechanisation reports its own (`round_earth`);
//! - gyro: the trajectory's (the body's rate relative to the NED frame) plus C^T (omega_ie +
//!   omega_en), the frame's own rotation (Earth rate and transport rate, eq 5.45 read backwards);
//! - specific force: the trajectory's, built with the start place's gravity gamma_0, plus
//!   C^T ((2 omega_ie + omega_en) x v + (0, 0, gamma_0 - gamma(L, h))) (eq 5.53 read backwards).
//!
//! The added terms are averaged over each sample interval by 3-point Gauss-Legendre quadrature
//! (exact for polynomials of degree 5): they are Earth rate, transport rate and Coriolis, at most
//! about 1e-4 rad/s and 1e-2 m/s^2, smooth within a profile segment, so the quadrature's error is
//! some 1e-12 of them over a 0.01 s sample even at 100 deg/s of body rate; for a static IMU the
//! readings are exact ([`crate::RoundEarth::static_imu`]). The place is integrated by 4-point
//! Gauss-Legendre panels of at most 10 s split at the profile's segment boundaries (the velocity is
//! piecewise linear, the integrand smooth between them), with the latitude inside the radii taken
//! from the trajectory's north position (its difference from the integrated one, some 1e-7 of the
//! distance, changes the radii by 1e-9 of themselves).

use crate::earth::{radii_m, transport_rate_ned};
use crate::round_earth::Origin;
use crate::trajectory::{AnyTrajectory, Trajectory};
use crate::{Attitude, BodyVector, NavState, NavVector, RoundEarth, Scheme, StrapdownLanes};
use nalgebra::Vector3;

/// The Earth a navigation runs on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EarthModel {
    /// Woodman's flat, non-rotating Earth with constant gravity `gravity_mps2` (TR-696 §3).
    Flat { gravity_mps2: f64 },
    /// The round, rotating WGS-84 Earth ([`crate::round_earth`]).
    Round(RoundEarth),
}

impl EarthModel {
    /// The scenario name of the model: `flat` or `wgs84`.
    pub fn name(&self) -> &'static str {
        match self {
            EarthModel::Flat { .. } => "flat",
            EarthModel::Round(_) => "wgs84",
        }
    }

    /// Gravity at the start place, m/s^2 (a static IMU there reads its negative on its down
    /// accelerometer).
    pub fn gravity_mps2(&self) -> f64 {
        match self {
            EarthModel::Flat { gravity_mps2 } => *gravity_mps2,
            EarthModel::Round(e) => e.place.gravity_mps2(),
        }
    }

    /// The round Earth, if it is one.
    pub fn round(&self) -> Option<&RoundEarth> {
        match self {
            EarthModel::Flat { .. } => None,
            EarthModel::Round(e) => Some(e),
        }
    }

    /// What an ideal IMU at rest at the start place reads with body attitude `attitude`:
    /// (gyro rad/s, specific force m/s^2), body frame.
    pub fn static_imu(&self, attitude: &Attitude) -> (BodyVector, BodyVector) {
        match self {
            EarthModel::Flat { gravity_mps2 } => (
                BodyVector::zeros(),
                attitude.to_body(&NavVector::new(0.0, 0.0, -gravity_mps2)),
            ),
            EarthModel::Round(e) => e.static_imu(attitude),
        }
    }

    /// `L` integrators on this Earth starting at `initial` (positions NED metres from the
    /// start place).
    pub fn lanes<const L: usize>(
        &self,
        scheme: Scheme,
        initial: &[NavState; L],
    ) -> StrapdownLanes<L> {
        match self {
            EarthModel::Flat { gravity_mps2 } => {
                StrapdownLanes::new(scheme, initial, *gravity_mps2)
            }
            EarthModel::Round(e) => StrapdownLanes::on_earth(scheme, initial, *e),
        }
    }
}

/// A trajectory on an Earth: on the flat one the trajectory itself; on the round one its motion
/// read relative to the local NED frame (module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct EarthTrajectory {
    motion: AnyTrajectory,
    earth: EarthModel,
    /// The round Earth's start-place constants, computed once (not per sample).
    origin: Option<Origin>,
}

/// 3-point Gauss-Legendre nodes on [0, 1] and weights (sum 1).
const GL3: [(f64, f64); 3] = [
    (0.112_701_665_379_258_3, 5.0 / 18.0),
    (0.5, 8.0 / 18.0),
    (0.887_298_334_620_741_7, 5.0 / 18.0),
];

/// 4-point Gauss-Legendre nodes on [0, 1] and weights (Abramowitz & Stegun Table 25.4).
const GL4: [(f64, f64); 4] = [
    (0.069_431_844_202_973_71, 0.173_927_422_568_726_9),
    (0.330_009_478_207_571_9, 0.326_072_577_431_273_1),
    (0.669_990_521_792_428_1, 0.326_072_577_431_273_1),
    (0.930_568_155_797_026_3, 0.173_927_422_568_726_9),
];

/// The longest place-integration panel, s.
const PANEL_S: f64 = 10.0;

impl EarthTrajectory {
    /// `motion` on `earth`; its ideal accelerometer outputs must use the earth's gravity at the
    /// start place (`TrajectorySpec::build_with_gravity(earth.gravity_mps2())`).
    pub fn new(motion: AnyTrajectory, earth: EarthModel) -> EarthTrajectory {
        let origin = earth.round().map(|e| Origin::new(*e));
        EarthTrajectory {
            motion,
            earth,
            origin,
        }
    }

    pub fn motion(&self) -> &AnyTrajectory {
        &self.motion
    }

    pub fn earth(&self) -> &EarthModel {
        &self.earth
    }

    /// Whether the motion stays at the start place (no velocity ever): then the place terms vanish.
    fn stays(&self) -> bool {
        !matches!(self.motion, AnyTrajectory::Profile(_))
    }

    /// Latitude, longitude and height at `t_s` (module documentation), rad, rad, m.
    fn geodetic(&self, origin: &Origin, t_s: f64) -> [f64; 3] {
        let start = origin.geodetic_of(self.motion.truth(0.0).position.0.into());
        if self.stays() || t_s == 0.0 {
            return start;
        }
        let mut breaks: Vec<f64> = match &self.motion {
            AnyTrajectory::Profile(p) => p
                .segment_starts()
                .filter(|&b| b > t_s.min(0.0) && b < t_s.max(0.0))
                .collect(),
            _ => Vec::new(),
        };
        breaks.insert(0, 0.0);
        breaks.push(t_s);
        let (mut lat, mut lon) = (start[0], start[1]);
        for w in breaks.windows(2) {
            let span = w[1] - w[0];
            let panels = (span.abs() / PANEL_S).ceil().max(1.0) as usize;
            let h = span / panels as f64;
            for i in 0..panels {
                let a = w[0] + i as f64 * h;
                for (x, wt) in GL4 {
                    let s = self.motion.truth(a + x * h);
                    let geo = origin.geodetic_of(s.position.0.into());
                    let (rn, re) = radii_m(geo[0]);
                    let v = s.velocity.0;
                    lat += wt * h * v.x / (rn + geo[2]);
                    lon += wt * h * v.y / ((re + geo[2]) * geo[0].cos());
                }
            }
        }
        let height =
            start[2] - (self.motion.truth(t_s).position.0.z - self.motion.truth(0.0).position.0.z);
        [lat, lon, height]
    }

    /// The frame-rotation and Coriolis terms at `t_s` in body axes: (gyro, specific force).
    fn earth_terms(
        &self,
        e: &RoundEarth,
        origin: &Origin,
        t_s: f64,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let s = self.motion.truth(t_s);
        let geo = origin.geodetic_of(s.position.0.into());
        let (sl, cl) = geo[0].sin_cos();
        let w = e.rate_rad_s();
        let omega_ie = Vector3::new(w * cl, 0.0, -w * sl);
        let omega_en = transport_rate_ned(geo[0], geo[2], &s.velocity).0;
        let gamma = crate::earth::normal_gravity_mps2(geo[0], geo[2]);
        let f = (2.0 * omega_ie + omega_en).cross(&s.velocity.0)
            + Vector3::new(0.0, 0.0, e.place.gravity_mps2() - gamma);
        let c = s.attitude.matrix().transpose();
        (c * (omega_ie + omega_en), c * f)
    }
}

impl Trajectory for EarthTrajectory {
    fn truth(&self, t_s: f64) -> NavState {
        let state = self.motion.truth(t_s);
        match &self.origin {
            Some(origin) if !self.stays() => {
                let geo = self.geodetic(origin, t_s);
                NavState {
                    position: NavVector(origin.ned_of(geo[0], geo[1], geo[2]).into()),
                    ..state
                }
            }
            _ => state,
        }
    }

    #[inline]
    fn imu_average(&self, t0_s: f64, t1_s: f64) -> (BodyVector, BodyVector) {
        let (g, f) = self.motion.imu_average(t0_s, t1_s);
        let EarthModel::Round(e) = &self.earth else {
            return (g, f);
        };
        if let AnyTrajectory::Static(s) = &self.motion {
            let (w, _) = e.static_imu(&s.attitude);
            return (BodyVector(g.0 + w.0), f);
        }
        let Some(origin) = &self.origin else {
            return (g, f);
        };
        let h = t1_s - t0_s;
        let (mut dg, mut df) = (Vector3::zeros(), Vector3::zeros());
        for (x, wt) in GL3 {
            let (a, b) = self.earth_terms(e, origin, t0_s + x * h);
            dg += wt * a;
            df += wt * b;
        }
        (BodyVector(g.0 + dg), BodyVector(f.0 + df))
    }

    fn is_static(&self) -> bool {
        self.motion.is_static()
    }

    fn gravity_mps2(&self) -> f64 {
        self.earth.gravity_mps2()
    }
}
