//! Unit tests of the sensor config.

use super::allan_minimum::model_adev_minimum;
use super::*;
use crate::closed_form as cf;

const BASIC: &str = r#"
name = "test"
[gyro.all]
white_noise = "0.075 deg/sqrt(s)"
[gyro.x]
bias_instability = { value = "0.010 deg/s", convention = "allan_minimum" }
rate_random_walk = "2e-4 deg/s/sqrt(s)"
[gyro.y]
white_noise = "0.1 deg/sqrt(s)"
"#;

#[test]
fn all_table_applies_unless_axis_overrides() {
    let m = SensorModel::from_toml_str(BASIC, "basic.toml").unwrap();
    let n = 0.075f64.to_radians();
    assert!((m.gyro.axes[0].white_noise.unwrap() - n).abs() < 1e-15);
    assert!((m.gyro.axes[1].white_noise.unwrap() - 0.1f64.to_radians()).abs() < 1e-15);
    assert!((m.gyro.axes[2].white_noise.unwrap() - n).abs() < 1e-15);
    assert!(m.accel.axes.iter().all(|a| a.effects().is_empty()));
}

#[test]
fn allan_minimum_convention_reproduces_the_minimum() {
    let m = SensorModel::from_toml_str(BASIC, "basic.toml").unwrap();
    let axis = &m.gyro.axes[0];
    let Some(BiasInstability::Flicker(f)) = &axis.bias_instability else {
        panic!("flicker expected")
    };
    let (min, _) = model_adev_minimum(axis, f);
    assert!((min / 0.010f64.to_radians() - 1.0).abs() < 1e-9);
    // B is smaller than min/0.664: white noise and RRW contribute to the minimum too.
    let min_only = 0.010f64.to_radians() / cf::FLICKER_PLATEAU_PER_B;
    assert!(f.b < min_only, "B {} vs min/0.664 {}", f.b, min_only);
}

#[test]
fn round_trip_through_toml_is_exact() {
    let text = r#"
name = "full \"quoted\""
description = "every term"
[temperature]
profile = "ramp"
start = "10 degC"
rate = "0.01 degC/s"
end = "40 degC"
reference = "20 degC"
[gyro.all]
quantization = "0.001 deg"
white_noise = "0.2 deg/sqrt(h)"
bias_instability = { value = "70 deg/h", convention = "ieee", band = ["0.5 s", "1e4 s"], per_decade = 3 }
rate_random_walk = "1 deg/h/sqrt(h)"
rate_ramp = "1 deg/h/h"
gauss_markov = { sigma = "0.01 deg/s", time_constant = "30 s" }
sinusoidal = { amplitude = "0.01 deg/s", frequency = "0.2 Hz", phase = "10 deg" }
temperature_bias = "0.01 deg/s/degC"
constant_bias = "-0.3 deg/s"
turn_on_bias = "3 deg/s"
scale_factor = "300 ppm"
misalignment = ["0.5 mrad", "-1 mrad"]
[accel.z]
white_noise = "40 ug/sqrt(Hz)"
bias_instability = { model = "random_walk", stability = "36 ug", period = "800 s" }
sinusoidal = { amplitude = "1 mg", frequency = "2 Hz" }
"#;
    let m = SensorModel::from_toml_str(text, "full.toml").unwrap();
    let back = SensorModel::from_toml_str(&m.to_toml_string(), "written.toml").unwrap();
    assert_eq!(m, back);
    for profile in [
        "profile = \"constant\"\nvalue = \"21 degC\"",
        "profile = \"warmup\"\nstart = \"20 degC\"\nend = \"35 degC\"\ntime_constant = \"10 min\"",
        "profile = \"sinusoid\"\nmean = \"25 degC\"\namplitude = \"2 degC\"\nperiod = \"1 h\"",
    ] {
        let text = format!("name = \"t\"\n[temperature]\n{profile}\n");
        let m = SensorModel::from_toml_str(&text, "t.toml").unwrap();
        assert_eq!(
            SensorModel::from_toml_str(&m.to_toml_string(), "w").unwrap(),
            m
        );
    }
}

fn err(text: &str) -> String {
    SensorModel::from_toml_str(text, "bad.toml")
        .unwrap_err()
        .to_string()
}

#[test]
fn bad_configs_name_file_key_and_expectation() {
    let e = err("name = \"b\"\n[gyro.x]\nwhite_noize = \"1 deg/sqrt(h)\"\n");
    assert!(
        e.contains("bad.toml") && e.contains("white_noize") && e.contains("line 3"),
        "{e}"
    );
    let e = err("name = \"b\"\n[gyro.x]\nwhite_noise = \"1 deg/h\"\n");
    assert!(e.starts_with("bad.toml:3: key `gyro.x.white_noise`"), "{e}");
    assert!(
        e.contains("bad.toml") && e.contains("gyro.x.white_noise") && e.contains("rad/s/sqrt(Hz)"),
        "{e}"
    );
    let e = err("name = \"b\"\n[accel.all]\nwhite_noise = \"-1 ug/sqrt(Hz)\"\n");
    assert!(
        e.contains("accel.all.white_noise") && e.contains(">= 0"),
        "{e}"
    );
    let e = err("name = \"b\"\n[gyro.z]\nconstant_bias = \"NaN deg/s\"\n");
    assert!(e.contains("gyro.z.constant_bias"), "{e}");
    let e = err("name = \"b\"\n[gyro.z]\nconstant_bias = \"nan deg/s\"\n");
    assert!(e.contains("gyro.z.constant_bias"), "{e}");
    let e = err("name = \"b\"\n[gyro.z]\nbias_instability = { value = \"1 deg/h\" }\n");
    assert!(
        e.contains("gyro.z.bias_instability.convention") && e.contains("allan_minimum"),
        "{e}"
    );
    let e = err("name = \"b\"\n[gyro.z]\nwhite_noise = \"1 deg/sqrt(s)\"\nbias_instability = { value = \"1 deg/h\", convention = \"allan_minimum\" }\n");
    assert!(
        e.contains("gyro.z.bias_instability.value") && e.contains("above what the other terms"),
        "{e}"
    );
    let e = err(
        "name = \"b\"\n[gyro.z]\ngauss_markov = { sigma = \"1 deg/s\", time_constant = \"0 s\" }\n",
    );
    assert!(
        e.contains("gyro.z.gauss_markov.time_constant") && e.contains("> 0"),
        "{e}"
    );
    let e = err("name = \"b\"\n[temperature]\nprofile = \"warmup\"\nstart = \"20 degC\"\n");
    assert!(e.contains("temperature.end"), "{e}");
    let e = err("name = \"b\"\n[temperature]\nprofile = \"constant\"\nvalue = \"20 degC\"\nrate = \"1 degC/s\"\n");
    assert!(e.contains("temperature.rate"), "{e}");
    let e = err("name = \"b\"\n[temperature]\nprofile = \"ramp\"\nstart = \"30 degC\"\nrate = \"0.1 degC/s\"\nend = \"20 degC\"\n");
    assert!(e.starts_with("bad.toml:6: key `temperature.end`"), "{e}");
    let e = err("name = \"b\"\n[gyro.x]\nmisalignment = [\"1 mrad\"]\n");
    assert!(e.contains("gyro.x.misalignment"), "{e}");
    let e = err("name = \"b\"\n[gyro.x]\nwhite_noise = 0.1\n");
    assert!(e.contains("bad.toml") && e.contains("string"), "{e}");
    let e = err("[gyro.x]\n");
    assert!(e.contains("name"), "{e}");
}

#[test]
fn a_plain_bias_instability_is_the_allan_minimum_as_spec_sheets_quote_it() {
    let plain = "name = \"p\"\n[gyro.all]\nwhite_noise = \"0.05 deg/s/rtHz\"\nbias_instability = \"20 deg/h\"\n";
    let table = "name = \"p\"\n[gyro.all]\nwhite_noise = \"0.05 deg/s/sqrt(Hz)\"\nbias_instability = { value = \"20 deg/h\", convention = \"allan_minimum\" }\n";
    let a = SensorModel::from_toml_str(plain, "plain.toml").unwrap();
    let b = SensorModel::from_toml_str(table, "table.toml").unwrap();
    assert_eq!(a.gyro, b.gyro);
    // The error of a plain value too low for the axis names its line and key.
    let e = err("name = \"p\"\n[gyro.all]\nwhite_noise = \"0.05 deg/s/rtHz\"\nbias_instability = \"2 deg/h\"\n");
    assert!(
        e.contains("bad.toml:4: key `gyro.all.bias_instability.value`"),
        "{e}"
    );
}

#[test]
fn wrong_shapes_show_the_accepted_forms_with_an_example() {
    let e = err("name = \"b\"\n[gyro.all]\nwhite_noise = 0.05\n");
    assert!(
        e.contains("line 3") && e.contains("white_noise = \"0.05 deg/s/sqrt(Hz)\""),
        "{e}"
    );
    let e = err("name = \"b\"\n[gyro.all]\nbias_instability = 2\n");
    assert!(
        e.contains("line 3")
            && e.contains("bias_instability = \"10 deg/h\"")
            && e.contains("convention"),
        "{e}"
    );
    let e = err("[gyro.all]\nwhite_noise = \"1 deg/sqrt(h)\"\n");
    assert!(e.contains("name = \"My IMU\""), "{e}");
}

/// The styled writer: the input config's units, five significant digits, `[sensor.all]` when
/// the axes agree, no empty tables, no default temperature table; it loads back within the
/// rounding.
#[test]
fn styled_toml_keeps_the_input_units_and_loads_back() {
    let text = r#"
name = "styled"
[gyro.all]
white_noise = "0.05 deg/s/sqrt(Hz)"
bias_instability = { value = "0.007 deg/s", convention = "allan_minimum" }
[accel.x]
white_noise = "0.5 mg/sqrt(Hz)"
"#;
    let m = SensorModel::from_toml_str(text, "styled.toml").unwrap();
    let styled = m.to_toml_string_styled(&UnitStyle::from_config_text(text));
    assert!(
        styled.contains("[gyro.all]") && styled.contains("deg/s/sqrt(Hz)"),
        "{styled}"
    );
    assert!(
        styled.contains("[accel.x]") && styled.contains("mg/sqrt(Hz)"),
        "{styled}"
    );
    assert!(
        !styled.contains("[accel.y]") && !styled.contains("[temperature]"),
        "{styled}"
    );
    let back = SensorModel::from_toml_str(&styled, "back.toml").unwrap();
    let rel = |a: f64, b: f64| (a / b - 1.0).abs();
    for (a, b) in m.gyro.axes.iter().zip(&back.gyro.axes) {
        assert!(rel(a.white_noise.unwrap(), b.white_noise.unwrap()) < 5e-5);
    }
    assert!(
        rel(
            m.accel.axes[0].white_noise.unwrap(),
            back.accel.axes[0].white_noise.unwrap()
        ) < 5e-5
    );
    // Quantities the input does not use are written in spec-sheet units.
    let mut k = m.clone();
    k.gyro.axes[0].rate_random_walk = Some(1e-5);
    assert!(k
        .to_toml_string_styled(&UnitStyle::from_config_text(text))
        .contains("deg/h/sqrt(h)"));
}
