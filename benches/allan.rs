//! Allan deviation: the overlapping deviation of one 4.32 M-sample channel (12 h at 100 Hz) at
//! octave taus, in memory, with and without confidence intervals (noise identification +
//! Greenhall EDF + chi-squared bounds), and the IEEE 952 fit. Compare with
//! `scripts/bench_allantools.py`, which times allantools' `oadev` on the same kind of channel.

use allan::{DataKind, EdfMethod, Estimator, Options, TauGrid};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;

const SAMPLES: usize = 4_320_000;

/// White noise plus a slow random walk (SplitMix64 + Box-Muller; deterministic).
fn channel() -> Vec<f64> {
    let mut rng = testkit::SplitMix64::new(20261121);
    let mut walk = 0.0;
    (0..SAMPLES)
        .map(|_| {
            let g = rng.normal();
            walk += 3e-7 * g;
            0.01 + 1e-2 * g + walk
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let y = channel();
    let mut group = c.benchmark_group("allan_4.32M");
    group.throughput(Throughput::Elements(SAMPLES as u64));
    group.sample_size(10);
    let none = Options {
        edf: EdfMethod::None,
        ..Options::default()
    };
    group.bench_function("oadev_octave_no_ci", |b| {
        b.iter(|| {
            allan::deviation_with(
                black_box(&y),
                DataKind::Rate,
                0.01,
                Estimator::Overlapping,
                &TauGrid::Octave,
                &none,
            )
        })
    });
    group.bench_function("oadev_octave_with_ci", |b| {
        b.iter(|| {
            allan::deviation(
                black_box(&y),
                DataKind::Rate,
                0.01,
                Estimator::Overlapping,
                &TauGrid::Octave,
            )
        })
    });
    let pts = allan::deviation(
        &y,
        DataKind::Rate,
        0.01,
        Estimator::Overlapping,
        &TauGrid::Octave,
    );
    group.bench_function("fit_ieee952", |b| {
        b.iter(|| allan::fit::fit_ieee952(black_box(&pts)))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
