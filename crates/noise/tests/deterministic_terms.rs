//! Deterministic and per-run terms, stream independence, determinism.

mod common;

use common::*;
use nalgebra::Vector3;
use noise::{ImuErrors, SensorModel, TemperatureProfile, TriadModel};

#[test]
fn bias_scale_factor_and_misalignment_act_on_the_ideal_input() {
    let axis = |i: usize| {
        noise::AxisModel::default()
            .with(noise::ConstantBias::new(0.01 * (i as f64 + 1.0)).unwrap())
            .with(noise::ScaleFactor::new(1e-3 * (i as f64 + 1.0)).unwrap())
            .with(noise::Misalignment::new([2e-3, -3e-3]).unwrap())
    };
    let model = SensorModel {
        name: "det".into(),
        gyro: TriadModel {
            axes: [axis(0), axis(1), axis(2)],
        },
        accel: TriadModel {
            axes: [axis(0), axis(1), axis(2)],
        },
        ..SensorModel::default()
    };
    let mut e = ImuErrors::new(&model, 0.01, 1, 0);
    let w = Vector3::new(0.1, -0.2, 0.3);
    let f = Vector3::new(0.0, 0.0, -9.80665);
    let (g, a) = e.corrupt(0, &w, &f);
    // measured_i = (1 + s_i) ideal_i + m_i1 ideal_other1 + m_i2 ideal_other2 + b_i
    let expect = |v: &Vector3<f64>| {
        Vector3::new(
            1.001 * v.x + 2e-3 * v.y - 3e-3 * v.z + 0.01,
            1.002 * v.y + 2e-3 * v.x - 3e-3 * v.z + 0.02,
            1.003 * v.z + 2e-3 * v.x - 3e-3 * v.y + 0.03,
        )
    };
    assert!((g - expect(&w)).norm() < 1e-15);
    assert!((a - expect(&f)).norm() < 1e-14);
}

#[test]
fn turn_on_bias_is_drawn_once_per_run() {
    let sigma = 0.05;
    let axis = noise::AxisModel::default().with(noise::TurnOnBias::new(sigma).unwrap());
    let draws: Vec<f64> = (0..4000)
        .map(|run| {
            let y = gyro_x_series(&axis, 100.0, 50, 3, run);
            assert!(
                y.iter().all(|&v| v == y[0]),
                "turn-on bias changed within a run"
            );
            y[0]
        })
        .collect();
    assert_variance("turn-on bias across runs", &draws, sigma * sigma);
}

#[test]
fn temperature_bias_follows_the_profile() {
    let profiles = [
        TemperatureProfile::Constant { temp_c: 30.0 },
        TemperatureProfile::Ramp {
            start_c: 20.0,
            rate_c_per_s: 0.5,
            end_c: Some(30.0),
        },
        TemperatureProfile::Warmup {
            start_c: 20.0,
            end_c: 40.0,
            time_constant_s: 10.0,
        },
        TemperatureProfile::Sinusoid {
            mean_c: 25.0,
            amplitude_c: 3.0,
            period_s: 7.0,
        },
    ];
    let coefficient = 1e-3;
    for profile in profiles {
        let mut model = gyro_x_model(
            noise::AxisModel::default().with(noise::TemperatureBias::new(coefficient).unwrap()),
        );
        model.temperature = profile.clone();
        model.temperature_reference_c = 25.0;
        let dt = 0.1;
        let mut e = ImuErrors::new(&model, dt, 5, 0);
        for k in 0..400u64 {
            let t = k as f64 * dt;
            let (g, _) = e.corrupt(k, &Vector3::zeros(), &Vector3::zeros());
            let temp = e.temperature_c(k);
            assert_eq!(temp, profile.at(t));
            assert!((g.x - coefficient * (temp - 25.0)).abs() < 1e-15);
        }
        // Ends where the profile says.
        let end = profile.at(1e6);
        match profile {
            TemperatureProfile::Ramp { .. } => assert_eq!(end, 30.0),
            TemperatureProfile::Warmup { .. } => assert!((end - 40.0).abs() < 1e-12),
            _ => {}
        }
    }
}

#[test]
fn adding_a_term_does_not_reshuffle_the_others() {
    let white = noise::AxisModel::default().with(noise::WhiteNoise::new(1e-3).unwrap());
    let base = gyro_x_series(&white, 100.0, 10_000, 9, 4);
    let with_bias = gyro_x_series(
        &white.clone().with(noise::ConstantBias::new(0.5).unwrap()),
        100.0,
        10_000,
        9,
        4,
    );
    for (a, b) in base.iter().zip(&with_bias) {
        assert!((b - 0.5 - a).abs() < 1e-15);
    }
    // A term on another channel leaves this channel's bits alone.
    let mut model = gyro_x_model(white.clone());
    model.gyro.axes[1].set_term(noise::GaussMarkov::new(1.0, 1.0).unwrap());
    model.accel.axes[2].set_term(noise::WhiteNoise::new(1.0).unwrap());
    let mut e = ImuErrors::new(&model, 0.01, 9, 4);
    let mut other = vec![0.0; 10_000];
    e.channels_mut()[0].fill_static(0, &Vector3::zeros(), &mut other);
    assert!(base
        .iter()
        .zip(&other)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
    // Different runs and seeds differ.
    assert_ne!(base, gyro_x_series(&white, 100.0, 10_000, 9, 5));
    assert_ne!(base, gyro_x_series(&white, 100.0, 10_000, 10, 4));
}

#[test]
fn corrupt_and_channel_fill_give_the_same_bits() {
    let model = common::shipped_model("mtx.toml");
    let ideal = noise::StaticLevel::STANDARD.inputs();
    let mut a = ImuErrors::new(&model, 0.01, 42, 1);
    let mut b = a.clone();
    // 25 000 samples: the held flicker components (m = 10 .. 10 000 at 100 Hz) are updated within
    // them, and blocks of uneven lengths start and end between updates.
    const N: usize = 25_000;
    let mut cols = vec![vec![0.0; N]; 6];
    for (c, (ch, col)) in noise::Channel::ALL
        .into_iter()
        .zip(b.channels_mut().iter_mut().zip(cols.iter_mut()))
    {
        let mut k0 = 0;
        for len in [1, 7, 9_993, 3, 10_000, 4_996] {
            ch.fill_static(k0 as u64, &ideal[c], &mut col[k0..k0 + len]);
            k0 += len;
        }
        assert_eq!(k0, N);
    }
    let rows: Vec<_> = (0..N as u64)
        .map(|k| a.corrupt(k, &ideal[noise::Channel::Gx], &ideal[noise::Channel::Ax]))
        .collect();
    for (c, col) in cols.iter().enumerate() {
        for ((g, acc), v) in rows.iter().zip(col) {
            let got = if c < 3 { g[c] } else { acc[c - 3] };
            assert_eq!(got.to_bits(), v.to_bits());
        }
    }
}

/// A moving IMU in blocks (`fill_moving`, what the Monte Carlo runner runs) gives the bits of
/// `corrupt` sample by sample, with inputs that change every sample reaching the scale factor
/// and the output filter's zero-order hold (raw samples at 4x the output rate).
#[test]
fn fill_moving_gives_the_bits_of_corrupt() {
    let mut model = common::shipped_model("mtx.toml");
    for triad in [&mut model.gyro, &mut model.accel] {
        for axis in &mut triad.axes {
            axis.set_term(noise::ScaleFactor::new(3e-3).unwrap());
            axis.set_term(
                noise::OutputFilter::new(noise::FilterKind::Bartlett { taps: 9 }, 4).unwrap(),
            );
        }
    }
    const N: usize = 5_000;
    let input = |k: usize, s: f64| {
        let t = k as f64 * 0.01;
        Vector3::new(s * (0.7 * t).sin(), s * (1.3 * t).cos(), s + 0.1 * t)
    };
    let gyro: Vec<_> = (0..N).map(|k| input(k, 0.5)).collect();
    let accel: Vec<_> = (0..N).map(|k| input(k, 9.8)).collect();
    let mut a = ImuErrors::new(&model, 0.01, 42, 1);
    let mut b = a.clone();
    let mut cols = vec![vec![0.0; N]; 6];
    let mut k0 = 0;
    for len in [1, 255, 256, 3, 2_000, 2_485] {
        let [c0, c1, c2, c3, c4, c5] = &mut cols[..] else {
            unreachable!()
        };
        let r = k0..k0 + len;
        let out = [
            &mut c0[r.clone()],
            &mut c1[r.clone()],
            &mut c2[r.clone()],
            &mut c3[r.clone()],
            &mut c4[r.clone()],
            &mut c5[r.clone()],
        ];
        b.fill_moving(k0 as u64, &gyro[r.clone()], &accel[r], out);
        k0 += len;
    }
    assert_eq!(k0, N);
    for k in 0..N {
        let (g, acc) = a.corrupt(k as u64, &gyro[k], &accel[k]);
        for c in 0..6 {
            let got = if c < 3 { g[c] } else { acc[c - 3] };
            assert_eq!(
                got.to_bits(),
                cols[c][k].to_bits(),
                "channel {c}, sample {k}"
            );
        }
    }
}
