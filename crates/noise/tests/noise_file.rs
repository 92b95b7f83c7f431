//! Kalibr / OpenVINS / VINS-Fusion IMU noise files: the published EuRoC values read exactly, the
//! three flavours written and read back, and bad files named by line and key.

use noise::noise_file::{
    read_noise_file, write_noise_file, AxisValue, Flavor, Inflation, NoiseValues,
};
use noise::SensorModel;

/// The EuRoC MAV dataset's `imu0/sensor.yaml` (ADIS16448), as published with the dataset.
const EUROC: &str = "\
#Default imu sensor yaml file
sensor_type: imu
comment: VI-Sensor IMU (ADIS16448)

# Sensor extrinsics wrt. the body-frame.
T_BS:
  cols: 4
  rows: 4
  data: [1.0, 0.0, 0.0, 0.0,
         0.0, 1.0, 0.0, 0.0,
         0.0, 0.0, 1.0, 0.0,
         0.0, 0.0, 0.0, 1.0]
rate_hz: 200

# inertial sensor noise model parameters (static)
gyroscope_noise_density: 1.6968e-04     # [ rad / s / sqrt(Hz) ]   ( gyro \"white noise\" )
gyroscope_random_walk: 1.9393e-05       # [ rad / s^2 / sqrt(Hz) ] ( gyro bias diffusion )
accelerometer_noise_density: 2.0000e-3  # [ m / s^2 / sqrt(Hz) ]   ( accel \"white noise\" )
accelerometer_random_walk: 3.0000e-3    # [ m / s^3 / sqrt(Hz) ].  ( accel bias diffusion )
";

fn values(m: &SensorModel) -> [f64; 4] {
    let g = &m.gyro.axes;
    let a = &m.accel.axes;
    for axes in [g, a] {
        assert_eq!(axes[0], axes[1]);
        assert_eq!(axes[0], axes[2]);
    }
    [
        g[0].get::<noise::WhiteNoise>()
            .map(noise::WhiteNoise::density)
            .unwrap_or(0.0),
        g[0].get::<noise::RateRandomWalk>()
            .map(noise::RateRandomWalk::density)
            .unwrap_or(0.0),
        a[0].get::<noise::WhiteNoise>()
            .map(noise::WhiteNoise::density)
            .unwrap_or(0.0),
        a[0].get::<noise::RateRandomWalk>()
            .map(noise::RateRandomWalk::density)
            .unwrap_or(0.0),
    ]
}

#[test]
fn euroc_adis16448_values_are_read_exactly() {
    let m = read_noise_file(EUROC, "euroc/imu0/sensor.yaml").unwrap();
    assert_eq!(values(&m), [1.6968e-04, 1.9393e-05, 2.0000e-3, 3.0000e-3]);
    assert_eq!(m.name, "sensor");
    // Units: the noise density is the Allan deviation of the white noise at 1 s (N^2 / tau), and
    // the random walk adds K^2 tau / 3 (IEEE 952 Table A.1 / docs/model.md §2).
    let g = &m.gyro.axes[0];
    let n = 1.6968e-04f64;
    let k = 1.9393e-05f64;
    let expected = n * n / 1.0 + k * k * 1.0 / 3.0;
    assert!((g.allan_variance(1.0) - expected).abs() <= 1e-12 * expected);
    // Nothing else is modelled.
    assert!(
        g.get::<noise::BiasInstability>().cloned().is_none()
            && g.get::<noise::Quantization>()
                .map(noise::Quantization::coefficient)
                .is_none()
            && g.get::<noise::ConstantBias>()
                .map(noise::ConstantBias::bias)
                .is_none()
    );
}

fn axis(v: f64) -> AxisValue {
    AxisValue {
        value: v,
        how: "IEEE 952 fit".into(),
    }
}

fn sample() -> NoiseValues {
    NoiseValues {
        gyro_noise_density: [axis(1.1e-4), axis(1.3e-4), axis(1.2e-4)],
        gyro_random_walk: [axis(2.0e-6), axis(2.5e-6), axis(2.2e-6)],
        accel_noise_density: [axis(1.9e-3), axis(1.7e-3), axis(2.1e-3)],
        accel_random_walk: [axis(3.0e-4), axis(3.1e-4), axis(2.9e-4)],
        rostopic: "/imu0".into(),
        update_rate_hz: 200.0,
        origin: "a test".into(),
    }
}

#[test]
fn every_flavour_round_trips_with_the_worst_axis() {
    for flavor in [Flavor::Kalibr, Flavor::OpenVins, Flavor::VinsFusion] {
        let text = write_noise_file(&sample(), flavor, Inflation::NONE);
        let m = read_noise_file(&text, "imu.yaml").unwrap_or_else(|e| panic!("{text}\n{e}"));
        // Written with five significant digits: the worst axis of each value.
        assert_eq!(
            values(&m),
            [1.3e-4, 2.5e-6, 2.1e-3, 3.1e-4],
            "{}",
            flavor.name()
        );
        assert!(text.contains("worst axis"), "{text}");
        // Per-axis values in the comments.
        assert!(text.contains("x 1.1000e-04"), "{text}");
    }
    let kalibr = write_noise_file(&sample(), Flavor::Kalibr, Inflation::NONE);
    assert!(kalibr.contains("rostopic: /imu0") && kalibr.contains("update_rate: 200"));
    let openvins = write_noise_file(&sample(), Flavor::OpenVins, Inflation::NONE);
    assert!(openvins.starts_with("%YAML:1.0") && openvins.contains("imu0:\n  T_i_b:"));
    for key in [
        "model: \"calibrated\"",
        "Tw:",
        "R_IMUtoGYRO:",
        "Ta:",
        "R_IMUtoACC:",
        "Tg:",
        "time_offset: 0.0",
    ] {
        assert!(openvins.contains(key), "{key}\n{openvins}");
    }
    let vins = write_noise_file(&sample(), Flavor::VinsFusion, Inflation::NONE);
    assert!(vins.contains("gyr_n: 1.3000e-04") && vins.contains("acc_w: 3.1000e-04"));
    // PyYAML floats: a dot and a signed exponent.
    assert!(
        kalibr.contains("update_rate: 200") && !kalibr.contains("e-4 ") && !kalibr.contains("e4")
    );
}

#[test]
fn inflation_multiplies_the_written_values_and_says_so() {
    let text = write_noise_file(
        &sample(),
        Flavor::Kalibr,
        Inflation {
            factor: 10.0,
            setting: "margin",
        },
    );
    let m = read_noise_file(&text, "imu.yaml").unwrap();
    let v = values(&m);
    for (got, want) in v.iter().zip([1.3e-3, 2.5e-5, 2.1e-2, 3.1e-3]) {
        assert!((got - want).abs() <= 1e-12 * want, "{got} {want}");
    }
    assert!(text.contains("multiplied by 10 (margin)"), "{text}");
}

#[test]
fn bad_files_name_the_line_and_the_key() {
    let e = read_noise_file("gyroscope_noise_density: 1e-4\n", "a.yaml").unwrap_err();
    assert!(
        e.to_string().contains("a.yaml") && e.to_string().contains("gyroscope_random_walk"),
        "{e}"
    );
    let text = EUROC.replace("1.9393e-05", "fast");
    let e = read_noise_file(&text, "b.yaml").unwrap_err().to_string();
    assert!(
        e.starts_with("b.yaml:17:") && e.contains("gyroscope_random_walk") && e.contains("`fast`"),
        "{e}"
    );
    let text = EUROC.replace("2.0000e-3", "-2.0e-3");
    let e = read_noise_file(&text, "c.yaml").unwrap_err().to_string();
    assert!(e.contains("c.yaml:18") && e.contains(">= 0"), "{e}");
}

#[test]
fn a_noise_file_loads_wherever_a_sensor_toml_does() {
    let m = SensorModel::from_text(EUROC, "euroc.yaml").unwrap();
    assert_eq!(values(&m)[0], 1.6968e-04);
    let e = SensorModel::from_text("gyroscope_noise_density: x\n", "bad.yaml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("bad.yaml"), "{e}");
}

/// Issue 27, item 7: noise files are read as YAML. A duplicate key takes the last value (as YAML
/// does); a key inside a text block or under another section is not the IMU's; a byte-order
/// mark, a flow map, a quoted number and an anchor are read; OpenVINS's keys under `imu0:`.
#[test]
fn noise_files_are_read_as_yaml() {
    let v = |text: &str| {
        values(&read_noise_file(text, "y.yaml").unwrap_or_else(|e| panic!("{text}\n{e}")))
    };
    let four = "gyroscope_noise_density: 1.0e-4\ngyroscope_random_walk: 2.0e-5\naccelerometer_noise_density: 3.0e-3\naccelerometer_random_walk: 4.0e-4\n";
    let want = [1.0e-4, 2.0e-5, 3.0e-3, 4.0e-4];
    assert_eq!(v(four), want);
    // Duplicate: the last wins.
    assert_eq!(v(&format!("gyroscope_noise_density: 9.0e-1\n{four}")), want);
    // A key inside a text block, or under another section, is not the IMU's.
    let decoy = format!(
        "description: |\n  gyroscope_noise_density: 7.0\ncam0:\n  gyroscope_noise_density: 8.0\n{four}"
    );
    assert_eq!(v(&decoy), want);
    let only_decoys =
        "description: |\n  gyroscope_noise_density: 7.0\ncam0:\n  gyroscope_random_walk: 8.0\n";
    assert!(read_noise_file(only_decoys, "d.yaml").is_err());
    // Byte-order mark, flow map, quoted number, anchor and alias.
    assert_eq!(v(&format!("\u{feff}{four}")), want);
    let flow = "{gyroscope_noise_density: 1.0e-4, gyroscope_random_walk: \"2.0e-5\", accelerometer_noise_density: &a 3.0e-3, accelerometer_random_walk: 4.0e-4}\n";
    assert_eq!(v(flow), want);
    let alias = "base: &n 1.0e-4\ngyroscope_noise_density: *n\ngyroscope_random_walk: 2.0e-5\naccelerometer_noise_density: 3.0e-3\naccelerometer_random_walk: 4.0e-4\n";
    assert_eq!(v(alias), want);
    // OpenVINS: %YAML:1.0 and the keys under imu0.
    let openvins = format!(
        "%YAML:1.0\n\nimu0:\n{}",
        four.lines().map(|l| format!("  {l}\n")).collect::<String>()
    );
    assert_eq!(v(&openvins), want);
    // 1e400 is out of range, not "negative".
    let e = read_noise_file(&four.replace("1.0e-4", "1e400"), "r.yaml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("r.yaml:1") && e.contains("beyond the range"),
        "{e}"
    );
    // A 1 MB number is quoted by a prefix.
    let long = four.replace("1.0e-4", &"1".repeat(1 << 20));
    let e = read_noise_file(&long, "l.yaml").unwrap_err().to_string();
    assert!(e.len() < 400, "{} bytes", e.len());
}

/// Issue 27, item 7: reading is linear in the number of keys (20 k / 80 k keys took 0.2 / 4.5 s).
#[test]
fn many_keys_read_in_linear_time() {
    let mut text = String::new();
    for i in 0..80_000 {
        text += &format!("key_{i}: {i}\n");
    }
    text += "gyroscope_noise_density: 1.0e-4\ngyroscope_random_walk: 2.0e-5\naccelerometer_noise_density: 3.0e-3\naccelerometer_random_walk: 4.0e-4\n";
    let started = std::time::Instant::now();
    read_noise_file(&text, "big.yaml").unwrap();
    assert!(
        started.elapsed().as_secs_f64() < 2.0,
        "{:?}",
        started.elapsed()
    );
}

/// Reading stays linear when the keys sit deep in nested maps: 40 000 keys under 1 000 levels
/// of block maps each copied their whole path (4e7 strings; through the CLI, 1 500 levels and
/// 60 000 keys took 24 s and 5.2 GB) before only the top two levels, where an IMU's keys are,
/// were kept (0.19 s, 38 MB).
#[test]
fn deeply_nested_keys_read_in_linear_time() {
    let mut text = "gyroscope_noise_density: 1.0e-4\ngyroscope_random_walk: 2.0e-5\naccelerometer_noise_density: 3.0e-3\naccelerometer_random_walk: 4.0e-4\n".to_string();
    let depth = 1000;
    for i in 0..depth {
        text += &format!("{}a:\n", "  ".repeat(i));
    }
    let keys: Vec<String> = (0..40_000).map(|i| format!("k{i}: {i}")).collect();
    text += &format!("{}{{{}}}\n", "  ".repeat(depth), keys.join(", "));
    let started = std::time::Instant::now();
    let m = read_noise_file(&text, "deep.yaml").unwrap();
    assert_eq!(values(&m), [1.0e-4, 2.0e-5, 3.0e-3, 4.0e-4]);
    assert!(
        started.elapsed().as_secs_f64() < 2.0,
        "{:?}",
        started.elapsed()
    );
}
