//! Unit tests of the sensor config.

use super::*;
use crate::closed_form as cf;
use crate::temperature::TemperatureProfile;
use crate::terms::bias_instability::model_adev_minimum;
use crate::terms::bias_instability::BiasInstability;
use crate::terms::outliers::Outliers;
use crate::terms::output_filter::{FilterKind, OutputFilter};
use crate::terms::warmup_transient::WarmupTransient;
use crate::terms::Effect;

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
    assert!(
        (m.gyro.axes[0]
            .get::<crate::WhiteNoise>()
            .map(crate::WhiteNoise::density)
            .unwrap()
            - n)
            .abs()
            < 1e-15
    );
    assert!(
        (m.gyro.axes[1]
            .get::<crate::WhiteNoise>()
            .map(crate::WhiteNoise::density)
            .unwrap()
            - 0.1f64.to_radians())
        .abs()
            < 1e-15
    );
    assert!(
        (m.gyro.axes[2]
            .get::<crate::WhiteNoise>()
            .map(crate::WhiteNoise::density)
            .unwrap()
            - n)
            .abs()
            < 1e-15
    );
    assert!(m.accel.axes.iter().all(|a| a.effects().is_empty()));
}

#[test]
fn allan_minimum_convention_reproduces_the_minimum() {
    let m = SensorModel::from_toml_str(BASIC, "basic.toml").unwrap();
    let axis = &m.gyro.axes[0];
    let Some(BiasInstability::Flicker(f)) = axis.get::<crate::BiasInstability>() else {
        panic!("flicker expected")
    };
    let (min, _) = model_adev_minimum(&|tau| axis.allan_variance(tau), f);
    assert!((min / 0.010f64.to_radians() - 1.0).abs() < 1e-9);
    // B is smaller than min/0.664: white noise and RRW contribute to the minimum too.
    let min_only = 0.010f64.to_radians() / cf::FLICKER_PLATEAU_PER_B;
    assert!(f.b() < min_only, "B {} vs min/0.664 {}", f.b(), min_only);
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
output_filter = { kind = "lowpass2", cutoff = "25 Hz", decimation = 4 }
outliers = { rate = "60 /h", size = "0.02 rad/s" }
warmup_transient = { amplitude = "5e-4 rad/s", time_constant = "10 min", per_run = true }
[accel.x]
output_filter = { kind = "moving_average", taps = 5 }
outliers = { rate = "3", size = "1.3 mg" }
[accel.y]
output_filter = { kind = "lowpass1", cutoff = "0.7 kHz", decimation = 3 }
outliers = { rate = "0.013 /s", size = "0.3 m/s^2" }
[accel.z]
white_noise = "40 ug/sqrt(Hz)"
bias_instability = { model = "random_walk", stability = "36 ug", period = "800 s" }
sinusoidal = { amplitude = "1 mg", frequency = "2 Hz" }
output_filter = { kind = "bartlett", taps = 8, decimation = 8 }
outliers = { rate = "0.7 /min", size = "0.5 mg" }
warmup_transient = { amplitude = "-2 mg", time_constant = "600 s" }
resonance = { sigma = "0.5 mg", frequency = "10 Hz", bandwidth = "700 mHz" }
"#;
    let m = SensorModel::from_toml_str(text, "full.toml").unwrap();
    let back = SensorModel::from_toml_str(&m.to_toml_string(), "written.toml").unwrap();
    assert_eq!(m, back);
    // The real-sensor effects as read.
    let g = &m.gyro.axes[1];
    assert_eq!(
        g.get::<crate::OutputFilter>().copied(),
        Some(OutputFilter::new(FilterKind::LowPass2 { cutoff_hz: 25.0 }, 4).unwrap())
    );
    assert_eq!(
        g.get::<crate::Outliers>().copied(),
        Some(Outliers::new(60.0, 0.02).unwrap())
    );
    assert_eq!(
        g.get::<crate::WarmupTransient>().copied(),
        Some(WarmupTransient::new(5e-4, 600.0, true).unwrap())
    );
    let [ax, ay, az] = &m.accel.axes;
    assert_eq!(
        ax.get::<crate::OutputFilter>().copied(),
        Some(OutputFilter::new(FilterKind::MovingAverage { taps: 5 }, 1).unwrap())
    );
    assert_eq!(
        ax.get::<crate::Outliers>()
            .copied()
            .unwrap()
            .rate_per_hour(),
        3.0
    );
    assert_eq!(
        ay.get::<crate::OutputFilter>().copied().unwrap().kind(),
        FilterKind::LowPass1 { cutoff_hz: 700.0 }
    );
    assert!(
        (ay.get::<crate::Outliers>()
            .copied()
            .unwrap()
            .rate_per_hour()
            / (0.013 * 3600.0)
            - 1.0)
            .abs()
            < 1e-15
    );
    assert!(
        (az.get::<crate::Outliers>()
            .copied()
            .unwrap()
            .rate_per_hour()
            / 42.0
            - 1.0)
            .abs()
            < 1e-15
    );
    let r = az.get::<crate::Resonance>().copied().unwrap();
    assert!((r.sigma() / (0.5e-3 * crate::units::STANDARD_GRAVITY_MPS2) - 1.0).abs() < 1e-15);
    assert_eq!(r.frequency_hz(), 10.0);
    assert!((r.bandwidth_hz() / 0.7 - 1.0).abs() < 1e-15);
    assert!(
        (az.get::<crate::Outliers>().copied().unwrap().size()
            / (0.5e-3 * crate::units::STANDARD_GRAVITY_MPS2)
            - 1.0)
            .abs()
            < 1e-15
    );
    assert_eq!(
        az.get::<crate::OutputFilter>().copied(),
        Some(OutputFilter::new(FilterKind::Bartlett { taps: 8 }, 8).unwrap())
    );
    let w = az.get::<crate::WarmupTransient>().copied().unwrap();
    assert!(w.amplitude() < 0.0 && w.tau_s() == 600.0 && !w.per_run());
    // Every new term written back, bit for bit, on every axis it is on.
    let written = m.to_toml_string();
    assert_eq!(written.matches("output_filter = ").count(), 6, "{written}");
    assert_eq!(written.matches("outliers = ").count(), 6, "{written}");
    assert_eq!(
        written.matches("warmup_transient = ").count(),
        4,
        "{written}"
    );
    for profile in [
        "profile = \"constant\"\nvalue = \"21 degC\"",
        "profile = \"warmup\"\nstart = \"20 degC\"\nend = \"35 degC\"\ntime_constant = \"10 min\"",
        "profile = \"sinusoid\"\nmean = \"25 degC\"\namplitude = \"2 degC\"\nperiod = \"1 h\"",
        "profile = \"step\"\nstart = \"20 degC\"\nend = \"31.5 degC\"\nat = \"15 min\"",
    ] {
        let text = format!("name = \"t\"\n[temperature]\n{profile}\n");
        let m = SensorModel::from_toml_str(&text, "t.toml").unwrap();
        if profile.contains("step") {
            assert_eq!(
                m.temperature,
                TemperatureProfile::Step {
                    before_c: 20.0,
                    after_c: 31.5,
                    at_s: 900.0
                }
            );
        }
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
fn bad_real_sensor_effects_name_the_key() {
    let axis = |line: &str| err(&format!("name = \"b\"\n[gyro.x]\n{line}\n"));
    let e = axis("output_filter = { kind = \"boxcar\", taps = 4 }");
    assert!(
        e.starts_with("bad.toml:3: key `gyro.x.output_filter.kind`")
            && e.contains("moving_average")
            && e.contains("\"boxcar\""),
        "{e}"
    );
    let e = axis("output_filter = { kind = \"bartlett\" }");
    assert!(
        e.contains("gyro.x.output_filter.taps") && e.contains("taps = 8"),
        "{e}"
    );
    let e = axis("output_filter = { kind = \"bartlett\", taps = 8, cutoff = \"25 Hz\" }");
    assert!(
        e.starts_with("bad.toml:3: key `gyro.x.output_filter.cutoff`")
            && e.contains("only `taps`")
            && e.contains("extra key"),
        "{e}"
    );
    let e = axis("output_filter = { kind = \"lowpass1\", cutoff = \"25 Hz\", taps = 8 }");
    assert!(
        e.contains("gyro.x.output_filter.taps") && e.contains("only `cutoff`"),
        "{e}"
    );
    let e = axis("output_filter = { kind = \"lowpass2\" }");
    assert!(
        e.contains("gyro.x.output_filter.cutoff") && e.contains("Hz"),
        "{e}"
    );
    let e = axis("output_filter = { kind = \"lowpass2\", cutoff = \"0 Hz\" }");
    assert!(
        e.contains("gyro.x.output_filter.cutoff") && e.contains("> 0"),
        "{e}"
    );
    let e = axis("output_filter = { kind = \"lowpass2\", cutoff = \"25 s\" }");
    assert!(
        e.contains("gyro.x.output_filter.cutoff") && e.contains("Hz"),
        "{e}"
    );
    let e = axis("output_filter = { kind = \"moving_average\", taps = 4, decimation = 0 }");
    assert!(
        e.starts_with("bad.toml:3: key `gyro.x.output_filter.decimation`")
            && e.contains(">= 1")
            && e.ends_with("found 0"),
        "{e}"
    );
    for taps in ["0", "-3", "9000"] {
        let e = axis(&format!(
            "output_filter = {{ kind = \"moving_average\", taps = {taps} }}"
        ));
        assert!(
            e.contains("gyro.x.output_filter.taps") && e.contains("1 to 8192"),
            "{e}"
        );
    }
    // Wrong types and unknown keys: serde's message, with the key and line.
    let e = axis("output_filter = { kind = \"bartlett\", taps = \"8\" }");
    assert!(
        e.contains("line 3") && e.contains("whole numbers without quotes"),
        "{e}"
    );
    let e = axis("output_filter = { kind = \"bartlett\", taps = 8, order = 2 }");
    assert!(e.contains("line 3") && e.contains("order"), "{e}");
    let e = axis("outliers = { rate = \"60 deg\", size = \"1 deg/s\" }");
    assert!(
        e.contains("gyro.x.outliers.rate") && e.contains("\"60 /h\""),
        "{e}"
    );
    let e = axis("outliers = { rate = \"-1 /h\", size = \"1 deg/s\" }");
    assert!(
        e.contains("gyro.x.outliers.rate") && e.contains(">= 0"),
        "{e}"
    );
    let e = axis("outliers = { rate = \"1 /h\", size = \"1 mg\" }");
    assert!(
        e.contains("gyro.x.outliers.size") && e.contains("rad/s"),
        "{e}"
    );
    let e = axis("outliers = { rate = \"1 /h\" }");
    assert!(e.contains("line 3") && e.contains("size"), "{e}");
    let e = axis("outliers = { rate = 60, size = \"1 deg/s\" }");
    assert!(e.contains("outliers = { rate = \"60 /h\""), "{e}");
    let e = axis("resonance = { sigma = \"1 deg/s\", frequency = \"2 Hz\", bandwidth = \"5 Hz\" }");
    assert!(
        e.contains("gyro.x.resonance.bandwidth")
            && e.contains("below twice the frequency")
            && e.contains("\"5 Hz\" with frequency \"2 Hz\""),
        "{e}"
    );
    let e = axis("resonance = { sigma = \"1 deg/s\", frequency = \"0 Hz\", bandwidth = \"1 Hz\" }");
    assert!(
        e.contains("gyro.x.resonance.frequency") && e.contains("> 0"),
        "{e}"
    );
    let e = axis("resonance = { sigma = \"1 deg/s\", frequency = \"2 Hz\" }");
    assert!(e.contains("line 3") && e.contains("bandwidth"), "{e}");
    let e = axis("warmup_transient = { amplitude = \"1 deg/s\", time_constant = \"0 s\" }");
    assert!(
        e.contains("gyro.x.warmup_transient.time_constant") && e.contains("> 0"),
        "{e}"
    );
    let e = axis("warmup_transient = { amplitude = \"1 deg/s\", time_constant = \"1 s\", per_run = \"yes\" }");
    assert!(e.contains("line 3") && e.contains("bool"), "{e}");
    let e = err(
        "name = \"b\"\n[temperature]\nprofile = \"step\"\nstart = \"20 degC\"\nend = \"30 degC\"\n",
    );
    assert!(
        e.contains("temperature.at") && e.contains("start, end, at"),
        "{e}"
    );
    let e = err("name = \"b\"\n[temperature]\nprofile = \"step\"\nstart = \"20 degC\"\nend = \"30 degC\"\nat = \"-1 s\"\n");
    assert!(e.starts_with("bad.toml:6: key `temperature.at`"), "{e}");
    let e = err("name = \"b\"\n[temperature]\nprofile = \"warmup\"\nstart = \"20 degC\"\nend = \"30 degC\"\ntime_constant = \"1 s\"\nat = \"1 s\"\n");
    assert!(
        e.contains("temperature.at") && e.contains("extra key"),
        "{e}"
    );
    let e = err("name = \"b\"\n[temperature]\nprofile = \"stair\"\n");
    assert!(e.contains("\"step\""), "{e}");
}

#[test]
fn outlier_rates_in_any_time_unit() {
    let rate = |text: &str| {
        SensorModel::from_toml_str(
            &format!("name = \"r\"\n[gyro.all]\noutliers = {{ rate = \"{text}\", size = \"1 deg/s\" }}\n"),
            "r.toml",
        )
        .unwrap()
        .gyro
        .axes[0].get::<crate::Outliers>().copied()
            .unwrap()
            .rate_per_hour()
    };
    for (text, per_hour) in [
        ("60 /h", 60.0),
        ("60/h", 60.0),
        ("60 1/h", 60.0),
        ("60 /hr", 60.0),
        ("60", 60.0),
        ("1 /min", 60.0),
        ("0.5 /s", 1800.0),
        ("0.5 Hz", 1800.0),
        ("2 h^-1", 2.0),
    ] {
        let r = rate(text);
        assert!((r / per_hour - 1.0).abs() < 1e-14, "{text}: {r}");
    }
    // A rate per hour keeps its bits.
    assert_eq!(rate("0.1 /h").to_bits(), 0.1f64.to_bits());
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
output_filter = { kind = "lowpass2", cutoff = "40 Hz", decimation = 10 }
outliers = { rate = "12 /h", size = "2 deg/s" }
[accel.x]
white_noise = "0.5 mg/sqrt(Hz)"
warmup_transient = { amplitude = "3 mg", time_constant = "5 min", per_run = true }
[accel.y]
output_filter = { kind = "bartlett", taps = 16 }
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
        !styled.contains("[accel.z]") && !styled.contains("[temperature]"),
        "{styled}"
    );
    assert!(
        styled.contains("cutoff = \"40 Hz\"")
            && styled.contains("rate = \"12 /h\"")
            && styled.contains("size = \"2 deg/s\"")
            && styled.contains("per_run = true")
            && styled.contains("kind = \"bartlett\", taps = 16, decimation = 1"),
        "{styled}"
    );
    let back = SensorModel::from_toml_str(&styled, "back.toml").unwrap();
    // Exact where five digits are exact: integers, round values.
    for i in 0..3 {
        assert_eq!(
            back.gyro.axes[i].get::<crate::OutputFilter>().copied(),
            m.gyro.axes[i].get::<crate::OutputFilter>().copied()
        );
        assert_eq!(
            back.gyro.axes[i].get::<crate::Outliers>().copied(),
            m.gyro.axes[i].get::<crate::Outliers>().copied()
        );
    }
    assert_eq!(
        back.accel.axes[1].get::<crate::OutputFilter>().copied(),
        m.accel.axes[1].get::<crate::OutputFilter>().copied()
    );
    let (wb, wm) = (
        back.accel.axes[0]
            .get::<crate::WarmupTransient>()
            .copied()
            .unwrap(),
        m.accel.axes[0]
            .get::<crate::WarmupTransient>()
            .copied()
            .unwrap(),
    );
    assert!(
        wb.per_run()
            && wb.tau_s() == wm.tau_s()
            && (wb.amplitude() / wm.amplitude() - 1.0).abs() < 5e-5
    );
    let rel = |a: f64, b: f64| (a / b - 1.0).abs();
    for (a, b) in m.gyro.axes.iter().zip(&back.gyro.axes) {
        assert!(
            rel(
                a.get::<crate::WhiteNoise>()
                    .map(crate::WhiteNoise::density)
                    .unwrap(),
                b.get::<crate::WhiteNoise>()
                    .map(crate::WhiteNoise::density)
                    .unwrap()
            ) < 5e-5
        );
    }
    assert!(
        rel(
            m.accel.axes[0]
                .get::<crate::WhiteNoise>()
                .map(crate::WhiteNoise::density)
                .unwrap(),
            back.accel.axes[0]
                .get::<crate::WhiteNoise>()
                .map(crate::WhiteNoise::density)
                .unwrap()
        ) < 5e-5
    );
    // The input's allan_minimum convention is kept (issue 24) and reads back to the same B: the
    // minimum is written to 5 digits (5e-5) and B moves by min^2 / (0.664 B)^2 times as much
    // (the other terms share the minimum; about 3 here), so 5e-4.
    assert!(
        styled.contains("convention = \"allan_minimum\""),
        "{styled}"
    );
    let flicker_b = |m: &SensorModel| match m.gyro.axes[0].get::<crate::BiasInstability>() {
        Some(crate::BiasInstability::Flicker(f)) => f.b(),
        _ => f64::NAN,
    };
    assert!(
        rel(flicker_b(&m), flicker_b(&back)) < 5e-4,
        "{} vs {}",
        flicker_b(&m),
        flicker_b(&back)
    );
    // Quantities the input does not use are written in spec-sheet units.
    let mut k = m.clone();
    k.gyro.axes[0].set_term(crate::RateRandomWalk::new(1e-5).unwrap());
    assert!(k
        .to_toml_string_styled(&UnitStyle::from_config_text(text))
        .contains("deg/h/sqrt(h)"));
}

#[test]
fn power_law_reads_writes_and_refuses() {
    let text = "name = \"p\"\n[accel.x]\npower_law = { alpha = -1.4, level = \"20 ug\", tau = \"100 s\" }\n[accel.y]\npower_law = { alpha = -1, level = \"3 ug\", band = [\"1 s\", \"1e4 s\"], per_decade = 3 }\n[gyro.z]\npower_law = { alpha = -0.35, level = \"2 deg/h\" }\n";
    let m = SensorModel::from_toml_str(text, "p.toml").unwrap();
    let p = m.accel.axes[0].get::<crate::PowerLaw>().unwrap();
    assert_eq!((p.alpha(), p.tau_ref_s(), p.per_decade()), (-1.4, 100.0, 1));
    assert!((p.level() / (20e-6 * crate::units::STANDARD_GRAVITY_MPS2) - 1.0).abs() < 1e-12);
    let q = m.accel.axes[1].get::<crate::PowerLaw>().unwrap();
    assert_eq!(
        (
            q.alpha(),
            q.tau_ref_s(),
            q.tau_min_s(),
            q.tau_max_s(),
            q.per_decade()
        ),
        (-1.0, 1.0, 1.0, 1e4, 3)
    );
    // Written and read back bit for bit, in SI and in the config's own units.
    let back = SensorModel::from_toml_str(&m.to_toml_string(), "written.toml").unwrap();
    assert_eq!(m, back);
    let styled = m.to_toml_string_styled(&UnitStyle::from_config_text(text));
    assert!(
        styled.contains("alpha = -1.4") && styled.contains("ug"),
        "{styled}"
    );
    let back = SensorModel::from_toml_str(&styled, "styled.toml").unwrap();
    let b = back.accel.axes[0].get::<crate::PowerLaw>().unwrap();
    assert_eq!(b.alpha(), -1.4);
    assert!((b.level() / p.level() - 1.0).abs() < 1e-4);

    let axis = |line: &str| err(&format!("name = \"b\"\n[accel.x]\n{line}\n"));
    let e = axis("power_law = { alpha = -2.0, level = \"20 ug\" }");
    assert!(
        e.starts_with("bad.toml:3: key `accel.x.power_law.alpha`") && e.contains("-1.9 to -0.1"),
        "{e}"
    );
    let e = axis("power_law = { alpha = 0.5, level = \"20 ug\" }");
    assert!(e.contains("accel.x.power_law.alpha"), "{e}");
    let e = axis("power_law = { alpha = -1.5 }");
    assert!(
        e.contains("accel.x.power_law.level") && e.contains("nothing"),
        "{e}"
    );
    let e = axis("power_law = { level = \"20 ug\" }");
    assert!(e.contains("accel.x.power_law.alpha"), "{e}");
    let e = axis("power_law = { alpha = -1.5, level = \"20 deg/h\" }");
    assert!(e.contains("accel.x.power_law.level"), "{e}");
    let e = axis("power_law = { alpha = -1.5, level = \"20 ug\", tau = \"3 ug\" }");
    assert!(e.contains("accel.x.power_law.tau"), "{e}");
    let e = axis("power_law = { alpha = -1.5, level = \"20 ug\", band = [\"10 s\", \"1 s\"] }");
    assert!(
        e.starts_with("bad.toml:3: key `accel.x.power_law.band`"),
        "{e}"
    );
    let e = axis("power_law = { alpha = -1.5, level = \"20 ug\", per_decade = 0 }");
    assert!(e.contains("accel.x.power_law.per_decade"), "{e}");
    let e = axis("power_law = { alpha = -1.5, level = \"20 ug\", slope = 1 }");
    assert!(e.contains("slope") && e.contains("line 3"), "{e}");
}

const SPREAD: &str = r#"
name = "spread"
[gyro.all]
white_noise = "0.2 deg/sqrt(h)"
bias_instability = { value = "7 deg/h", convention = "ieee" }
[gyro.z]
white_noise = "0.2 deg/sqrt(h)"
bias_instability = { value = "7 deg/h", convention = "ieee" }
rate_random_walk = "3 deg/h/sqrt(h)"
run_to_run = { rate_random_walk = 0.4, bias_instability = "30 %" }
[accel.all]
white_noise = "60 ug/sqrt(Hz)"
run_to_run = { white_noise = 0 }
"#;

/// `run_to_run` (docs/model.md §2.3): read per axis (or from `all`), in numbers or per cent,
/// written back exactly and in a config's style, and dropped with its term.
#[test]
fn run_to_run_reads_writes_and_round_trips() {
    let m = SensorModel::from_toml_str(SPREAD, "spread.toml").unwrap();
    let gz = &m.gyro.axes[2];
    assert_eq!(
        gz.run_to_run()
            .iter()
            .map(|(e, &s)| (*e, s))
            .collect::<Vec<_>>(),
        vec![
            (Effect::BiasInstability, 0.3),
            (Effect::RateRandomWalk, 0.4)
        ]
    );
    assert!(gz.varies_between_runs());
    assert!(m.gyro.axes[0].run_to_run().is_empty());
    assert_eq!(
        m.accel.axes[1].run_to_run().get(&Effect::WhiteNoise),
        Some(&0.0)
    );
    assert!(!m.accel.axes[1].varies_between_runs());
    let back = SensorModel::from_toml_str(&m.to_toml_string(), "w").unwrap();
    assert_eq!(back, m);
    let styled = m.to_toml_string_styled(&UnitStyle::from_config_text(SPREAD));
    assert!(
        styled.contains("run_to_run = { bias_instability = 0.3, rate_random_walk = 0.4 }"),
        "{styled}"
    );
    assert_eq!(
        SensorModel::from_toml_str(&styled, "s").unwrap().gyro.axes[2].run_to_run(),
        gz.run_to_run()
    );
    let mut no_rrw = gz.clone();
    no_rrw.remove(Effect::RateRandomWalk);
    assert_eq!(no_rrw.run_to_run().len(), 1);
    // A draw scales the listed levels by exp(s z - s^2) and drops the spreads.
    let z = 1.3;
    let drawn = gz.at_run_draws([z, z]);
    assert!(drawn.run_to_run().is_empty());
    let level = |a: &AxisModel, e: Effect| a.term(e).unwrap().level().unwrap().1;
    for (e, s) in [
        (Effect::RateRandomWalk, 0.4),
        (Effect::BiasInstability, 0.3),
    ] {
        let want = level(gz, e) * (s * z - s * s).exp();
        assert!((level(&drawn, e) / want - 1.0).abs() < 1e-12, "{e:?}");
    }
    assert_eq!(
        level(&drawn, Effect::WhiteNoise),
        level(gz, Effect::WhiteNoise)
    );
    // Two groups: a long-term term takes the first draw, a short-term one the second.
    let mut both = gz.clone();
    both.set_run_to_run(Effect::WhiteNoise, 0.2).unwrap();
    assert_eq!(both.varying_groups(), [true, true]);
    assert_eq!(gz.varying_groups(), [true, false]);
    let (z_long, z_short) = (1.3, -0.7);
    let drawn = both.at_run_draws([z_long, z_short]);
    let rrw = level(gz, Effect::RateRandomWalk) * (0.4 * z_long - 0.16f64).exp();
    let wn = level(gz, Effect::WhiteNoise) * (0.2 * z_short - 0.04f64).exp();
    assert!((level(&drawn, Effect::RateRandomWalk) / rrw - 1.0).abs() < 1e-12);
    assert!((level(&drawn, Effect::WhiteNoise) / wn - 1.0).abs() < 1e-12);
}

/// Bad spreads name the file, the line, the key and what was expected.
#[test]
fn bad_run_to_run_names_file_line_and_key() {
    let axis = |spread: &str| {
        err(&format!(
            "name = \"b\"\n[gyro.x]\nwhite_noise = \"1 deg/sqrt(h)\"\nrate_ramp = \"1 deg/h/h\"\nrun_to_run = {{ {spread} }}\n"
        ))
    };
    let e = axis("white_noize = 0.3");
    assert!(
        e.starts_with("bad.toml:5: key `gyro.x.run_to_run.white_noize`"),
        "{e}"
    );
    assert!(e.contains("not an effect"), "{e}");
    let e = axis("rate_random_walk = 0.3");
    assert!(
        e.starts_with("bad.toml:5: key `gyro.x.run_to_run.rate_random_walk`"),
        "{e}"
    );
    assert!(e.contains("has no `rate_random_walk`"), "{e}");
    for bad in [
        "white_noise = -0.1",
        "white_noise = 2.5",
        "white_noise = \"250 %\"",
        "white_noise = \"lots\"",
        "white_noise = true",
    ] {
        let e = axis(bad);
        assert!(
            e.starts_with("bad.toml:5: key `gyro.x.run_to_run.white_noise`"),
            "{bad}: {e}"
        );
        assert!(e.contains("a spread from 0 to 2"), "{bad}: {e}");
    }
    assert!(SensorModel::from_toml_str(
        "name = \"b\"\n[gyro.x]\nwhite_noise = \"1 deg/sqrt(h)\"\nrun_to_run = { white_noise = \"200 %\" }\n",
        "ok.toml"
    )
    .is_ok());
    // A term without a level (the output filter) has no spread.
    let e = err("name = \"b\"\n[gyro.x]\noutput_filter = { kind = \"moving_average\", taps = 4 }\nrun_to_run = { output_filter = 0.1 }\n");
    assert!(
        e.starts_with("bad.toml:4: key `gyro.x.run_to_run.output_filter`"),
        "{e}"
    );
    assert!(e.contains("a term with a level"), "{e}");
}
