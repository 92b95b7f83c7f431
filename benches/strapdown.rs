//! Cost of one strapdown mechanisation step (issue 4 target: >= 20 million steps/s on one core).
//!
//! Inputs vary per step (a slow coning-like rate and a tilted gravity reading) so neither the compiler
//! nor the branch predictor sees a constant; the rate keeps |w dt| in the series branch of Woodman eq 41,
//! as for any IMU below ~570 deg/s at 100 Hz.

use criterion::{black_box, criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use strapdown::earth::Place;
use strapdown::{
    BodyVector, NavState, RoundEarth, Scheme, Static, Strapdown, StrapdownLanes, Trajectory,
    STANDARD_GRAVITY_MPS2,
};

const STEPS_PER_ITER: usize = 1000;
const DT_S: f64 = 0.01;

fn inputs() -> Vec<(BodyVector, BodyVector)> {
    (0..STEPS_PER_ITER)
        .map(|k| {
            let phase = k as f64 * 0.01;
            let gyro = BodyVector::new(0.02 * phase.sin(), 0.02 * phase.cos(), -1e-3);
            let accel = BodyVector::new(0.05 * phase.cos(), -0.03, -STANDARD_GRAVITY_MPS2);
            (gyro, accel)
        })
        .collect()
}

fn bench_step(c: &mut Criterion) {
    let samples = inputs();
    let mut group = c.benchmark_group("strapdown_step");
    group.throughput(Throughput::Elements(STEPS_PER_ITER as u64));
    for (name, scheme) in [("woodman", Scheme::Woodman), ("accurate", Scheme::Accurate)] {
        group.bench_function(name, |b| {
            b.iter_batched_ref(
                || Strapdown::new(scheme, NavState::default(), STANDARD_GRAVITY_MPS2),
                |sd| {
                    for (gyro, accel) in &samples {
                        sd.step(black_box(gyro), black_box(accel), DT_S);
                    }
                },
                BatchSize::SmallInput,
            )
        });
    }
    // The same steps on the round, rotating Earth (45 deg N; strapdown::round_earth).
    let earth = RoundEarth::at(Place::from_deg(45.0, 0.0, 0.0));
    for (name, scheme) in [
        ("woodman_round_earth", Scheme::Woodman),
        ("accurate_round_earth", Scheme::Accurate),
    ] {
        group.bench_function(name, |b| {
            b.iter_batched_ref(
                || Strapdown::on_earth(scheme, NavState::default(), earth),
                |sd| {
                    for (gyro, accel) in &samples {
                        sd.step(black_box(gyro), black_box(accel), DT_S);
                    }
                },
                BatchSize::SmallInput,
            )
        });
    }
    // The Monte Carlo inner loop on a static scenario: ideal sample + step.
    let traj = Static::default();
    group.bench_function("accurate_with_static_ideal_imu", |b| {
        b.iter_batched_ref(
            || Strapdown::for_trajectory(Scheme::Accurate, &traj, DT_S),
            |sd| {
                for k in 0..STEPS_PER_ITER as u64 {
                    let (gyro, accel) = traj.ideal_imu(black_box(k), DT_S);
                    sd.step(&gyro, &accel, DT_S);
                }
            },
            BatchSize::SmallInput,
        )
    });
    group.finish();
}

/// Eight runs side by side, as the Monte Carlo kernel steps them (`StrapdownLanes::integrate`,
/// the widest vector unit the CPU has), on the flat and on the round Earth.
fn bench_lanes(c: &mut Criterion) {
    const L: usize = 8;
    let samples = inputs();
    let mut group = c.benchmark_group("strapdown_lanes8");
    group.throughput(Throughput::Elements((STEPS_PER_ITER * L) as u64));
    let earth = RoundEarth::at(Place::from_deg(45.0, 0.0, 0.0));
    let initial = [NavState::default(); L];
    for (name, round) in [("accurate_flat", false), ("accurate_round_earth", true)] {
        group.bench_function(name, |b| {
            b.iter_batched_ref(
                || {
                    if round {
                        StrapdownLanes::<L>::on_earth(Scheme::Accurate, &initial, earth)
                    } else {
                        StrapdownLanes::<L>::new(Scheme::Accurate, &initial, STANDARD_GRAVITY_MPS2)
                    }
                },
                |nav| {
                    nav.integrate(STEPS_PER_ITER, DT_S, |start, chunk| {
                        for (j, s) in chunk.iter_mut().enumerate() {
                            let (g, a) = &samples[start + j];
                            for k in 0..3 {
                                s[k] = [g.0[k]; L];
                                s[3 + k] = [a.0[k]; L];
                            }
                        }
                    });
                },
                BatchSize::SmallInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, bench_step, bench_lanes);
criterion_main!(benches);
