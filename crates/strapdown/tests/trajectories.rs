//! The closed-form ideal IMU outputs of every trajectory agree with an independent route: the body rate
//! and specific force obtained by central differences of the truth itself, integrated by Gauss-Legendre
//! quadrature over the sample interval.

use nalgebra::Vector3;
use strapdown::{
    nav_error, Attitude, BodyVector, Coning, ConstantRate, Profile, Static, Trajectory,
    STANDARD_GRAVITY_MPS2,
};

/// Central-difference half-width, s. Truncation ~ delta^2 |d^3/dt^3| ~ 1e-10 here, rounding ~ 1e-16/delta
/// times the magnitude (<= 30 m/s): both below 1e-9.
const DELTA_S: f64 = 1e-5;
/// Agreement required between closed form and quadrature, rad/s and m/s^2: 100x the numerical error
/// above, while any formula slip (a wrong sign, a missing half-angle factor) is O(w h) ~ 1e-3 or more.
const IMU_TOL: f64 = 1e-7;

/// 5-point Gauss-Legendre nodes and weights on [-1, 1] (Abramowitz & Stegun, Table 25.4).
const GL5: [(f64, f64); 5] = [
    (0.0, 0.568_888_888_888_888_9),
    (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (0.906_179_845_938_664, 0.236_926_885_056_189_1),
    (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
];

/// Body rate and specific force at `t` from central differences of the truth.
fn differentiated<T: Trajectory>(traj: &T, t: f64) -> (Vector3<f64>, Vector3<f64>) {
    let (minus, mid, plus) = (
        traj.truth(t - DELTA_S),
        traj.truth(t),
        traj.truth(t + DELTA_S),
    );
    // C+ C-^T = exp([psi x]) in the navigation frame; psi = C w 2 delta to second order.
    let psi = Vector3::from(nav_error(&plus, &minus).attitude_nav_rad);
    let rate_body = mid.attitude.matrix().tr_mul(&psi) / (2.0 * DELTA_S);
    let accel_nav = (plus.velocity.0 - minus.velocity.0) / (2.0 * DELTA_S);
    let gravity_nav = Vector3::new(0.0, 0.0, traj.gravity_mps2());
    let force_body = mid.attitude.matrix().tr_mul(&(accel_nav - gravity_nav));
    (rate_body, force_body)
}

/// Mean over `[t0, t1]` by composite Gauss-Legendre, split at `breaks` (segment boundaries) so that
/// every node is in the interior of a smooth piece.
fn quadrature_mean<T: Trajectory>(
    traj: &T,
    t0: f64,
    t1: f64,
    breaks: &[f64],
) -> (Vector3<f64>, Vector3<f64>) {
    const PANELS: usize = 8;
    let mut cuts = vec![t0];
    cuts.extend(breaks.iter().copied().filter(|&b| b > t0 && b < t1));
    cuts.push(t1);
    let (mut rate, mut force) = (Vector3::zeros(), Vector3::zeros());
    for piece in cuts.windows(2) {
        let width = (piece[1] - piece[0]) / PANELS as f64;
        for p in 0..PANELS {
            let centre = piece[0] + (p as f64 + 0.5) * width;
            for (x, w) in GL5 {
                let (r, f) = differentiated(traj, centre + 0.5 * width * x);
                rate += r * (0.5 * width * w);
                force += f * (0.5 * width * w);
            }
        }
    }
    (rate / (t1 - t0), force / (t1 - t0))
}

fn check<T: Trajectory>(name: &str, traj: &T, intervals: &[(f64, f64)], breaks: &[f64]) {
    for &(t0, t1) in intervals {
        let (gyro, accel) = traj.imu_average(t0, t1);
        let (rate_q, force_q) = quadrature_mean(traj, t0, t1, breaks);
        let (dg, df) = ((gyro.0 - rate_q).norm(), (accel.0 - force_q).norm());
        assert!(
            dg < IMU_TOL && df < IMU_TOL,
            "{name} [{t0}, {t1}]: gyro diff {dg:e} rad/s, accel diff {df:e} m/s^2"
        );
    }
}

#[test]
fn static_tilted_reads_gravity_in_body_axes() {
    let traj = Static::new(Attitude::from_euler_rad(0.3, -0.2, 1.0));
    check("static", &traj, &[(0.0, 0.01), (5.0, 6.0)], &[]);
    let (_, accel) = traj.ideal_imu(7, 0.01);
    assert!((accel.0.norm() - STANDARD_GRAVITY_MPS2).abs() < 1e-14);
}

#[test]
fn constant_rate_outputs_match_differentiated_truth() {
    let traj = ConstantRate::new(
        Attitude::from_euler_rad(0.1, 0.4, -0.7),
        BodyVector::new(0.3, -0.2, 0.5),
    );
    // h = 0.01 s uses the series branch of the closed forms, h = 0.5 s the trigonometric one.
    check(
        "constant rate",
        &traj,
        &[(0.0, 0.01), (12.34, 12.35), (3.0, 3.5), (-0.5, 0.0)],
        &[],
    );
}

#[test]
fn coning_outputs_match_differentiated_truth() {
    // Non-standard gravity (Mars) so a hard-wired g anywhere would show.
    let traj = Coning {
        gravity_mps2: 3.71,
        ..Coning::new(0.2, std::f64::consts::TAU * 2.0)
    };
    check(
        "coning",
        &traj,
        &[(-0.01, 0.0), (0.0, 0.01), (1.2345, 1.2445), (2.0, 2.1)],
        &[],
    );
    // The truth really is a cone: the body z axis keeps the half-angle to the vertical.
    for t in [0.0, 0.1, 0.37, 5.0] {
        let c = traj.truth(t).attitude;
        let z_nav = c.matrix().column(2);
        assert!((z_nav[2] - 0.2f64.cos()).abs() < 1e-15, "t = {t}");
    }
}

const PROFILE: &str = include_str!("data/profile.toml");
const PROFILE_BREAKS: [f64; 7] = [0.0, 1.003, 2.003, 5.003, 7.003, 9.003, 10.003];

#[test]
fn profile_outputs_match_differentiated_truth_inside_and_across_segments() {
    let traj = Profile::from_toml_str(PROFILE, "trajectories.rs").unwrap();
    let inside = [
        (0.5, 0.51),
        (1.5, 1.51),
        (1.2, 1.5),
        (3.0, 3.01),
        (6.0, 6.01),
        (8.0, 8.01),
        (-1.0, -0.99),
        (12.0, 12.01),
    ];
    check("profile inside", &traj, &inside, &PROFILE_BREAKS);
    let across = [
        (-0.005, 0.005),
        (1.0, 1.01),
        (1.998, 2.008),
        (4.995, 5.005),
        (7.0, 7.01),
        (9.0, 9.01),
        (9.998, 10.008),
        (0.9, 2.1),
    ];
    check("profile across", &traj, &across, &PROFILE_BREAKS);
}

#[test]
fn profile_truth_is_continuous_and_integrates_its_own_velocity() {
    let traj = Profile::from_toml_str(PROFILE, "trajectories.rs").unwrap();
    // Continuity at each boundary: a 1e-9 s step moves nothing by more than rate x 1e-9 plus rounding.
    for b in PROFILE_BREAKS {
        let e = nav_error(&traj.truth(b - 1e-9), &traj.truth(b));
        assert!(e.attitude_angle_rad < 1e-8, "attitude jumps at {b}: {e:?}");
        assert!(
            e.vel_ned_mps
                .iter()
                .chain(&e.pos_ned_m)
                .all(|x| x.abs() < 1e-7),
            "jump at {b}: {e:?}"
        );
    }
    // Position is the integral of velocity: Simpson over each piece (exact for the piecewise quadratic).
    let mut p = traj.truth(0.0).position.0;
    for piece in PROFILE_BREAKS
        .windows(2)
        .map(|w| (w[0], w[1]))
        .chain([(10.003, 11.0)])
    {
        let (a, b) = piece;
        let v = |t: f64| traj.truth(t).velocity.0;
        p += (b - a) / 6.0 * (v(a) + 4.0 * v(0.5 * (a + b)) + v(b - 1e-12));
    }
    let end = traj.truth(11.0).position.0;
    assert!((p - end).norm() < 1e-9, "integrated {p:?} vs truth {end:?}");
}
