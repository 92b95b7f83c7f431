//! Same seed, any thread count: the simulated band and drifts are bit-identical (docs/architecture.md, Randomness).

use diagnose::simulate::{simulate, SimResult, SimSetup};
use noise::{BiasInstability, Flicker, SensorModel};

fn run(threads: usize) -> SimResult {
    let mut model = SensorModel {
        name: "det".into(),
        ..Default::default()
    };
    for axis in model
        .gyro
        .axes
        .iter_mut()
        .chain(model.accel.axes.iter_mut())
    {
        axis.set_term(noise::WhiteNoise::new(1e-3).unwrap());
        axis.set_term(BiasInstability::Flicker(Flicker::with_b(1e-4).unwrap()));
        axis.set_term(noise::RateRandomWalk::new(1e-5).unwrap());
    }
    let setup = SimSetup {
        dt_s: 0.01,
        samples: 1 << 13,
        grid_m: (0..11).map(|j| 1usize << j).collect(),
        active: noise::ImuChannels([true; 6]),
        horizons_s: vec![10.0],
        temperature_c: None,
        temp_coeff: noise::ImuChannels::default(),
        latitude_deg: diagnose::protocol::Protocol::default().latitude_deg,
        stop: None,
    };
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(|| simulate(&model, &setup, 7, 20).unwrap())
}

fn bits(r: &SimResult) -> Vec<u64> {
    let mut out = Vec::new();
    for b in r.bands.values().iter().flatten() {
        for v in [&b.ln_mean, &b.ln_sd, &b.avar_mean, &b.adev_lo, &b.adev_hi] {
            out.extend(v.iter().map(|x| x.to_bits()));
        }
    }
    for d in &r.drift {
        out.extend(
            d.heading_rad
                .iter()
                .chain(&d.horizontal_m)
                .map(|x| x.to_bits()),
        );
    }
    out
}

#[test]
fn band_is_bit_identical_for_1_2_and_3_threads() {
    let one = bits(&run(1));
    assert!(!one.is_empty());
    assert_eq!(one, bits(&run(2)));
    assert_eq!(one, bits(&run(3)));
}

/// The drift check with the levels drawn by the parametric bootstrap and a run-to-run spread drawn
/// per replicate: the JSON of the whole check (every band, every drawn level's and spread's
/// quantiles) is the same text for 1, 2 and 3 threads; serde_json
/// writes every f64 in its shortest exact form, so equal text is equal bits.
#[test]
fn bootstrapped_drift_check_is_identical_for_1_2_and_3_threads() {
    use diagnose::drift_check::{check_drift_fitted, CheckSettings};
    use diagnose::fitted_on::FittedOn;
    use diagnose::protocol::Protocol;
    let model = SensorModel::from_toml_str(
        r#"
name = "det"
[gyro.all]
white_noise = "0.3 deg/sqrt(h)"
bias_instability = "5 deg/h"
rate_random_walk = "3 deg/h/sqrt(h)"
[accel.all]
white_noise = "60 ug/sqrt(Hz)"
bias_instability = "30 ug"
"#,
        "det.toml",
    )
    .unwrap();
    let setup = SimSetup::plain(0.1, 6_000, noise::ImuChannels([true; 6]));
    let logs: Vec<[Vec<f64>; 6]> = (0..2)
        .map(|run| diagnose::simulate::static_log(&model, &setup, 99, run).0)
        .collect();
    let inputs: Vec<diagnose::LogInput> = logs
        .iter()
        .map(|l| diagnose::LogInput {
            dt_s: 0.1,
            channels: noise::ImuChannels(l.each_ref().map(|c| Some(c.as_slice()))),
            temperature_c: None,
        })
        .collect();
    let fitted = FittedOn {
        sample_interval_s: 0.1,
        samples: vec![4_000, 3_000],
        channels: noise::ImuChannels([true; 6]),
        tau_min_s: 0.0,
        // A run-to-run spread estimated from the two runs: each replicate draws it too.
        run_to_run: vec![diagnose::fitted_on::SpreadFit {
            channel: noise::Channel::Gz,
            effects: vec![noise::Effect::RateRandomWalk],
            runs: 2,
            variance: 0.3,
            null_variance: 0.1,
        }],
    };
    let settings = CheckSettings {
        protocol: Protocol {
            horizons_s: vec![10.0, 60.0],
            ..Protocol::default()
        },
        replicates: 12,
        seed: 3,
    };
    let json = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let c = check_drift_fitted(&inputs, &model, Some(&fitted), &settings, &()).unwrap();
                let p = c.parameters.as_ref().unwrap();
                assert_eq!(p.run_to_run.len(), 1);
                assert!(p.run_to_run[0].p97_5 > p.run_to_run[0].p2_5);
                serde_json::to_string(&c).unwrap()
            })
    };
    let one = json(1);
    assert_eq!(one, json(2));
    assert_eq!(one, json(3));
}
