//! Perfect sensors on analytic trajectories: no drift beyond rounding.

use strapdown::{nav_error, Attitude, ConstantRate, Scheme, Static, Strapdown, Trajectory};

const SCHEMES: [Scheme; 2] = [Scheme::Woodman, Scheme::Accurate];

fn run<T: Trajectory>(traj: &T, scheme: Scheme, dt_s: f64, steps: u64) -> strapdown::NavError {
    let mut sd = Strapdown::for_trajectory(scheme, traj, dt_s);
    for k in 0..steps {
        let (gyro, accel) = traj.ideal_imu(k, dt_s);
        sd.step(&gyro, &accel, dt_s);
    }
    nav_error(&sd.state(), &traj.truth(steps as f64 * dt_s))
}

#[test]
fn static_level_is_bit_exactly_zero_for_one_hour() {
    let traj = Static::new(Attitude::identity());
    for scheme in SCHEMES {
        let e = run(&traj, scheme, 0.01, 360_000);
        assert_eq!(e.pos_ned_m, [0.0; 3], "{scheme:?}");
        assert_eq!(e.vel_ned_mps, [0.0; 3], "{scheme:?}");
        assert_eq!([e.roll_rad, e.pitch_rad, e.yaw_rad], [0.0; 3], "{scheme:?}");
        assert_eq!(e.attitude_angle_rad, 0.0, "{scheme:?}");
    }
}

#[test]
fn static_tilted_stays_at_rounding_level() {
    // C C^T differs from I by ~1e-16 per element, so gravity leaks ~g*1e-16 m/s^2 per step at worst;
    // over n steps of dt the position can move at most ~g*1e-16*t^2/2 (t = 600 s: ~2e-10 m).
    const POS_TOL_M: f64 = 1e-9;
    const ATT_TOL_RAD: f64 = 1e-13;
    let traj = Static::new(Attitude::from_euler_rad(0.2, -0.4, 1.0));
    for scheme in SCHEMES {
        let e = run(&traj, scheme, 0.01, 60_000);
        assert!(
            e.pos_ned_m.iter().all(|p| p.abs() < POS_TOL_M),
            "{scheme:?} {e:?}"
        );
        assert!(e.attitude_angle_rad < ATT_TOL_RAD, "{scheme:?} {e:?}");
    }
}

#[test]
fn constant_rate_one_hour_attitude_error_below_1e9_rad() {
    // Issue requirement: attitude error below 1e-9 rad after 1 h of constant-rate rotation.
    const ATT_TOL_RAD: f64 = 1e-9;
    let traj = ConstantRate::new(
        Attitude::from_euler_rad(0.1, 0.2, 0.3),
        strapdown::BodyVector::new(0.3, -0.2, 0.5),
    );
    for scheme in SCHEMES {
        let e = run(&traj, scheme, 0.01, 360_000);
        eprintln!(
            "{scheme:?}: constant rate, 1 h at 100 Hz: attitude error {:.3e} rad",
            e.attitude_angle_rad
        );
        assert!(
            e.attitude_angle_rad < ATT_TOL_RAD,
            "{scheme:?}: {:e} rad",
            e.attitude_angle_rad
        );
    }
}

#[test]
fn static_level_with_other_gravity_from_spec_is_bit_exactly_zero() {
    let spec = strapdown::TrajectorySpec::from_toml_str("kind = \"static\"", "perfect_sensors.rs")
        .unwrap();
    let traj = spec.build_with_gravity(3.71).unwrap();
    assert_eq!(traj.gravity_mps2(), 3.71);
    for scheme in SCHEMES {
        let e = run(&traj, scheme, 0.01, 60_000);
        assert_eq!(e.pos_ned_m, [0.0; 3], "{scheme:?}");
        assert_eq!(e.vel_ned_mps, [0.0; 3], "{scheme:?}");
    }
    assert!(spec
        .build_with_gravity(-1.0)
        .unwrap_err()
        .to_string()
        .contains("gravity_mps2"));
}
