//! Perfect sensors on moving trajectories: the navigation error shrinks with the step at the order each
//! scheme should have. Orders are measured as the least-squares slope of log(error) against log(dt).
//!
//! Expected orders for interval-average (integrating) IMU samples:
//! - Woodman (rectangular, eqs 41/45/46): attitude 2 under coning (the uncorrected coning drift of the
//!   single-sample rotation vector is O(dt^2)), velocity and position 1 (rectangle rule).
//! - Accurate: attitude 4 under small-angle coning (one-plus-previous-sample correction cancels the
//!   dt^2 term; the cone here is 0.1 rad, where dt^4 dominates down to ~1 ms; for cone angles of
//!   0.3-0.6 rad a dt^3 term of higher degree in the angle takes over below ~5 ms),
//!   velocity and position 2 (trapezoidal rule).
//!
//! Tolerance on a measured order: 0.15. The runs are deterministic; the slack covers the higher-order
//! terms still present at the coarsest step (the asymptotic regime is reached to within a few percent in
//! error ratio, i.e. < 0.1 in order, over the steps used) and the segment-boundary alignment on profiles.

use strapdown::{nav_error, Coning, NavError, Profile, Scheme, Strapdown, Trajectory};

const ORDER_TOL: f64 = 0.15;

/// Error at `t_end_s` of a perfect-sensor run with `n` steps.
fn final_error<T: Trajectory>(traj: &T, scheme: Scheme, t_end_s: f64, n: u64) -> NavError {
    let dt = t_end_s / n as f64;
    let mut sd = Strapdown::for_trajectory(scheme, traj, dt);
    for k in 0..n {
        let (gyro, accel) = traj.ideal_imu(k, dt);
        sd.step(&gyro, &accel, dt);
    }
    nav_error(&sd.state(), &traj.truth(t_end_s))
}

fn norm3(v: [f64; 3]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Least-squares slope of log(err) on log(dt).
fn measured_order(dts: &[f64], errs: &[f64]) -> f64 {
    let xs: Vec<f64> = dts.iter().map(|d| d.ln()).collect();
    let ys: Vec<f64> = errs.iter().map(|e| e.ln()).collect();
    let n = xs.len() as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    sxy / sxx
}

struct Orders {
    attitude: f64,
    velocity: f64,
    position: f64,
}

fn orders<T: Trajectory>(
    traj: &T,
    scheme: Scheme,
    t_end_s: f64,
    steps: &[u64],
) -> (Orders, Vec<NavError>) {
    let errs: Vec<NavError> = steps
        .iter()
        .map(|&n| final_error(traj, scheme, t_end_s, n))
        .collect();
    let dts: Vec<f64> = steps.iter().map(|&n| t_end_s / n as f64).collect();
    let att: Vec<f64> = errs.iter().map(|e| e.attitude_angle_rad).collect();
    let vel: Vec<f64> = errs.iter().map(|e| norm3(e.vel_ned_mps)).collect();
    let pos: Vec<f64> = errs.iter().map(|e| norm3(e.pos_ned_m)).collect();
    let o = Orders {
        attitude: measured_order(&dts, &att),
        velocity: measured_order(&dts, &vel),
        position: measured_order(&dts, &pos),
    };
    eprintln!(
        "{scheme:?}: measured orders attitude {:.3}, velocity {:.3}, position {:.3}; finest errors {:.3e} rad, {:.3e} m/s, {:.3e} m",
        o.attitude, o.velocity, o.position, att[att.len() - 1], vel[vel.len() - 1], pos[pos.len() - 1]
    );
    (o, errs)
}

fn assert_order(what: &str, got: f64, expected: f64) {
    assert!(
        (got - expected).abs() < ORDER_TOL,
        "{what}: measured order {got:.3}, expected {expected}"
    );
}

#[test]
fn coning_error_orders() {
    // 1 Hz coning, 0.1 rad half-angle, over 10.3 s: not a whole number of cone periods, so the periodic
    // part of the velocity error does not cancel by accident at the end time.
    let traj = Coning::new(0.1, std::f64::consts::TAU);
    let t_end = 10.3;
    let steps = [500, 1000, 2000, 4000];
    let (w, _) = orders(&traj, Scheme::Woodman, t_end, &steps);
    assert_order("Woodman attitude", w.attitude, 2.0);
    assert_order("Woodman velocity", w.velocity, 1.0);
    assert_order("Woodman position", w.position, 1.0);
    let (a, errs) = orders(&traj, Scheme::Accurate, t_end, &steps);
    assert_order("Accurate attitude", a.attitude, 4.0);
    assert_order("Accurate velocity", a.velocity, 2.0);
    assert_order("Accurate position", a.position, 2.0);
    // At 100 Hz-ish rates the accurate attitude error is far below the Woodman one.
    let e = errs.last().unwrap();
    assert!(e.attitude_angle_rad < 1e-8, "{e:?}");
}

const PROFILE: &str = include_str!("data/profile.toml");

#[test]
fn profile_error_orders() {
    // Rotations are single-axis within a step (segments never overlap), so interval-average rates give
    // the exact rotation: attitude stays at rounding level for both schemes. Velocity and position follow
    // the integration rule; the specific force jumps at segment boundaries that fall inside a step, which
    // adds a one-off O(dt^2) term whose size depends on where the boundary falls, hence the wider spread
    // of the Accurate points (6 steps over a factor 32 to average it out).
    let traj = Profile::from_toml_str(PROFILE, "convergence.rs").unwrap();
    let t_end = 10.3;
    let steps = [250, 500, 1000, 2000, 4000, 8000];
    let (w, errs_w) = orders(&traj, Scheme::Woodman, t_end, &steps);
    assert_order("Woodman velocity", w.velocity, 1.0);
    assert_order("Woodman position", w.position, 1.0);
    let (a, errs_a) = orders(&traj, Scheme::Accurate, t_end, &steps);
    assert_order("Accurate velocity", a.velocity, 2.0);
    assert_order("Accurate position", a.position, 2.0);
    // Rounding: ~1e-16 per step over at most 8000 steps.
    for e in errs_w.iter().chain(&errs_a) {
        assert!(e.attitude_angle_rad < 1e-12, "{e:?}");
    }
}
