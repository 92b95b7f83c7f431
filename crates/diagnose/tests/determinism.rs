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
        axis.set_term(BiasInstability::Flicker(Flicker::with_b(1e-4)));
        axis.set_term(noise::RateRandomWalk::new(1e-5).unwrap());
    }
    let setup = SimSetup {
        dt_s: 0.01,
        samples: 1 << 13,
        grid_m: (0..11).map(|j| 1usize << j).collect(),
        active: [true; 6],
        horizons_s: vec![10.0],
        temperature_c: None,
        temp_coeff: [0.0; 6],
    };
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(|| simulate(&model, &setup, 7, 20).unwrap())
}

fn bits(r: &SimResult) -> Vec<u64> {
    let mut out = Vec::new();
    for b in r.bands.iter().flatten() {
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
