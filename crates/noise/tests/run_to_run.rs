//! Run-to-run variation (docs/model.md §2.3): each run draws its levels of the listed terms, from
//! a stream no other draw uses, so a model without spreads (or with spreads of 0) gives the same
//! bits as before; runs side by side equal their runs alone; the per-run levels have the stated
//! log-normal spread and the model's mean square.

use nalgebra::Vector3;
use noise::{Effect, ImuErrors, SensorModel};

const BASE: &str = r#"
name = "spread"
[gyro.all]
white_noise = "0.3 deg/sqrt(h)"
bias_instability = { value = "5 deg/h", convention = "ieee" }
rate_random_walk = "3 deg/h/sqrt(h)"
[accel.all]
white_noise = "60 ug/sqrt(Hz)"
bias_instability = { value = "30 ug", convention = "ieee" }
"#;

fn model(extra_gz: &str, extra_ax: &str) -> SensorModel {
    let text = format!(
        "{BASE}\n[gyro.z]\nwhite_noise = \"0.3 deg/sqrt(h)\"\nbias_instability = {{ value = \"5 deg/h\", convention = \"ieee\" }}\nrate_random_walk = \"3 deg/h/sqrt(h)\"\n{extra_gz}\n[accel.x]\nwhite_noise = \"60 ug/sqrt(Hz)\"\nbias_instability = {{ value = \"30 ug\", convention = \"ieee\" }}\n{extra_ax}\n"
    );
    SensorModel::from_toml_str(&text, "spread.toml").expect("the test model parses")
}

/// `n` samples of every channel of run `run` (seed 5), static level, 100 Hz, one block per
/// `lanes` runs side by side when `lanes > 1`.
fn generate(models: &[&SensorModel], first: u64, n: usize) -> Vec<Vec<Vec<f64>>> {
    let mut errors: Vec<ImuErrors> = models
        .iter()
        .enumerate()
        .map(|(l, m)| ImuErrors::new(m, 0.01, 5, first + l as u64))
        .collect();
    let mut out = vec![vec![vec![0.0; n]; 6]; models.len()];
    let mut blocks: Vec<[&mut [f64]; 6]> = out
        .iter_mut()
        .map(|lane| {
            let [o0, o1, o2, o3, o4, o5] = &mut lane[..] else {
                unreachable!()
            };
            [o0, o1, o2, o3, o4, o5].map(|o| &mut o[..])
        })
        .collect();
    ImuErrors::fill_static_lanes(
        &mut errors,
        0,
        &Vector3::zeros(),
        &Vector3::new(0.0, 0.0, -9.80665),
        &mut blocks,
    );
    out
}

fn bits(v: &[Vec<f64>]) -> Vec<Vec<u64>> {
    v.iter()
        .map(|c| c.iter().map(|x| x.to_bits()).collect())
        .collect()
}

/// A spread of 0 changes no bit; a spread on gz changes gz only (the other channels' streams
/// are untouched); runs side by side (lanes whose levels differ) equal their runs alone.
#[test]
fn zero_spread_gives_the_same_bits_and_a_spread_moves_only_its_axis() {
    let n = 6_000;
    let plain = model("", "");
    let zero = model(
        "run_to_run = { rate_random_walk = 0, bias_instability = 0 }",
        "run_to_run = { white_noise = 0.0 }",
    );
    let spread = model(
        "run_to_run = { rate_random_walk = 0.5, bias_instability = \"30 %\" }",
        "",
    );
    for run in 0..3 {
        let a = generate(&[&plain], run, n);
        let b = generate(&[&zero], run, n);
        assert_eq!(
            bits(&a[0]),
            bits(&b[0]),
            "run {run}: zero spread changed bits"
        );
        let c = generate(&[&spread], run, n);
        for ch in [0, 1, 3, 4, 5] {
            assert_eq!(
                bits(&a[0][ch..ch + 1]),
                bits(&c[0][ch..ch + 1]),
                "channel {ch}"
            );
        }
        assert_ne!(bits(&a[0][2..3]), bits(&c[0][2..3]), "gz must differ");
    }
    let lanes = generate(&[&spread, &spread, &plain, &spread, &spread], 20, n);
    for (l, lane) in lanes.iter().enumerate() {
        let m = if l == 2 { &plain } else { &spread };
        let alone = generate(&[m], 20 + l as u64, n);
        assert_eq!(bits(lane), bits(&alone[0]), "lane {l}");
    }
}

/// Each run's white-noise level is drawn: with a spread s = 0.3 on gz's white noise only, the
/// per-run log of the sample standard deviation over 2000 samples has variance s^2 plus the
/// sampling part trigamma((n-1)/2)/4 ~ 1/(2(n-1)) (the log of a chi-square; about 2.5e-4), and
/// the mean over runs of the sample variance is the model's N^2/dt (the level written is the
/// RMS over power-ons). 400 runs. Tolerances 5 standard errors (false alarm about 6e-7 each):
/// the sample variance of 400 near-normal values has relative sd sqrt(2/399) = 7.1 %; the mean
/// of the per-run variances relative sd sqrt((e^{4 s^2} - 1)/400) = 3.3 % (the log-normal's).
#[test]
fn per_run_levels_have_the_stated_spread_and_mean_square() {
    let (runs, n, s) = (400u64, 2_000usize, 0.3f64);
    let m = {
        let text = format!("{BASE}\n[gyro.z]\nwhite_noise = \"0.3 deg/sqrt(h)\"\nrun_to_run = {{ white_noise = {s} }}\n");
        SensorModel::from_toml_str(&text, "wn.toml").unwrap()
    };
    assert_eq!(
        m.gyro.axes[2].run_to_run().get(&Effect::WhiteNoise),
        Some(&s)
    );
    let density = (0.3f64 / 60.0).to_radians();
    let per_sample_var = density * density / 0.01;
    let (mut logs, mut vars) = (Vec::new(), Vec::new());
    for run in 0..runs {
        let out = generate(&[&m], run, n);
        let gz = &out[0][2];
        let mean = gz.iter().sum::<f64>() / n as f64;
        let var = gz.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        logs.push(0.5 * var.ln());
        vars.push(var);
    }
    let r = runs as f64;
    let mean_log = logs.iter().sum::<f64>() / r;
    let var_log = logs.iter().map(|x| (x - mean_log).powi(2)).sum::<f64>() / (r - 1.0);
    let expected = s * s + 1.0 / (2.0 * (n - 1) as f64);
    assert!(
        (var_log / expected - 1.0).abs() < 5.0 * (2.0 / (r - 1.0)).sqrt(),
        "variance of ln sd {var_log} against {expected}"
    );
    let mean_var = vars.iter().sum::<f64>() / r;
    let sd_rel = (((4.0 * s * s).exp() - 1.0) / r).sqrt();
    assert!(
        (mean_var / per_sample_var - 1.0).abs() < 5.0 * sd_rel,
        "mean square {mean_var} against {per_sample_var}"
    );
}
