//! Allan deviation: the overlapping deviation of one 4.32 M-sample channel (12 h at 100 Hz) at
//! octave taus, in memory, with and without confidence intervals (noise identification +
//! Greenhall EDF + chi-squared bounds), and the IEEE 952 fit. Compare with
//! `scripts/bench_allantools.py`, which times allantools' `oadev` on the same kind of channel.
//! `total_100k`: the modified total, Hadamard total and Theo1 kernels and MTIE.

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

/// The O(N m) kernels of issue 45 at one tau each (100,000 samples, m = 64; Theo1 at m = 128, the
/// same N m / 2 work): throughput is counted in N m work units, so the figure is the time per
/// subsequence-and-factor (ns per element), and MTIE's octave grid (O(N) per tau).
fn bench_total(c: &mut Criterion) {
    const N: usize = 100_000;
    const M: usize = 64;
    let y: Vec<f64> = channel()[..N].to_vec();
    let series = allan::Series::new(&y, DataKind::Rate, 0.01);
    let mut group = c.benchmark_group("total_100k");
    group.sample_size(10);
    group.throughput(Throughput::Elements((N * M) as u64));
    for est in [
        Estimator::ModifiedTotal,
        Estimator::HadamardTotal,
        Estimator::Theo1,
    ] {
        let m = if est == Estimator::Theo1 { 2 * M } else { M };
        group.bench_function(format!("{}_m{m}", est.name()), |b| {
            b.iter(|| series.raw_point(black_box(est), m))
        });
    }
    group.throughput(Throughput::Elements(N as u64));
    let x = series.phase().to_vec();
    group.bench_function("mtie_octave", |b| {
        b.iter(|| {
            TauGrid::Octave
                .ms(x.len())
                .into_iter()
                .filter_map(|m| allan::total::mtie(black_box(&x), m))
                .count()
        })
    });
    group.finish();
}

criterion_group!(benches, bench, bench_total);
criterion_main!(benches);
