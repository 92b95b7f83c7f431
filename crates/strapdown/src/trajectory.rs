//! Trajectories: closed-form truth (attitude, velocity, position) and the ideal IMU outputs that produce
//! it. Nothing here calls the mechanisation, so the truth is independent of the scheme under test.
//!
//! Ideal IMU outputs are those of an integrating IMU: the body-frame angle and velocity increments over
//! `[t_k, t_{k+1}]` divided by `dt` (the convention [`crate::Strapdown::step`] consumes). Each
//! trajectory implements [`Trajectory::imu_average`] for any interval; `ideal_imu(k, dt)` is that over
//! `[k dt, (k+1) dt]`, with time from the integer index.

use crate::frames::{rodrigues_coefficients, so3_exp, Attitude, BodyVector, NavVector};
use crate::mechanisation::NavState;
use crate::STANDARD_GRAVITY_MPS2;
use nalgebra::{Matrix3, Vector3};

/// A motion with closed-form truth and ideal IMU outputs.
pub trait Trajectory: Sync {
    /// The true state at `t_s` (s).
    fn truth(&self, t_s: f64) -> NavState;

    /// Ideal IMU outputs averaged over `[t0_s, t1_s]`: (gyro rad/s, specific force m/s^2), body frame.
    /// Defined for `t0_s < 0` too (the motion before the start), e.g. to prime a coning correction.
    fn imu_average(&self, t0_s: f64, t1_s: f64) -> (BodyVector, BodyVector);

    /// Ideal IMU outputs of sample `k` at rate `1/dt`: (gyro rad/s, specific force m/s^2), body frame,
    /// in the convention the mechanisation consumes for step `k -> k+1` (averages over `[k dt, (k+1) dt]`).
    #[inline]
    fn ideal_imu(&self, k: u64, dt_s: f64) -> (BodyVector, BodyVector) {
        self.imu_average(k as f64 * dt_s, (k + 1) as f64 * dt_s)
    }

    /// True when the IMU never moves (the growth laws for a static level IMU apply if also level).
    fn is_static(&self) -> bool {
        false
    }

    /// Gravity magnitude the ideal accelerometer outputs are computed with, m/s^2; give the same value
    /// to [`crate::Strapdown::new`] (as [`crate::Strapdown::for_trajectory`] does).
    fn gravity_mps2(&self) -> f64 {
        STANDARD_GRAVITY_MPS2
    }
}

/// Specific force in the navigation frame for nav-frame acceleration `a_nav`: `f = a - gamma` with
/// gravity `gamma = (0, 0, +g)` in NED (Woodman eq 43 read backwards: `dv/dt = C f + gamma`).
#[inline]
fn specific_force_nav(a_nav: &Vector3<f64>, gravity_mps2: f64) -> Vector3<f64> {
    Vector3::new(a_nav.x, a_nav.y, a_nav.z - gravity_mps2)
}

/// `(1/h) * integral_0^h exp(s [w x]) ds * v`. Integrating Woodman eq 41 term by term,
/// `exp(s X) = I + (sin ws/w) X + ((1 - cos ws)/w^2) X^2`, gives
/// `h I + ((1 - cos wh)/w^2) X + ((wh - sin wh)/w^3) X^2`.
fn mean_rotation_times(w: &Vector3<f64>, h: f64, v: &Vector3<f64>) -> Vector3<f64> {
    let x2 = w.norm_squared() * h * h;
    // (1 - cos x)/x^2 from the shared Rodrigues coefficients; (x - sin x)/x^3 by its Taylor series
    // below x = 0.1 (remainder < 0.1^10/13! < 2e-20), directly above.
    let (_, one_minus_cos_over_x2) = rodrigues_coefficients(x2);
    let x_minus_sin_over_x3 = if x2 < 1e-2 {
        (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0 * (1.0 - x2 / 110.0)))) / 6.0
    } else {
        let x = x2.sqrt();
        (x - x.sin()) / (x2 * x)
    };
    let wxv = w.cross(v);
    v + (h * one_minus_cos_over_x2) * wxv + (h * h * x_minus_sin_over_x3) * w.cross(&wxv)
}

/// At rest at the origin with a fixed attitude (level or tilted).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Static {
    /// Body-to-navigation attitude.
    pub attitude: Attitude,
    /// Gravity magnitude, m/s^2.
    pub gravity_mps2: f64,
}

impl Static {
    /// At rest with `attitude`, standard gravity.
    pub fn new(attitude: Attitude) -> Static {
        Static {
            attitude,
            gravity_mps2: STANDARD_GRAVITY_MPS2,
        }
    }
}

impl Default for Static {
    /// Level, heading north, standard gravity.
    fn default() -> Static {
        Static::new(Attitude::identity())
    }
}

impl Trajectory for Static {
    fn truth(&self, _t_s: f64) -> NavState {
        NavState {
            attitude: self.attitude,
            ..NavState::default()
        }
    }
    #[inline]
    fn imu_average(&self, _t0_s: f64, _t1_s: f64) -> (BodyVector, BodyVector) {
        // Level: C^T (0, 0, -g) = (0, 0, -g) exactly, so gravity compensation cancels bit-exactly.
        let f = self.attitude.to_body(&NavVector(specific_force_nav(
            &Vector3::zeros(),
            self.gravity_mps2,
        )));
        (BodyVector::zeros(), f)
    }
    fn is_static(&self) -> bool {
        true
    }
    fn gravity_mps2(&self) -> f64 {
        self.gravity_mps2
    }
}

/// At rest at the origin, rotating at a constant body rate: `C(t) = C_0 exp(t [w x])` (Woodman eq 34
/// with constant `Omega`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConstantRate {
    /// Attitude at `t = 0`.
    pub initial: Attitude,
    /// Body angular rate, rad/s.
    pub rate_body_rad_s: BodyVector,
    /// Gravity magnitude, m/s^2.
    pub gravity_mps2: f64,
}

impl ConstantRate {
    /// Constant body rate from `initial`, standard gravity.
    pub fn new(initial: Attitude, rate_body_rad_s: BodyVector) -> ConstantRate {
        ConstantRate {
            initial,
            rate_body_rad_s,
            gravity_mps2: STANDARD_GRAVITY_MPS2,
        }
    }
    fn attitude_at(&self, t_s: f64) -> Attitude {
        self.initial
            .then_body_rotation(&so3_exp(&(self.rate_body_rad_s.0 * t_s)))
    }
}

impl Trajectory for ConstantRate {
    fn truth(&self, t_s: f64) -> NavState {
        NavState {
            attitude: self.attitude_at(t_s),
            ..NavState::default()
        }
    }
    fn imu_average(&self, t0_s: f64, t1_s: f64) -> (BodyVector, BodyVector) {
        let f_body_t0 = self
            .attitude_at(t0_s)
            .to_body(&NavVector(specific_force_nav(
                &Vector3::zeros(),
                self.gravity_mps2,
            )));
        // C(t)^T f = exp(-(t - t0) X) C(t0)^T f, averaged over the interval.
        let w = -self.rate_body_rad_s.0;
        (
            self.rate_body_rad_s,
            BodyVector(mean_rotation_times(&w, t1_s - t0_s, &f_body_t0.0)),
        )
    }
    fn gravity_mps2(&self) -> f64 {
        self.gravity_mps2
    }
}

/// Classical coning at rest: `C(t) = A(t) B A(t)^T` with `A(t) = Rz(W t)`, `B = Rx(theta)`, i.e. a rotation
/// by the half-angle `theta` about an axis sweeping the horizontal plane at `W` rad/s.
///
/// Body rate from Woodman eq 33 (`C^T dC/dt = [w x]`) applied to the product: with `dA/dt = A [W e_z x]`
/// and `R^T [v x] R = [(R^T v) x]`, `w(t) = W A(t) (B^T e_z - e_z) = W (-sin th sin Wt, sin th cos Wt,
/// cos th - 1)`. Specific force `C^T (0,0,-g) = -g A(t) B^T e_z` since `A^T` fixes `e_z`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coning {
    /// Cone half-angle `theta`, rad.
    pub half_angle_rad: f64,
    /// Coning angular frequency `W`, rad/s.
    pub frequency_rad_s: f64,
    /// Gravity magnitude, m/s^2.
    pub gravity_mps2: f64,
}

impl Coning {
    /// Coning with half-angle `half_angle_rad` at `frequency_rad_s`, standard gravity.
    pub fn new(half_angle_rad: f64, frequency_rad_s: f64) -> Coning {
        Coning {
            half_angle_rad,
            frequency_rad_s,
            gravity_mps2: STANDARD_GRAVITY_MPS2,
        }
    }
    /// `A(t) = Rz(W t)`.
    fn sweep(&self, t_s: f64) -> Matrix3<f64> {
        let (s, c) = (self.frequency_rad_s * t_s).sin_cos();
        Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
    }
    /// `B^T e_z = (0, sin th, cos th)` and `B^T e_z - e_z = (0, sin th, -2 sin^2(th/2))`.
    fn tilted_axes(&self) -> (Vector3<f64>, Vector3<f64>) {
        let th = self.half_angle_rad;
        let (s, c) = th.sin_cos();
        let half = (0.5 * th).sin();
        (
            Vector3::new(0.0, s, c),
            Vector3::new(0.0, s, -2.0 * half * half),
        )
    }
    /// `(1/h) * integral_{t0}^{t1} A(t) u dt` in closed form; sums of sines written as products so a short
    /// interval does not cancel digits (`sin a - sin b = 2 cos((a+b)/2) sin((a-b)/2)`).
    fn mean_sweep_times(&self, t0_s: f64, t1_s: f64, u: &Vector3<f64>) -> Vector3<f64> {
        let w = self.frequency_rad_s;
        let h = t1_s - t0_s;
        let (s_mid, c_mid) = (0.5 * w * (t0_s + t1_s)).sin_cos();
        let half = 0.5 * w * h;
        // sin(half)/half, by series when small so that h -> 0 stays exact to rounding.
        let sinc = if half.abs() < 1e-4 {
            1.0 - half * half / 6.0
        } else {
            half.sin() / half
        };
        let (ic, is) = (c_mid * sinc, s_mid * sinc);
        Vector3::new(ic * u.x - is * u.y, is * u.x + ic * u.y, u.z)
    }
}

impl Trajectory for Coning {
    fn truth(&self, t_s: f64) -> NavState {
        let a = self.sweep(t_s);
        let b = *Attitude::from_euler_rad(self.half_angle_rad, 0.0, 0.0).matrix();
        NavState {
            attitude: Attitude(a * b * a.transpose()),
            ..NavState::default()
        }
    }
    fn imu_average(&self, t0_s: f64, t1_s: f64) -> (BodyVector, BodyVector) {
        let (bt_ez, rate_axis) = self.tilted_axes();
        let gyro = self.mean_sweep_times(t0_s, t1_s, &rate_axis) * self.frequency_rad_s;
        let accel = self.mean_sweep_times(t0_s, t1_s, &bt_ez) * -self.gravity_mps2;
        (BodyVector(gyro), BodyVector(accel))
    }
    fn gravity_mps2(&self) -> f64 {
        self.gravity_mps2
    }
}

/// One piece of a [`Profile`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Segment {
    /// Keep attitude and velocity (constant-velocity straight line, or rest).
    Hold { duration_s: f64 },
    /// Rotate about a body-fixed unit axis at a constant rate, velocity unchanged.
    Rotate {
        duration_s: f64,
        axis_body: BodyVector,
        rate_rad_s: f64,
    },
    /// Constant acceleration given in body axes at a fixed attitude.
    Accelerate {
        duration_s: f64,
        accel_body_mps2: BodyVector,
    },
}

impl Segment {
    fn duration_s(&self) -> f64 {
        match *self {
            Segment::Hold { duration_s }
            | Segment::Rotate { duration_s, .. }
            | Segment::Accelerate { duration_s, .. } => duration_s,
        }
    }
    fn rate_body(&self) -> Vector3<f64> {
        match *self {
            Segment::Rotate {
                axis_body,
                rate_rad_s,
                ..
            } => axis_body.0 * rate_rad_s,
            _ => Vector3::zeros(),
        }
    }
}

/// A piecewise motion (hold, rotate, accelerate) whose truth is evaluated in closed form within each
/// segment from the segment's start state. Before `t = 0` and after the last segment it holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Profile {
    segments: Vec<Segment>,
    /// Start time and true state at the start of each segment, plus one entry for the end.
    starts: Vec<(f64, NavState)>,
    gravity_mps2: f64,
}

impl Profile {
    /// A profile from its initial state and segments. Durations must be positive and rotation axes unit
    /// (validated in [`crate::spec::TrajectorySpec::build`]; here they are taken as given).
    pub fn new(initial: NavState, segments: Vec<Segment>) -> Profile {
        let mut starts = Vec::with_capacity(segments.len() + 1);
        let mut t0 = 0.0;
        let mut state = initial;
        starts.push((t0, state));
        for seg in &segments {
            state = Self::evolve(seg, &state, seg.duration_s());
            t0 += seg.duration_s();
            starts.push((t0, state));
        }
        Profile {
            segments,
            starts,
            gravity_mps2: STANDARD_GRAVITY_MPS2,
        }
    }

    /// The same profile with another gravity magnitude, m/s^2.
    pub fn with_gravity(self, gravity_mps2: f64) -> Profile {
        Profile {
            gravity_mps2,
            ..self
        }
    }

    /// The segments.
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// The start time of every segment and the end of the last, s.
    pub fn segment_starts(&self) -> impl Iterator<Item = f64> + '_ {
        self.starts.iter().map(|s| s.0)
    }

    /// Total duration of the segments, s.
    pub fn duration_s(&self) -> f64 {
        self.starts.last().map_or(0.0, |s| s.0)
    }

    /// Closed-form state `tau_s` into `seg` from its start state.
    fn evolve(seg: &Segment, start: &NavState, tau_s: f64) -> NavState {
        let v0 = start.velocity.0;
        match *seg {
            Segment::Hold { .. } => NavState {
                position: NavVector(start.position.0 + v0 * tau_s),
                ..*start
            },
            Segment::Rotate { .. } => NavState {
                attitude: start
                    .attitude
                    .then_body_rotation(&so3_exp(&(seg.rate_body() * tau_s))),
                velocity: start.velocity,
                position: NavVector(start.position.0 + v0 * tau_s),
            },
            Segment::Accelerate {
                accel_body_mps2, ..
            } => {
                let a_nav = start.attitude.to_nav(&accel_body_mps2).0;
                NavState {
                    attitude: start.attitude,
                    velocity: NavVector(v0 + a_nav * tau_s),
                    position: NavVector(
                        start.position.0 + v0 * tau_s + a_nav * (0.5 * tau_s * tau_s),
                    ),
                }
            }
        }
    }

    /// Index of the segment containing `t_s`, or `None` outside `[0, end)`.
    fn segment_at(&self, t_s: f64) -> Option<usize> {
        if t_s < 0.0 || t_s >= self.duration_s() {
            return None;
        }
        Some(self.starts.partition_point(|s| s.0 <= t_s) - 1)
    }
}

const HOLD_FOREVER: Segment = Segment::Hold {
    duration_s: f64::INFINITY,
};

impl Trajectory for Profile {
    fn truth(&self, t_s: f64) -> NavState {
        match self.segment_at(t_s) {
            Some(i) => Self::evolve(&self.segments[i], &self.starts[i].1, t_s - self.starts[i].0),
            None if t_s < 0.0 => Self::evolve(&HOLD_FOREVER, &self.starts[0].1, t_s),
            None => {
                let (t_end, end) = self.starts[self.starts.len() - 1];
                Self::evolve(&HOLD_FOREVER, &end, t_s - t_end)
            }
        }
    }

    fn imu_average(&self, t0_s: f64, t1_s: f64) -> (BodyVector, BodyVector) {
        let h = t1_s - t0_s;
        let mut gyro = Vector3::zeros();
        let mut force = Vector3::zeros();
        let mut a = t0_s;
        while a < t1_s {
            let (seg, seg_end) = match self.segment_at(a) {
                Some(i) => (self.segments[i], self.starts[i + 1].0),
                None if a < 0.0 => (HOLD_FOREVER, 0.0),
                None => (HOLD_FOREVER, f64::INFINITY),
            };
            let b = seg_end.min(t1_s);
            let weight = (b - a) / h;
            let state = self.truth(a);
            let a_nav = match seg {
                Segment::Accelerate {
                    accel_body_mps2, ..
                } => state.attitude.to_nav(&accel_body_mps2).0,
                _ => Vector3::zeros(),
            };
            let f_body_a = state
                .attitude
                .to_body(&NavVector(specific_force_nav(&a_nav, self.gravity_mps2)))
                .0;
            let w = seg.rate_body();
            gyro += weight * w;
            force += weight * mean_rotation_times(&-w, b - a, &f_body_a);
            a = b;
        }
        (BodyVector(gyro), BodyVector(force))
    }
    fn gravity_mps2(&self) -> f64 {
        self.gravity_mps2
    }
}

/// Any of the trajectories, for configs (static dispatch by `match`, no allocation per sample).
#[derive(Clone, Debug, PartialEq)]
pub enum AnyTrajectory {
    Static(Static),
    ConstantRate(ConstantRate),
    Coning(Coning),
    Profile(Profile),
}

impl Trajectory for AnyTrajectory {
    fn truth(&self, t_s: f64) -> NavState {
        match self {
            AnyTrajectory::Static(t) => t.truth(t_s),
            AnyTrajectory::ConstantRate(t) => t.truth(t_s),
            AnyTrajectory::Coning(t) => t.truth(t_s),
            AnyTrajectory::Profile(t) => t.truth(t_s),
        }
    }
    #[inline]
    fn imu_average(&self, t0_s: f64, t1_s: f64) -> (BodyVector, BodyVector) {
        match self {
            AnyTrajectory::Static(t) => t.imu_average(t0_s, t1_s),
            AnyTrajectory::ConstantRate(t) => t.imu_average(t0_s, t1_s),
            AnyTrajectory::Coning(t) => t.imu_average(t0_s, t1_s),
            AnyTrajectory::Profile(t) => t.imu_average(t0_s, t1_s),
        }
    }
    fn is_static(&self) -> bool {
        matches!(self, AnyTrajectory::Static(_))
    }
    fn gravity_mps2(&self) -> f64 {
        match self {
            AnyTrajectory::Static(t) => t.gravity_mps2(),
            AnyTrajectory::ConstantRate(t) => t.gravity_mps2(),
            AnyTrajectory::Coning(t) => t.gravity_mps2(),
            AnyTrajectory::Profile(t) => t.gravity_mps2(),
        }
    }
}
