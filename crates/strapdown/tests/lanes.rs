//! `StrapdownLanes`: each lane gives exactly the numbers of a one-lane integrator (`Strapdown`) fed
//! the same samples, whatever the other lanes do (large rotations in some lanes take the
//! coefficients' lane-by-lane path for the whole step), for both schemes.

use nalgebra::Vector3;
use strapdown::{Attitude, BodyVector, NavState, NavVector, Scheme, Strapdown, StrapdownLanes};

const L: usize = 8;

/// A deterministic, irregular input: lane l, step k, axis a.
fn sample(l: usize, k: usize, a: usize, scale: f64) -> f64 {
    let x = ((l * 7919 + k * 104_729 + a * 1_299_709) % 1_000_003) as f64 / 1_000_003.0 - 0.5;
    scale * x
}

#[test]
fn every_lane_is_a_one_lane_integrator() {
    for scheme in Scheme::ALL {
        let initial: [NavState; L] = std::array::from_fn(|l| NavState {
            attitude: Attitude::from_euler_rad(0.01 * l as f64, -0.02 * l as f64, 0.3 * l as f64),
            velocity: NavVector(Vector3::new(l as f64, -1.0, 0.5)),
            position: NavVector(Vector3::new(10.0 * l as f64, 3.0, -2.0)),
        });
        let (dt, g) = (0.01, 9.80665);
        let mut lanes = StrapdownLanes::<L>::new(scheme, &initial, g);
        let mut singles: Vec<Strapdown> = initial
            .iter()
            .map(|s| Strapdown::new(scheme, *s, g))
            .collect();
        let prev = Vector3::new(0.1, -0.2, 0.05);
        lanes.set_previous_gyro(&prev, dt);
        for s in &mut singles {
            s.set_previous_gyro(&BodyVector(prev), dt);
        }
        // 600 steps: past two re-orthonormalisations; lane 3 turns at up to 15 rad/s (0.15 rad a
        // step, the sin/cos branch) on every 50th step.
        for k in 0..600 {
            let mut gyro = [[0.0; L]; 3];
            let mut accel = [[0.0; L]; 3];
            for l in 0..L {
                let fast = if l == 3 && k % 50 == 0 { 30.0 } else { 2.0 };
                for a in 0..3 {
                    gyro[a][l] = sample(l, k, a, fast);
                    accel[a][l] = sample(l, k, a + 3, 4.0) - if a == 2 { g } else { 0.0 };
                }
                singles[l].step(
                    &BodyVector(Vector3::new(gyro[0][l], gyro[1][l], gyro[2][l])),
                    &BodyVector(Vector3::new(accel[0][l], accel[1][l], accel[2][l])),
                    dt,
                );
            }
            lanes.step(&gyro, &accel, dt);
        }
        for (l, single) in singles.iter().enumerate() {
            let (a, b) = (lanes.state(l), single.state());
            assert_eq!(a, b, "{scheme:?} lane {l}");
            assert!(a.position.0.iter().all(|v| v.is_finite()));
        }
    }
}
