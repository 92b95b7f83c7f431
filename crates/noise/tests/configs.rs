//! The shipped sensor configs load, carry their spec-sheet values in SI, and round-trip.

use noise::closed_form::FLICKER_PLATEAU_PER_B;
use noise::{BiasInstability, SensorModel};
use std::f64::consts::PI;

fn load(name: &str) -> SensorModel {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../configs/sensors")
        .join(name);
    SensorModel::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn rel(a: f64, b: f64) -> f64 {
    (a / b - 1.0).abs()
}

/// Minimum of the closed-form ADEV over the flicker band's plateau [30 tau_min, tau_max / 30].
fn adev_minimum(axis: &noise::AxisModel) -> f64 {
    let Some(BiasInstability::Flicker(f)) = axis.get::<noise::BiasInstability>() else {
        panic!("flicker expected");
    };
    let (lo, hi) = (30.0 * f.tau_min_s(), f.tau_max_s() / 30.0);
    (0..=1000)
        .map(|i| lo * (hi / lo).powf(i as f64 / 1000.0))
        .map(|tau| axis.allan_variance(tau).sqrt())
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn every_config_round_trips() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/sensors");
    let mut count = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let m = SensorModel::load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(
                SensorModel::from_toml_str(&m.to_toml_string(), "rt").unwrap(),
                m
            );
            count += 1;
        }
    }
    assert!(count >= 4);
}

#[test]
fn mtx_matches_woodman_table_4() {
    let m = load("mtx.toml");
    for (axis, (arw, bi)) in
        m.gyro
            .axes
            .iter()
            .zip([(0.075, 0.010), (0.078, 0.009), (0.079, 0.012)])
    {
        assert!(
            rel(
                axis.get::<noise::WhiteNoise>()
                    .map(noise::WhiteNoise::density)
                    .unwrap(),
                arw * PI / 180.0
            ) < 1e-12
        );
        // Woodman's bias instability is the minimum of the whole curve.
        assert!(rel(adev_minimum(axis), bi * PI / 180.0) < 1e-3);
    }
    for axis in &m.accel.axes {
        assert!(
            rel(
                axis.get::<noise::WhiteNoise>()
                    .map(noise::WhiteNoise::density)
                    .unwrap(),
                0.004
            ) < 1e-12
        );
    }
}

#[test]
fn honeywell_and_adis_values() {
    let gg1320 = load("gg1320an.toml");
    let gg5300 = load("gg5300.toml");
    let adis = load("adis16405.toml");
    let deg_h = PI / 180.0 / 3600.0;
    for axis in 0..3 {
        // 0.0035 deg/sqrt(h) = 0.0035/60 deg/sqrt(s) (docs/model.md §2).
        assert!(
            rel(
                gg1320.gyro.axes[axis]
                    .get::<noise::WhiteNoise>()
                    .map(noise::WhiteNoise::density)
                    .unwrap(),
                0.0035 / 60.0 * PI / 180.0
            ) < 1e-12
        );
        assert!(
            rel(
                gg5300.gyro.axes[axis]
                    .get::<noise::WhiteNoise>()
                    .map(noise::WhiteNoise::density)
                    .unwrap(),
                0.2 / 60.0 * PI / 180.0
            ) < 1e-12
        );
        assert!(
            rel(
                adis.gyro.axes[axis]
                    .get::<noise::WhiteNoise>()
                    .map(noise::WhiteNoise::density)
                    .unwrap(),
                0.05 * PI / 180.0
            ) < 1e-12
        );
        assert!(
            rel(
                adis.gyro.axes[axis]
                    .get::<noise::TurnOnBias>()
                    .map(noise::TurnOnBias::sigma)
                    .unwrap(),
                3.0 * PI / 180.0
            ) < 1e-12
        );
        assert!(rel(adev_minimum(&gg1320.gyro.axes[axis]), 0.0035 * deg_h) < 1e-3);
        assert!(rel(adev_minimum(&gg5300.gyro.axes[axis]), 70.0 * deg_h) < 1e-3);
        assert!(rel(adev_minimum(&adis.gyro.axes[axis]), 0.007 * PI / 180.0) < 1e-3);
        // With white noise only besides flicker, B is close to minimum / 0.664.
        let Some(BiasInstability::Flicker(f)) =
            gg5300.gyro.axes[axis].get::<noise::BiasInstability>()
        else {
            panic!("flicker expected");
        };
        assert!(rel(f.b() * FLICKER_PLATEAU_PER_B, 70.0 * deg_h) < 0.05);
    }
}
