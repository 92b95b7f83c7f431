//! Sample generation: ns per 6-axis sample of the full MTx model (configs/sensors/mtx.toml:
//! white noise, flicker bias instability as 7 Gauss-Markov components (0.1 s .. 1e5 s, one per decade)
//! and rate random walk on each
//! gyro, white noise on each accelerometer), through `ImuErrors::corrupt` (sample by sample),
//! `ImuErrors::fill_moving` (blocks of a moving IMU, what the Monte Carlo runner runs for a
//! trajectory with motion) and channel by channel (`ChannelErrors::fill_static`, what
//! `imudrift generate` runs in parallel).

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use noise::{Channel, ImuErrors, Sensor, SensorModel, StaticLevel};
use std::hint::black_box;

const SAMPLES: u64 = 100_000;

fn mtx() -> SensorModel {
    imudrift::files::sensor_model(
        &std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
            .join("configs/sensors/mtx.toml"),
    )
    .expect("mtx.toml")
}

/// Generate every channel of a static level IMU, `SAMPLES` samples each, with `model`'s errors.
fn fill_static_all(b: &mut criterion::Bencher, model: &SensorModel) {
    let ideal = StaticLevel::STANDARD.inputs();
    let mut out = vec![0.0; SAMPLES as usize];
    b.iter_batched(
        || ImuErrors::new(model, 0.01, 1, 0),
        |mut e| {
            for (c, ch) in Channel::ALL.into_iter().zip(e.channels_mut().iter_mut()) {
                ch.fill_static(0, &ideal[c], &mut out);
                black_box(&out);
            }
        },
        BatchSize::LargeInput,
    )
}

fn bench(c: &mut Criterion) {
    let model = mtx();
    let ideal_g = StaticLevel::STANDARD.triad(Sensor::Gyro);
    let ideal_a = StaticLevel::STANDARD.triad(Sensor::Accel);
    let mut group = c.benchmark_group("generate_mtx");
    group.throughput(Throughput::Elements(SAMPLES));
    group.sample_size(20);
    group.bench_function("corrupt_6axis", |b| {
        b.iter_batched(
            || ImuErrors::new(&model, 0.01, 1, 0),
            |mut e| {
                for k in 0..SAMPLES {
                    black_box(e.corrupt(k, &ideal_g, &ideal_a));
                }
            },
            BatchSize::LargeInput,
        )
    });
    // A moving IMU the way the runner generates it: 256 samples at a time, each with its own
    // ideal input (`ImuErrors::fill_moving`; the same values as `corrupt` sample by sample).
    group.bench_function("fill_moving_6axis", |b| {
        const BLOCK: usize = 256;
        let gyro = [ideal_g; BLOCK];
        let accel = [ideal_a; BLOCK];
        let mut block = [[0.0f64; BLOCK]; 6];
        b.iter_batched(
            || ImuErrors::new(&model, 0.01, 1, 0),
            |mut e| {
                for k0 in (0..SAMPLES).step_by(BLOCK) {
                    let n = (SAMPLES - k0).min(BLOCK as u64) as usize;
                    let out = block.each_mut().map(|b| &mut b[..n]);
                    e.fill_moving(k0, &gyro[..n], &accel[..n], out);
                    black_box(&block);
                }
            },
            BatchSize::LargeInput,
        )
    });
    group.bench_function("fill_static_6_channels", |b| {
        fill_static_all(b, &model);
    });
    group.finish();

    // The same model behind an output filter: Bartlett 16 taps at 8x the output rate (the raw
    // processes run at the internal rate), and a second-order low-pass at the output rate (IIR).
    let mut group = c.benchmark_group("generate_mtx_filtered");
    group.throughput(Throughput::Elements(SAMPLES));
    group.sample_size(10);
    for (name, kind, d) in [
        ("bartlett16_x8", noise::FilterKind::Bartlett { taps: 16 }, 8),
        // The moving average `diagnose` fits on the ADIS16405 runs: no sample kept.
        (
            "moving_average5_x4",
            noise::FilterKind::MovingAverage { taps: 5 },
            4,
        ),
        (
            "lowpass2_30hz_x1",
            noise::FilterKind::LowPass2 { cutoff_hz: 30.0 },
            1,
        ),
    ] {
        let mut m = model.clone();
        for s in noise::Sensor::ALL {
            for a in &mut m.triad_mut(s).axes {
                a.set_term(noise::OutputFilter::new(kind, d).unwrap());
            }
        }
        group.bench_function(name, |b| fill_static_all(b, &m));
    }
    group.finish();

    // The exact filtered Allan variance of the MTx gyro at 18 octave taus (what diagnose's filter
    // candidate and the readback tests evaluate).
    let mut group = c.benchmark_group("filtered_allan");
    let taus: Vec<f64> = (0..18).map(|j| 0.01 * f64::from(1u32 << j)).collect();
    let mut axis = model.gyro.axes[0].clone();
    axis.set_term(noise::OutputFilter::new(noise::FilterKind::Bartlett { taps: 16 }, 8).unwrap());
    group.bench_function("mtx_gyro_bartlett16_x8_18_taus", |b| {
        b.iter(|| black_box(axis.allan_variance_sampled_many(&taus, 0.01)))
    });
    // A long response (first-order low-pass at 0.1 Hz, 10 Hz output: ~620 samples, the Samsung
    // S5's filter), with a resonance: the FFT autocorrelation and the O(L) exponential sums.
    let mut long = model.gyro.axes[0].clone();
    long.set_term(
        noise::OutputFilter::new(noise::FilterKind::LowPass1 { cutoff_hz: 0.1 }, 1).unwrap(),
    );
    long.set_term(noise::Resonance::new(1e-3, 2.0, 0.2).unwrap());
    let taus10: Vec<f64> = (0..18).map(|j| 0.1 * f64::from(1u32 << j)).collect();
    group.bench_function("mtx_gyro_lowpass1_0.1hz_resonance_18_taus", |b| {
        b.iter(|| black_box(long.allan_variance_sampled_many(&taus10, 0.1)))
    });
    group.finish();

    // The MTx model with a resonance on every axis (two normals per sample for the oscillator).
    let mut group = c.benchmark_group("generate_mtx_resonance");
    group.throughput(Throughput::Elements(SAMPLES));
    group.sample_size(10);
    let mut m = model.clone();
    for s in noise::Sensor::ALL {
        for a in &mut m.triad_mut(s).axes {
            a.set_term(noise::Resonance::new(1e-3, 20.0, 0.7).unwrap());
        }
    }
    group.bench_function("fill_static_6_channels", |b| {
        fill_static_all(b, &m);
    });
    // Four runs: one after the other, and side by side (`ImuErrors::fill_static_lanes`: the
    // flicker bank, random walk and resonance of four runs in one AVX2 loop); the time is that
    // of all four runs (the throughput line counts one run's samples).
    let (g, a) = (
        StaticLevel::STANDARD.triad(Sensor::Gyro),
        StaticLevel::STANDARD.triad(Sensor::Accel),
    );
    let mut outs = vec![[(); 6].map(|_| vec![0.0; SAMPLES as usize]); 4];
    let runs = || {
        (0..4)
            .map(|r| ImuErrors::new(&m, 0.01, 1, r))
            .collect::<Vec<_>>()
    };
    for side_by_side in [false, true] {
        let name = if side_by_side {
            "fill_static_4_runs_side_by_side"
        } else {
            "fill_static_4_runs_one_by_one"
        };
        group.bench_function(name, |b| {
            b.iter_batched(
                runs,
                |mut es| {
                    let mut blocks: Vec<[&mut [f64]; 6]> = outs
                        .iter_mut()
                        .map(|lane| lane.each_mut().map(|o| &mut o[..]))
                        .collect();
                    if side_by_side {
                        ImuErrors::fill_static_lanes(&mut es, 0, &g, &a, &mut blocks);
                    } else {
                        for (e, lane) in es.iter_mut().zip(blocks.iter_mut()) {
                            e.fill_static(0, &g, &a, lane.each_mut().map(|o| &mut **o));
                        }
                    }
                    black_box(&blocks);
                },
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();

    // The MTx model with a sinusoid on every axis (the fitted ADIS16405 model's accelerometer
    // lines): exact sin/cos every 64 samples, eight windows rotated side by side in between.
    let mut group = c.benchmark_group("generate_mtx_sinusoid");
    group.throughput(Throughput::Elements(SAMPLES));
    group.sample_size(10);
    let mut m = model.clone();
    for s in noise::Sensor::ALL {
        for a in &mut m.triad_mut(s).axes {
            a.set_term(noise::Sinusoid::new(8e-3, 0.5641, None).unwrap());
        }
    }
    group.bench_function("fill_static_6_channels", |b| {
        fill_static_all(b, &m);
    });
    group.finish();
}

/// The standard-normal draws every stochastic term makes: the wide sampler (`NormalStream`, eight
/// Xoshiro256++ lanes, the ziggurat's first pass vectorised) against one Xoshiro256++ through
/// rand_distr's `StandardNormal` (the same ziggurat, ZIGNOR; the sampler before issue 26).
fn bench_normals(c: &mut Criterion) {
    use rand::{Rng, SeedableRng};
    const N: usize = 4096;
    let mut group = c.benchmark_group("normals");
    group.throughput(Throughput::Elements(N as u64));
    let mut out = vec![0.0; N];
    let mut wide = noise::NormalStream::new(noise::ImuRng::seed_from_u64(1));
    group.bench_function("normal_stream_fill", |b| {
        b.iter(|| {
            wide.fill(&mut out);
            black_box(&out);
        })
    });
    let mut rng = noise::ImuRng::seed_from_u64(1);
    group.bench_function("xoshiro256pp_rand_distr", |b| {
        b.iter(|| {
            for w in out.iter_mut() {
                *w = rng.sample(rand_distr::StandardNormal);
            }
            black_box(&out);
        })
    });
    group.finish();
}

criterion_group!(benches, bench, bench_normals);
criterion_main!(benches);
