//! The round, rotating Earth's mechanisation (strapdown::round_earth) against its closed forms:
//! an ideal static IMU stays put, a tilt oscillates at the Schuler period, a gyro bias follows
//! R eps (t - sin(w_s t) / w_s) on a non-rotating round Earth (Titterton & Weston ch. 12; the
//! theory notes' 7.3), and the flat Earth is unchanged (every flat test and golden output).
//!
//! Tolerances: the closed forms are the linearised single-channel errors with one radius; the
//! integration is exact to rounding for the static case (so: millimetres and 1e-10 rad, the
//! rounding of 144 000 steps, over four hours), and
//! the east channel's radius is R_E + h, not the Gaussian mean the forms take, 0.17 % apart at
//! 45 deg N, which sets the 0.5 % period tolerance the issue states and a 0.3 % one on the bias
//! error (the form's own linearisation error at 1 h, (eps t)^2 terms, is below 1e-6).

use strapdown::earth::{radii_m, schuler_gyro_bias_m, Place};
use strapdown::{Attitude, NavState, RoundEarth, Scheme, Strapdown, Vertical};

/// `attitudes`: the navigator's initial attitude and the truth's.
fn run(
    scheme: Scheme,
    earth: RoundEarth,
    (nav_attitude, truth_attitude): (Attitude, Attitude),
    gyro_bias: [f64; 3],
    dt: f64,
    steps: usize,
    mut each: impl FnMut(usize, &NavState),
) {
    let (w, f) = earth.static_imu(&truth_attitude);
    let initial = NavState {
        attitude: nav_attitude,
        ..NavState::default()
    };
    let mut nav = Strapdown::on_earth(scheme, initial, earth);
    let mut gyro = w;
    for (g, b) in gyro.0.iter_mut().zip(gyro_bias) {
        *g += b;
    }
    nav.set_previous_gyro(&gyro, dt);
    for i in 1..=steps {
        nav.step(&gyro, &f, dt);
        each(i, &nav.state());
    }
}

/// An ideal static IMU's solution stays at rest: with the height held for four hours, and with
/// the vertical channel free for one (beyond that the free channel's instability, time constant
/// about 570 s, amplifies the rounding of the first steps to metres: e^(4 h / 570 s) = 1e11).
#[test]
fn ideal_static_imu_stays_put() {
    for scheme in Scheme::ALL {
        for (lat, vertical, steps) in [
            (0.0, Vertical::Held, 144_000),
            (45.0, Vertical::Held, 144_000),
            (80.0, Vertical::Held, 144_000),
            (45.0, Vertical::Free, 36_000),
        ] {
            let earth = RoundEarth {
                vertical,
                ..RoundEarth::at(Place::from_deg(lat, 10.0, 300.0))
            };
            let att = Attitude::from_euler_rad(0.02, -0.01, 1.0);
            let mut worst = (0.0f64, 0.0f64);
            run(scheme, earth, (att, att), [0.0; 3], 0.1, steps, |_, s| {
                worst.0 = worst.0.max(s.position.0.norm());
                worst.1 = worst.1.max(
                    strapdown::nav_error(
                        s,
                        &NavState {
                            attitude: att,
                            ..NavState::default()
                        },
                    )
                    .attitude_angle_rad,
                );
            });
            eprintln!(
                "{scheme:?} {lat} deg {vertical:?}: largest position {:.2e} m, attitude {:.2e} rad",
                worst.0, worst.1
            );
            assert!(
                worst.0 < 1e-3 && worst.1 < 1e-10,
                "{scheme:?} {lat} {vertical:?}: {worst:?}"
            );
        }
    }
}

/// The east velocity error of a roll error of 0.01 deg on a non-rotating round Earth with the
/// height held: its zero crossings one Schuler period apart, 2 pi sqrt((R_E + h) / g).
#[test]
fn tilt_oscillates_at_the_schuler_period() {
    let place = Place::from_deg(45.0, 0.0, 0.0);
    let earth = RoundEarth {
        place,
        vertical: Vertical::Held,
        rotating: false,
    };
    let truth = Attitude::identity();
    let nav = Attitude::from_euler_rad(0.01f64.to_radians(), 0.0, 0.0);
    let dt = 0.1;
    let mut crossings = Vec::new();
    let mut last = 0.0f64;
    run(
        Scheme::Accurate,
        earth,
        (nav, truth),
        [0.0; 3],
        dt,
        4 * 36_000,
        |i, s| {
            let ve = s.velocity.0.y;
            if i > 1 && (ve > 0.0) != (last > 0.0) {
                crossings.push(i as f64 * dt - dt * ve / (ve - last));
            }
            last = ve;
        },
    );
    let (_, re) = radii_m(place.lat_rad);
    let expected = std::f64::consts::TAU * (re / place.gravity_mps2()).sqrt();
    let periods: Vec<f64> = crossings.windows(3).map(|w| w[2] - w[0]).collect();
    eprintln!(
        "crossings {crossings:?}; expected period {:.1} s ({:.2} min)",
        expected,
        expected / 60.0
    );
    assert!(
        !periods.is_empty(),
        "fewer than three zero crossings in 4 h"
    );
    for p in periods {
        assert!(
            (p / expected - 1.0).abs() < 5e-3,
            "period {p} s against {expected} s"
        );
        assert!((p / 60.0 - 84.4).abs() < 0.5, "period {} min", p / 60.0);
    }
}

/// A north gyro bias on a non-rotating round Earth with the height held: the east position error
/// R eps (t - sin(w_s t) / w_s) at 10, 30, 60 and 120 min (the form's radius: R_E + h here).
#[test]
fn gyro_bias_follows_the_schuler_closed_form() {
    let place = Place::from_deg(45.0, 0.0, 0.0);
    let earth = RoundEarth {
        place,
        vertical: Vertical::Held,
        rotating: false,
    };
    let eps = 0.1f64.to_radians() / 3600.0;
    let dt = 0.1;
    let at = [600.0, 1800.0, 3600.0, 7200.0];
    let mut got = Vec::new();
    run(
        Scheme::Accurate,
        earth,
        (Attitude::identity(), Attitude::identity()),
        [eps, 0.0, 0.0],
        dt,
        72_000,
        |i, s| {
            let t = i as f64 * dt;
            if at.iter().any(|a| (a - t).abs() < dt / 2.0) {
                got.push((t, s.position.0.y.abs()));
            }
        },
    );
    let (_, re) = radii_m(place.lat_rad);
    let ws = (place.gravity_mps2() / re).sqrt();
    for (t, e) in got {
        let law = re * eps * (t - (ws * t).sin() / ws);
        // The library's form (Gaussian mean radius) for the record.
        let lib = schuler_gyro_bias_m(&place, eps, t);
        eprintln!(
            "t {t} s: east error {e:.1} m, law {law:.1} m ({:.4}), Gaussian-radius form {lib:.1} m",
            e / law
        );
        assert!((e / law - 1.0).abs() < 3e-3, "t {t}: {e} against {law}");
    }
}
