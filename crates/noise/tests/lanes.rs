//! Several runs generated side by side (`ImuErrors::fill_static_lanes`, `fill_moving_lanes`) give
//! each run exactly the values of the run alone, bit for bit: for every shipped sensor, a fitted
//! model of the shape `imudrift diagnose` writes (flicker, random walk, resonance, sinusoid,
//! outliers, output filters), lanes whose levels differ, and lanes whose terms differ (which run
//! one after the other). With AVX2 the flicker bank and the terms fused with it run four runs in
//! one SIMD loop; without, each run alone: both must give these bits.

mod common;

use nalgebra::Vector3;
use noise::{ImuErrors, SensorModel};

/// A fitted ADIS16405-like model: every raw pass of the generator (bank with walk and resonance,
/// bank with resonance, bank with walk, bank alone, terms alone) behind FIR and IIR output filters
/// with decimation, and a Gauss-Markov term.
fn fitted(scale: f64, ax_resonance: bool) -> SensorModel {
    let resonance = if ax_resonance {
        r#"resonance = { sigma = "855.56 ug", frequency = "10.892 Hz", bandwidth = "0.10968 Hz" }"#
    } else {
        ""
    };
    let text = format!(
        r#"
name = "fitted"
[gyro.x]
white_noise = "{wn} deg/s/sqrt(Hz)"
turn_on_bias = "3 deg/s"
bias_instability = {{ value = "0.0081586 deg/s", convention = "ieee", band = ["0.1 s", "100000 s"], per_decade = 1 }}
output_filter = {{ kind = "bartlett", taps = 3, decimation = 2 }}

[gyro.y]
white_noise = "0.042615 deg/s/sqrt(Hz)"
bias_instability = {{ value = "{bi} deg/s", convention = "ieee", band = ["0.1 s", "100000 s"], per_decade = 2 }}
rate_random_walk = "{rrw} deg/s/sqrt(s)"

[gyro.z]
white_noise = "0.037392 deg/s/sqrt(Hz)"
bias_instability = {{ value = "0.010451 deg/s", convention = "ieee", band = ["0.1 s", "100000 s"], per_decade = 1 }}
output_filter = {{ kind = "lowpass2", cutoff = "43.452 Hz", decimation = 1 }}
resonance = {{ sigma = "{res} deg/s", frequency = "20.368 Hz", bandwidth = "0.23429 Hz" }}

[accel.x]
white_noise = "0.45306 mg/sqrt(Hz)"
rate_random_walk = "{rrw_a} ug/sqrt(h)"
bias_instability = {{ value = "375.68 ug", convention = "ieee", band = ["0.1 s", "100000 s"], per_decade = 1 }}
sinusoidal = {{ amplitude = "915.2 ug", frequency = "0.6008 Hz" }}
output_filter = {{ kind = "bartlett", taps = 3, decimation = 2 }}
{resonance}

[accel.y]
white_noise = "0.36865 mg/sqrt(Hz)"
rate_random_walk = "1505 ug/sqrt(h)"
bias_instability = {{ value = "285.12 ug", convention = "ieee", band = ["0.01 s", "100000 s"], per_decade = 3 }}
output_filter = {{ kind = "bartlett", taps = 13, decimation = 8 }}
outliers = {{ rate = "79.2 /h", size = "26640 ug" }}
resonance = {{ sigma = "473.5 ug", frequency = "10.53 Hz", bandwidth = "0.08031 Hz" }}

[accel.z]
white_noise = "0.46285 mg/sqrt(Hz)"
bias_instability = {{ value = "300.61 ug", convention = "ieee", band = ["0.1 s", "100000 s"], per_decade = 1 }}
gauss_markov = {{ sigma = "300 ug", time_constant = "20 s" }}
resonance = {{ sigma = "276.3 ug", frequency = "9.5469 Hz", bandwidth = "0.054555 Hz" }}
output_filter = {{ kind = "lowpass1", cutoff = "30 Hz", decimation = 4 }}
"#,
        wn = 0.04039 * scale,
        bi = 0.010451 * scale,
        rrw = 2.5e-4 * scale,
        res = 0.25486 * scale,
        rrw_a = 2066.0 * scale,
    );
    SensorModel::from_toml_str(&text, "fitted").expect("the test model parses")
}

type Ideal = (Vector3<f64>, Vector3<f64>);

/// Run `run` of `model` alone, `n` samples per channel in one block.
fn alone(model: &SensorModel, run: u64, n: usize, ideal: &[Ideal]) -> Vec<Vec<f64>> {
    let mut e = ImuErrors::new(model, 0.01, 7, run);
    let mut out = vec![vec![0.0; n]; 6];
    let (g, a): (Vec<_>, Vec<_>) = ideal[..n].iter().copied().unzip();
    let [o0, o1, o2, o3, o4, o5] = &mut out[..] else {
        unreachable!()
    };
    e.fill_moving(0, &g, &a, [o0, o1, o2, o3, o4, o5]);
    out
}

/// Runs `first..` of `models` (lane l: `models[l]`) side by side in blocks of mixed lengths.
fn side_by_side(
    models: &[&SensorModel],
    first: u64,
    n: usize,
    ideal: Option<&[Ideal]>,
) -> Vec<Vec<Vec<f64>>> {
    let mut errors: Vec<ImuErrors> = models
        .iter()
        .enumerate()
        .map(|(l, m)| ImuErrors::new(m, 0.01, 7, first + l as u64))
        .collect();
    let mut out = vec![vec![vec![0.0; n]; 6]; models.len()];
    let mut k = 0;
    for len in [1usize, 7, 256, 513, 4096, 100].iter().cycle() {
        if k >= n {
            break;
        }
        let end = (k + len).min(n);
        let mut blocks: Vec<[&mut [f64]; 6]> = out
            .iter_mut()
            .map(|lane| {
                let [o0, o1, o2, o3, o4, o5] = &mut lane[..] else {
                    unreachable!()
                };
                [o0, o1, o2, o3, o4, o5].map(|o| &mut o[k..end])
            })
            .collect();
        match ideal {
            None => ImuErrors::fill_static_lanes(
                &mut errors,
                k as u64,
                &Vector3::zeros(),
                &Vector3::new(0.0, 0.0, -9.80665),
                &mut blocks,
            ),
            Some(ideal) => {
                let (g, a): (Vec<_>, Vec<_>) = ideal[k..end].iter().copied().unzip();
                ImuErrors::fill_moving_lanes(&mut errors, k as u64, &g, &a, &mut blocks)
            }
        }
        k = end;
    }
    out
}

fn assert_same_bits(lanes: &[Vec<Vec<f64>>], expect: &[Vec<Vec<f64>>], what: &str) {
    for (l, (a, b)) in lanes.iter().zip(expect).enumerate() {
        for (c, (x, y)) in a.iter().zip(b).enumerate() {
            let differ = x
                .iter()
                .zip(y)
                .position(|(p, q)| p.to_bits() != q.to_bits());
            assert!(
                differ.is_none(),
                "{what}: lane {l} channel {c} differs at sample {differ:?}"
            );
        }
    }
}

fn still(n: usize) -> Vec<Ideal> {
    vec![(Vector3::zeros(), Vector3::new(0.0, 0.0, -9.80665)); n]
}

/// Whether this CPU runs four lanes in SIMD (then the tests below must see the SIMD loops run).
fn simd() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Blocks this thread ran through the four-run SIMD loops (noise terms, filters).
fn simd_blocks() -> (u64, u64) {
    #[cfg(target_arch = "x86_64")]
    {
        noise::simd_blocks()
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        (0, 0)
    }
}

#[test]
fn every_lane_equals_its_run_alone() {
    let n = 12_000;
    let mut models: Vec<(String, SensorModel)> =
        ["mtx", "adis16405", "bmi088", "gg1320an", "gg5300"]
            .iter()
            .map(|s| (s.to_string(), common::shipped_model(&format!("{s}.toml"))))
            .collect();
    models.push(("fitted".into(), fitted(1.0, true)));
    for (name, model) in &models {
        for lanes in [1usize, 2, 3, 4, 5, 8] {
            let ms = vec![model; lanes];
            let before = simd_blocks();
            let got = side_by_side(&ms, 11, n, None);
            let after = simd_blocks();
            if simd() && lanes >= 4 && name == "fitted" {
                // The fitted model has fused passes and filters on every channel: both loops ran.
                assert!(
                    after.0 > before.0 && after.1 > before.1,
                    "{lanes} lanes: the SIMD loops did not run ({before:?} -> {after:?})"
                );
            }
            if lanes < 4 {
                assert_eq!(before, after, "{lanes} lanes cannot run four at a time");
            }
            let expect: Vec<_> = (0..lanes as u64)
                .map(|l| alone(model, 11 + l, n, &still(n)))
                .collect();
            assert_same_bits(&got, &expect, &format!("{name}, {lanes} lanes"));
        }
    }
}

#[test]
fn lanes_with_other_levels_or_other_terms_equal_their_runs_alone() {
    let n = 9_000;
    let (a, b, c) = (fitted(1.0, true), fitted(1.7, true), fitted(0.6, false));
    for ms in [
        vec![&a, &b, &a, &b],
        vec![&a, &c, &b, &a],
        vec![&c, &a, &a, &a, &b],
    ] {
        let got = side_by_side(&ms, 3, n, None);
        let expect: Vec<_> = ms
            .iter()
            .enumerate()
            .map(|(l, m)| alone(m, 3 + l as u64, n, &still(n)))
            .collect();
        assert_same_bits(&got, &expect, "mixed lanes");
    }
}

#[test]
fn moving_lanes_equal_their_runs_alone() {
    let n = 6_000;
    let ideal: Vec<Ideal> = (0..n)
        .map(|k| {
            let t = k as f64 * 0.01;
            (
                Vector3::new(0.3 * t.sin(), 0.1, -0.2 * t.cos()),
                Vector3::new(0.5 * t.cos(), 0.2 * t, -9.80665),
            )
        })
        .collect();
    let model = fitted(1.0, true);
    let ms = vec![&model; 4];
    let got = side_by_side(&ms, 0, n, Some(&ideal));
    let expect: Vec<_> = (0..4).map(|l| alone(&model, l, n, &ideal)).collect();
    assert_same_bits(&got, &expect, "moving");
}
