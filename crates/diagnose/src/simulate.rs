//! The model's Allan band (docs/diagnose.md, diagnose step 2) and its drift consequence (step 6): the sensor
//! model simulated as a static, level log at the measured rate and length, many seeds, in memory.
//!
//! Each seed is one montecarlo run (the deterministic ordered runner), so the band is bit-identical for
//! any thread count. The run writes its Allan deviations at the measured tau grid and the segment
//! drifts of its log into the run's output row.

use crate::drift::{segment_drift, SegmentDrift, G_MPS2};
use crate::gap::Band;
use allan::{DataKind, EdfMethod, Estimator, Options, TauGrid};
use montecarlo::{run_range, RunKernel};
use nalgebra::Vector3;
use noise::{ImuErrors, SensorModel};

/// What to simulate.
#[derive(Clone, Debug)]
pub struct SimSetup<'a> {
    pub dt_s: f64,
    /// Samples per simulated log (the measured length).
    pub samples: usize,
    /// Averaging factors of the measured curve (the band uses exactly these).
    pub grid_m: Vec<usize>,
    /// Which of gx gy gz ax ay az are in the measured log.
    pub active: [bool; 6],
    /// Drift horizons, seconds.
    pub horizons_s: Vec<f64>,
    /// The measured temperature (degC), which drives fitted temperature-bias terms (`temp_coeff`).
    pub temperature_c: Option<&'a [f64]>,
    /// Fitted temperature-bias coefficient per channel (SI per degC), applied to the measured temperature.
    pub temp_coeff: [f64; 6],
}

/// Bands of the active channels and the segment drifts of all seeds (merged in seed order).
#[derive(Clone, Debug)]
pub struct SimResult {
    pub bands: [Option<Band>; 6],
    pub drift: Vec<SegmentDrift>,
}

/// Error of a simulation run (a non-finite sample or Allan value).
#[derive(Debug, thiserror::Error)]
#[error("simulating the model failed in seed {run}: {message}")]
pub struct SimError {
    pub run: u64,
    pub message: String,
}

struct Kernel<'a> {
    model: &'a SensorModel,
    setup: &'a SimSetup<'a>,
    seed: u64,
    /// Segments per horizon (fixed by the log length).
    segments: Vec<usize>,
}

impl Kernel<'_> {
    fn taus(&self) -> usize {
        self.setup.grid_m.len()
    }
}

/// Generate the static log of run `run`: channels gx gy gz ax ay az, SI (inactive channels empty).
pub fn static_log(model: &SensorModel, setup: &SimSetup, seed: u64, run: u64) -> [Vec<f64>; 6] {
    let n = setup.samples;
    let mut errors = ImuErrors::new(model, setup.dt_s, seed, run);
    // A static level IMU reads zero rate and specific force (0, 0, -g) (docs/cli.md convention).
    let gyro = Vector3::zeros();
    let accel = Vector3::new(0.0, 0.0, -G_MPS2);
    let mut out: [Vec<f64>; 6] = Default::default();
    // Each channel owns its random streams, so generating only the active ones changes nothing else.
    for (ch, gen) in errors.channels_mut().iter_mut().enumerate() {
        if setup.active[ch] {
            out[ch] = vec![0.0; n];
            gen.fill_static(0, if ch < 3 { &gyro } else { &accel }, &mut out[ch]);
        }
    }
    if let Some(temp) = setup.temperature_c {
        for (ch, series) in out.iter_mut().enumerate() {
            let c = setup.temp_coeff[ch];
            if c != 0.0 {
                for (x, t) in series.iter_mut().zip(temp) {
                    *x += c * t;
                }
            }
        }
    }
    out
}

/// Overlapping Allan deviation of `series` at exactly the averaging factors `grid_m` (no intervals).
pub fn adev_at(series: &[f64], dt_s: f64, grid_m: &[usize]) -> Vec<f64> {
    let opts = Options {
        edf: EdfMethod::None,
        stable32_stop: false,
        ..Options::default()
    };
    let grid = TauGrid::Explicit(grid_m.to_vec());
    let points = allan::deviation_with(
        series,
        DataKind::Rate,
        dt_s,
        Estimator::Overlapping,
        &grid,
        &opts,
    );
    let mut out = vec![f64::NAN; grid_m.len()];
    for p in points {
        if let Some(i) = grid_m.iter().position(|&m| m == p.m) {
            out[i] = p.dev;
        }
    }
    out
}

impl RunKernel for Kernel<'_> {
    fn checkpoints(&self) -> usize {
        self.taus() + self.segments.iter().sum::<usize>()
    }
    fn channels(&self) -> usize {
        6
    }
    fn run(&self, run: u64, out: &mut [f64]) -> Result<(), montecarlo::runner::RunError> {
        let log = static_log(self.model, self.setup, self.seed, run);
        let m = self.taus();
        for ch in 0..6 {
            let adev = if self.setup.active[ch] {
                adev_at(&log[ch], self.setup.dt_s, &self.setup.grid_m)
            } else {
                vec![0.0; m]
            };
            for (i, a) in adev.into_iter().enumerate() {
                out[i * 6 + ch] = a;
            }
        }
        let chans: [Option<&[f64]>; 6] =
            std::array::from_fn(|c| self.setup.active[c].then_some(log[c].as_slice()));
        let mut row = m;
        for (h, &horizon) in self.setup.horizons_s.iter().enumerate() {
            let d = segment_drift(&chans, self.setup.dt_s, horizon);
            for s in 0..self.segments[h] {
                out[row * 6] = d.heading_rad[s];
                out[row * 6 + 1] = d.horizontal_m[s];
                for c in 2..6 {
                    out[row * 6 + c] = 0.0;
                }
                row += 1;
            }
        }
        Ok(())
    }
}

/// Simulate `seeds` static logs of the model (runs 0..seeds of master seed `seed`) and return the
/// bands and drifts. Runs execute on the current rayon pool through the montecarlo runner.
pub fn simulate(
    model: &SensorModel,
    setup: &SimSetup,
    seed: u64,
    seeds: usize,
) -> Result<SimResult, SimError> {
    let segments: Vec<usize> = setup
        .horizons_s
        .iter()
        .map(|&h| {
            setup
                .samples
                .checked_div((h / setup.dt_s).round() as usize)
                .unwrap_or(0)
        })
        .collect();
    let kernel = Kernel {
        model,
        setup,
        seed,
        segments: segments.clone(),
    };
    let batch = run_range(&kernel, 0..seeds as u64, &|_| {});
    if let Some(f) = batch.failures.first() {
        return Err(SimError {
            run: f.run,
            message: f.message.clone(),
        });
    }
    let mx = &batch.matrix;
    let taus: Vec<f64> = setup
        .grid_m
        .iter()
        .map(|&m| m as f64 * setup.dt_s)
        .collect();
    let bands: [Option<Band>; 6] = std::array::from_fn(|ch| {
        setup.active[ch].then(|| {
            let per_seed: Vec<Vec<f64>> = (0..seeds)
                .map(|s| (0..taus.len()).map(|i| mx.series(i, ch)[s]).collect())
                .collect();
            Band::from_seeds(&taus, &per_seed)
        })
    });
    let mut drift = Vec::new();
    let mut row = taus.len();
    for (h, &horizon) in setup.horizons_s.iter().enumerate() {
        let mut d = SegmentDrift {
            horizon_s: horizon,
            ..Default::default()
        };
        for s in 0..seeds {
            for j in 0..segments[h] {
                d.heading_rad.push(mx.series(row + j, 0)[s]);
                d.horizontal_m.push(mx.series(row + j, 1)[s]);
            }
        }
        row += segments[h];
        drift.push(d);
    }
    Ok(SimResult { bands, drift })
}
