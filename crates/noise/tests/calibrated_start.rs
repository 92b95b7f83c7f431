//! `ImuErrors::with_calibrated_start`: the flicker and Gauss-Markov bias processes referenced to
//! their value at t = 0 (b(t) - b(0)), the same draws, every other term unchanged.

use nalgebra::Vector3;
use noise::{AxisModel, BiasInstability, Flicker, GaussMarkov, ImuErrors, SensorModel, TriadModel};

fn model(axis: AxisModel) -> SensorModel {
    SensorModel {
        name: "calibrated".into(),
        gyro: TriadModel {
            axes: [axis.clone(), axis.clone(), axis.clone()],
        },
        accel: TriadModel {
            axes: [axis.clone(), axis.clone(), axis],
        },
        ..SensorModel::default()
    }
}

fn series(model: &SensorModel, calibrated: bool, n: usize) -> Vec<[f64; 6]> {
    let e = ImuErrors::new(model, 0.01, 7, 3);
    let mut e = if calibrated {
        e.with_calibrated_start()
    } else {
        e
    };
    let zero = Vector3::zeros();
    (0..n as u64)
        .map(|k| {
            let (g, a) = e.corrupt(k, &zero, &zero);
            [g.x, g.y, g.z, a.x, a.y, a.z]
        })
        .collect()
}

#[test]
fn slow_bias_processes_start_at_zero_and_keep_their_increments() {
    // Default flicker band 0.1 s .. 1e5 s at 100 Hz: the components of T >= 10 s are held
    // (multirate), so both the every-sample and the held parts are referenced.
    let slow = AxisModel {
        bias_instability: Some(BiasInstability::Flicker(Flicker::with_b(1e-3))),
        gauss_markov: Some(GaussMarkov::new(2e-3, 5.0).unwrap()),
        ..AxisModel::default()
    };
    let n = 3000;
    let raw = series(&model(slow.clone()), false, n);
    let cal = series(&model(slow), true, n);
    // b(0) - b(0) is exactly 0 (the offset is summed in the generator's own order).
    assert_eq!(cal[0], [0.0; 6]);
    for c in 0..6 {
        let b0 = raw[0][c];
        assert!(b0 != 0.0);
        for k in 0..n {
            // The same draws: calibrated = raw - b(0), up to rounding (each process subtracts
            // its own b(0); values ~1e-3, so 1e-16 is ~1e-13 relative, a few hundred ulps).
            assert!(
                (cal[k][c] - (raw[k][c] - b0)).abs() <= 1e-16,
                "channel {c} sample {k}"
            );
        }
    }
}

#[test]
fn other_terms_are_bit_identical() {
    // White noise and a random walk (already zero at the start): the switch changes nothing.
    let fast = AxisModel {
        white_noise: Some(1e-3),
        rate_random_walk: Some(1e-4),
        turn_on_bias: Some(1e-2),
        bias_instability: Some(BiasInstability::RandomWalk {
            stability: 1e-3,
            period_s: 4.0,
        }),
        ..AxisModel::default()
    };
    let m = model(fast);
    assert_eq!(series(&m, false, 500), series(&m, true, 500));
}
