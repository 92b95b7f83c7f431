//! Monte Carlo throughput: whole runs of Woodman's MTx experiment (static, 100 Hz, 60 s) through
//! the deterministic runner, single-threaded, with the full MTx model and with white noise only.
//! Criterion reports time per run; steps per second = 6000 / (time per run).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use montecarlo::experiment::{Experiment, Overrides};
use montecarlo::run_range;
use montecarlo::scenario::Scenario;
use noise::{Effect, Sensor, TermSelector};

fn experiment(only: Option<Vec<TermSelector>>) -> Experiment {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    let text =
        std::fs::read_to_string(format!("{root}/configs/scenarios/mtx-static-60s.toml")).unwrap();
    let scenario = Scenario::from_toml_str(&text, "mtx-static-60s.toml").unwrap();
    let model = imudrift::files::sensor_model(std::path::Path::new(&format!(
        "{root}/configs/sensors/mtx.toml"
    )))
    .unwrap();
    Experiment::new(
        scenario,
        &model,
        &Overrides {
            only,
            ..Overrides::default()
        },
    )
    .unwrap()
}

fn bench(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut group = c.benchmark_group("mtx_static_60s_100hz");
    group.sample_size(10);
    const RUNS: u64 = 64;
    group.throughput(Throughput::Elements(RUNS * 6000));
    for (name, only) in [
        ("full_model", None),
        (
            "white_noise_only",
            Some(vec![
                TermSelector::term(Sensor::Gyro, Effect::WhiteNoise),
                TermSelector::term(Sensor::Accel, Effect::WhiteNoise),
            ]),
        ),
    ] {
        let exp = experiment(only);
        let kernel = exp.kernel();
        group.bench_function(name, |b| {
            b.iter(|| pool.install(|| run_range(&kernel, 0..RUNS, &|_| {})))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
