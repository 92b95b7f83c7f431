//! Diagnose benchmarks: the model band (16 simulated 6-channel static logs and their overlapping Allan
//! deviations) and the whole workflow on a 6-channel log with a hidden rate random walk on gx, both for
//! the ADIS16405 datasheet model (configs/sensors/adis16405.toml: white noise, 13-component flicker on the
//! gyros) at 100 Hz, 2^16 samples, and the drift protocol's dead reckoning of that log's segments. The
//! whole command on a 1 M-sample log is timed in docs/performance.md.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use diagnose::protocol::{all_segment_errors, Calibration, Initialisation, Protocol};
use diagnose::simulate::{simulate, static_log, SimSetup};
use diagnose::{diagnose, LogInput, Settings};
use noise::SensorModel;
use std::hint::black_box;

const SAMPLES: usize = 1 << 16;
const DT_S: f64 = 0.01;

fn adis() -> SensorModel {
    imudrift::files::sensor_model(
        &std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
            .join("configs/sensors/adis16405.toml"),
    )
    .expect("adis16405.toml")
}

fn setup(grid_m: Vec<usize>) -> SimSetup<'static> {
    SimSetup {
        dt_s: DT_S,
        samples: SAMPLES,
        grid_m,
        active: noise::ImuChannels([true; 6]),
        horizons_s: vec![60.0],
        temperature_c: None,
        temp_coeff: noise::ImuChannels::default(),
        latitude_deg: diagnose::protocol::Protocol::default().latitude_deg,
        stop: None,
    }
}

fn bench(c: &mut Criterion) {
    let model = adis();
    let mut truth = model.clone();
    truth.gyro.axes[0].set_term(noise::RateRandomWalk::new(5e-4).unwrap()); // crosses the white noise (N = 8.7e-4) at 3N^2/K^2 = 9 s
    let log = static_log(&truth, &setup(vec![]), 99, 0);
    let grid: Vec<usize> = (0..15).map(|j| 1usize << j).collect();
    let mut group = c.benchmark_group("diagnose_adis_2^16");
    group.sample_size(10);
    group.throughput(Throughput::Elements((SAMPLES * 6 * 16) as u64));
    group.bench_function("band_16_seeds_6_channels", |b| {
        let s = setup(grid.clone());
        b.iter(|| black_box(simulate(&model, &s, 1, 16).expect("simulates")))
    });
    group.throughput(Throughput::Elements((SAMPLES * 6) as u64));
    group.bench_function("whole_workflow_hidden_rrw", |b| {
        let input = LogInput {
            dt_s: DT_S,
            channels: noise::ImuChannels(log.0.each_ref().map(|c| Some(c.as_slice()))),
            temperature_c: None,
        };
        let settings = Settings {
            horizons_s: vec![60.0],
            ..Settings::default()
        };
        b.iter(|| black_box(diagnose(&input, &model, &settings).expect("diagnoses")))
    });
    group.finish();
    // The drift protocol on the same log (the dead reckoning of every segment, eight segments at
    // a time in the strapdown's lanes): 10 s and 60 s horizons, both protocols.
    let chans = log.0.each_ref().map(|c| Some(c.as_slice()));
    let mut group = c.benchmark_group("drift_protocol_2^16");
    group.sample_size(20);
    group.throughput(Throughput::Elements((SAMPLES * 2) as u64));
    for (name, protocol) in [
        ("log_mean_perfect_10s_60s", Protocol::default()),
        (
            "window_levelled_10s_60s",
            Protocol {
                calibration: Calibration::Window { window_s: 10.0 },
                initialisation: Initialisation::Levelled { window_s: 10.0 },
                ..Protocol::default()
            },
        ),
    ] {
        let protocol = Protocol {
            horizons_s: vec![10.0, 60.0],
            ..protocol
        };
        group.bench_function(name, |b| {
            b.iter(|| black_box(all_segment_errors(&chans, DT_S, &protocol)))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
