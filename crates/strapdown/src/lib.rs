//! Strapdown inertial mechanisation, analytic trajectories and navigation error for imudrift.
//!
//! Turns (corrupted) gyro and accelerometer outputs into attitude, velocity and position, so that the
//! growth of their error can be compared with the closed-form drift laws.
//!
//! **Conventions.**
//! - Navigation frame: north-east-down (NED), flat and non-rotating, origin at the start position.
//! - Body frame: forward-right-down. [`NavVector`] and [`BodyVector`] are distinct types; only an
//!   [`Attitude`] (body-to-navigation direction cosine matrix `C`, `v_nav = C v_body`, Woodman eq 21)
//!   converts between them.
//! - Gravity: constant, `g = 9.80665 m/s^2` ([`STANDARD_GRAVITY_MPS2`]) pointing down, i.e. the gravity
//!   vector in NED is `(0, 0, +g)`. Accelerometers measure specific force, so a static level IMU reads
//!   `(0, 0, -g)` and `dv/dt = C f + (0, 0, g)` (Woodman eq 43 with his `g_g` the reading at rest).
//! - Units: SI (rad, rad/s, m/s^2, m/s, m, s). IMU samples are *interval averages*: sample `k` is the
//!   body-frame angle and velocity increment over `[k dt, (k+1) dt]` divided by `dt` (an integrating IMU).
//!
//! **Schemes** ([`Scheme`]): `Woodman` is TR-696 eqs 41, 42, 45, 46 exactly (docs/model.md §1.1-1.2);
//! `Accurate` (default) uses the exact rotation for a constant rate over each step with a
//! one-plus-previous-sample coning correction, and trapezoidal velocity and position.
//!
//! **Trajectories** ([`Trajectory`]): [`Static`], [`ConstantRate`], [`Coning`] and piecewise
//! [`Profile`]s give closed-form truth and the ideal IMU outputs; [`TrajectorySpec`] reads them from TOML
//! with units in the key names (`rate_deg_s`, `duration_s`, ...).
//!
//! **Error** ([`nav_error`]): estimate minus truth, in the navigation frame.
//!
//! A static, level IMU integrated for 10 s at 100 Hz: with perfect readings it stays at the
//! origin; with an accelerometer bias b along its forward (north) axis the position error is
//! b t^2 / 2, which the trapezoidal scheme integrates exactly for a constant bias.
//!
//! ```
//! use strapdown::{nav_error, BodyVector, NavState, Scheme, Strapdown, STANDARD_GRAVITY_MPS2};
//!
//! let (dt_s, steps) = (0.01, 1000);
//! let gyro = BodyVector::zeros();
//! let run = |bias_mps2: f64| {
//!     let mut nav = Strapdown::new(Scheme::Accurate, NavState::default(), STANDARD_GRAVITY_MPS2);
//!     let accel = BodyVector::new(bias_mps2, 0.0, -STANDARD_GRAVITY_MPS2);
//!     for _ in 0..steps {
//!         nav.step(&gyro, &accel, dt_s);
//!     }
//!     nav_error(&nav.state(), &NavState::default())
//! };
//! let still = run(0.0);
//! assert_eq!(still.pos_ned_m, [0.0; 3]);
//! assert_eq!(still.attitude_angle_rad, 0.0);
//! let biased = run(0.01);
//! let t_s = steps as f64 * dt_s;
//! assert!((biased.pos_ned_m[0] - 0.5 * 0.01 * t_s * t_s).abs() < 1e-9);
//! assert!((biased.vel_ned_mps[0] - 0.01 * t_s).abs() < 1e-12);
//! assert!(biased.pos_ned_m[1].abs() < 1e-12 && biased.pos_ned_m[2].abs() < 1e-9);
//! ```

pub mod earth;
pub mod error_model;
mod frames;
mod lanes;
mod mechanisation;
mod nav_error;
mod on_earth;
pub mod round_earth;
pub mod spec;
pub mod trajectory;

pub use frames::{Attitude, BodyVector, NavVector};
pub use lanes::{Lanes, Strapdown, StrapdownLanes, CHUNK};
pub use mechanisation::{NavState, Scheme};
pub use nav_error::{nav_error, NavError};
pub use on_earth::{EarthModel, EarthTrajectory};
pub use round_earth::{RoundEarth, Vertical};
pub use spec::{TrajectoryError, TrajectorySpec};
pub use trajectory::{AnyTrajectory, Coning, ConstantRate, Profile, Segment, Static, Trajectory};

/// Standard gravity, m/s^2 (the constant of the seed and of docs/cli.md).
pub const STANDARD_GRAVITY_MPS2: f64 = 9.80665;

impl Strapdown {
    /// An integrator started on `trajectory`'s truth at `t = 0`, with the trajectory's gravity and the
    /// coning history primed from the interval `[-dt, 0]` so the first step is as accurate as the others.
    pub fn for_trajectory<T: Trajectory + ?Sized>(
        scheme: Scheme,
        trajectory: &T,
        dt_s: f64,
    ) -> Strapdown {
        let mut s = Strapdown::new(scheme, trajectory.truth(0.0), trajectory.gravity_mps2());
        let (gyro_prev, _) = trajectory.imu_average(-dt_s, 0.0);
        s.set_previous_gyro(&gyro_prev, dt_s);
        s
    }
}
