//! Navigation error of a solution against the truth.

use crate::frames::so3_log;
use crate::mechanisation::NavState;

/// Error of an estimate against the truth (estimate minus truth).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct NavError {
    /// Roll error: difference of z-y-x Euler roll angles, wrapped to `(-pi, pi]`, rad.
    pub roll_rad: f64,
    /// Pitch error: difference of Euler pitch angles, rad.
    pub pitch_rad: f64,
    /// Yaw (heading) error: difference of Euler yaw angles, wrapped to `(-pi, pi]`, rad.
    pub yaw_rad: f64,
    /// Attitude error as a rotation vector in the navigation frame: `C_est C_true^T = exp([psi x])`,
    /// components about north, east, down (rad). Free of Euler singularities; for a level, north-facing
    /// body its components equal roll, pitch and yaw error to first order.
    pub attitude_nav_rad: [f64; 3],
    /// Total attitude error angle `|psi|`, rad.
    pub attitude_angle_rad: f64,
    /// Position error north, east, down, m.
    pub pos_ned_m: [f64; 3],
    /// Velocity error north, east, down, m/s.
    pub vel_ned_mps: [f64; 3],
}

impl NavError {
    /// Horizontal position error magnitude, m.
    pub fn pos_horizontal_m(&self) -> f64 {
        self.pos_ned_m[0].hypot(self.pos_ned_m[1])
    }
    /// Horizontal velocity error magnitude, m/s.
    pub fn vel_horizontal_mps(&self) -> f64 {
        self.vel_ned_mps[0].hypot(self.vel_ned_mps[1])
    }
}

/// Wrap an angle difference to `(-pi, pi]`.
fn wrap_pi(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let w = a - TAU * (a / TAU).round();
    if w <= -PI {
        w + TAU
    } else {
        w
    }
}

/// The error of `estimate` against `truth`, all in the navigation frame.
pub fn nav_error(estimate: &NavState, truth: &NavState) -> NavError {
    let (r_e, p_e, y_e) = estimate.attitude.euler_rad();
    let (r_t, p_t, y_t) = truth.attitude.euler_rad();
    let psi = so3_log(&(estimate.attitude.0 * truth.attitude.0.transpose()));
    let dp = estimate.position.0 - truth.position.0;
    let dv = estimate.velocity.0 - truth.velocity.0;
    NavError {
        roll_rad: wrap_pi(r_e - r_t),
        pitch_rad: p_e - p_t,
        yaw_rad: wrap_pi(y_e - y_t),
        attitude_nav_rad: [psi.x, psi.y, psi.z],
        attitude_angle_rad: psi.norm(),
        pos_ned_m: [dp.x, dp.y, dp.z],
        vel_ned_mps: [dv.x, dv.y, dv.z],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frames::{Attitude, NavVector};

    #[test]
    fn identical_states_have_zero_error() {
        let s = NavState {
            attitude: Attitude::from_euler_rad(0.3, 0.1, -3.0),
            velocity: NavVector::new(1.0, 2.0, 3.0),
            position: NavVector::new(-4.0, 5.0, 6.0),
        };
        let e = nav_error(&s, &s);
        assert_eq!(e.pos_ned_m, [0.0; 3]);
        assert_eq!(e.vel_ned_mps, [0.0; 3]);
        assert_eq!((e.roll_rad, e.pitch_rad, e.yaw_rad), (0.0, 0.0, 0.0));
        assert!(e.attitude_angle_rad < 1e-15);
    }

    #[test]
    fn small_heading_error_is_seen_across_the_wrap() {
        const YAW_NEAR_PI: f64 = std::f64::consts::PI - 2.65e-6;
        let truth = NavState {
            attitude: Attitude::from_euler_rad(0.0, 0.0, YAW_NEAR_PI),
            ..Default::default()
        };
        let est = NavState {
            attitude: Attitude::from_euler_rad(0.0, 0.0, -YAW_NEAR_PI),
            ..Default::default()
        };
        let e = nav_error(&est, &truth);
        let expected = 2.0 * std::f64::consts::PI - 2.0 * YAW_NEAR_PI;
        assert!((e.yaw_rad - expected).abs() < 1e-12, "{}", e.yaw_rad);
        assert!((e.attitude_nav_rad[2] - expected).abs() < 1e-12);
        assert!((e.attitude_angle_rad - expected).abs() < 1e-12);
    }

    #[test]
    fn tiny_roll_error_is_resolved_below_acos_precision() {
        // acos near 1 resolves only ~1e-8 rad; the atan2 route must see 1e-12 rad.
        let truth = NavState::default();
        let est = NavState {
            attitude: Attitude::from_euler_rad(1e-12, 0.0, 0.0),
            ..Default::default()
        };
        let e = nav_error(&est, &truth);
        assert!((e.attitude_nav_rad[0] - 1e-12).abs() < 1e-24);
        assert!((e.roll_rad - 1e-12).abs() < 1e-24);
    }
}
