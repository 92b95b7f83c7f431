//! The spec-sheet comparison: a sensor's spec ARW and bias instability beside the values read back
//! (Woodman's method, TR-696 §5.1) from a simulated long static log made with the noise crate, and
//! the drift at chosen times (law and simulation) from a static Monte Carlo run.

use crate::experiment::{Experiment, Overrides};
use crate::nav_quantity::NavQuantity;
use crate::report::DriftReport;
use crate::scenario::Scenario;
use allan::{DataKind, Estimator, Options, TauGrid};
use noise::{BiasInstability, Effect, ImuErrors, Sensor, SensorModel, StaticLevel};
use rayon::prelude::*;
use serde::Serialize;

/// Woodman's readback log: 12 h at 100 Hz (TR-696 §5.1, Table 4; docs/model.md §1.4).
pub const READBACK_DURATION_S: f64 = 12.0 * 3600.0;
pub const READBACK_RATE_HZ: f64 = 100.0;
/// Confidence level of the readback intervals: 99 %, so that reading both values on three axes
/// (six intervals) still covers all spec values with probability ~94 % (Bonferroni). The bias
/// instability reading is the minimum of a noisy curve, which selection biases low; the interval is
/// that of the chosen point (chi-squared with its EDF, allan crate).
pub const READBACK_CONFIDENCE: f64 = 0.99;
/// A spec value is "masked" when, at the tau where it is read, its own term contributes less than
/// this share of the model's closed-form Allan variance (another term dominates the reading).
pub const MASKED_SHARE: f64 = 0.5;

/// Gyro spec values and readbacks, each over the x, y, z axes (SI, rad/sqrt(s) and rad/s);
/// `None` where a value cannot be read back.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct GyroSpec {
    pub arw_spec: [Option<f64>; 3],
    pub arw_sim: [Option<f64>; 3],
    pub arw_sim_lo: [Option<f64>; 3],
    pub arw_sim_hi: [Option<f64>; 3],
    /// Bias instability as a spec sheet states it in Woodman's convention: the minimum of the
    /// model's closed-form Allan deviation.
    pub bi_spec: [Option<f64>; 3],
    pub bi_sim: [Option<f64>; 3],
    pub bi_sim_lo: [Option<f64>; 3],
    pub bi_sim_hi: [Option<f64>; 3],
    /// tau (s) of the readback minimum.
    pub bi_sim_tau_s: [Option<f64>; 3],
    /// Why a value is missing or doubtful.
    pub notes: Vec<String>,
}

/// Drift at one time: heading and horizontal position, law and simulation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DriftRow {
    pub t_s: f64,
    pub heading_rms_sim_rad: f64,
    pub heading_rms_law_rad: Option<f64>,
    pub horizontal_mean_sim_m: f64,
    pub horizontal_mean_law_m: Option<f64>,
    pub horizontal_rms_sim_m: f64,
    pub horizontal_rms_law_m: Option<f64>,
    pub horizontal_p95_sim_m: f64,
    /// Why a law is missing.
    pub law_note: Option<String>,
}

/// One sensor's comparison.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SensorSpec {
    pub name: String,
    pub gyro: GyroSpec,
    pub drift: Vec<DriftRow>,
    pub drift_runs: u64,
}

/// Generate the static gyro log of `model` (12 h, 100 Hz unless given) and read its ARW and bias
/// instability back per axis. Axes are generated and analysed in parallel; each axis draws from its
/// own streams, so the result does not depend on the thread count.
pub fn gyro_readback(model: &SensorModel, seed: u64, duration_s: f64, rate_hz: f64) -> GyroSpec {
    let dt_s = 1.0 / rate_hz;
    let n = (duration_s * rate_hz).round() as usize;
    let mut g = GyroSpec::default();
    for (axis, points) in readback_curves(model, seed, n, dt_s) {
        let m = model.axis(noise::Sensor::Gyro, axis);
        g.arw_spec[axis] = m.white_noise_density();
        if m.has(Effect::BiasInstability) {
            let log_taus: Vec<f64> = points.iter().map(|p| p.tau_s).collect();
            g.bi_spec[axis] = bi_spec_value(m, dt_s, &log_taus);
        }
        let reading = AxisReading {
            axis,
            name: ["x", "y", "z"][axis],
            model: m,
            dt_s,
            log_hours: n as f64 * dt_s / 3600.0,
            readings: allan::fit::readings(&points),
            points: &points,
        };
        reading.arw(&mut g);
        reading.bias_instability(&mut g);
    }
    g
}

/// Per gyro axis, the overlapping Allan deviation of `n` samples of its static output at `dt_s`
/// (99 % intervals), at the taus Woodman's rule allows (at least 9 bins, TR-696 §5.1,
/// docs/model.md §1.7).
fn readback_curves(
    model: &SensorModel,
    seed: u64,
    n: usize,
    dt_s: f64,
) -> Vec<(usize, Vec<allan::AllanPoint>)> {
    let mut errors = ImuErrors::new(model, dt_s, seed, 0);
    let still_gyro = StaticLevel::STANDARD.triad(Sensor::Gyro);
    let opts = Options {
        confidence: READBACK_CONFIDENCE,
        ..Options::default()
    };
    let channels = errors.channels_mut();
    channels[..3]
        .par_iter_mut()
        .enumerate()
        .map(|(axis, ch)| {
            let mut data = vec![0.0; n];
            ch.fill_static(0, &still_gyro, &mut data);
            let points = allan::deviation_with(
                &data,
                DataKind::Rate,
                dt_s,
                Estimator::Overlapping,
                &TauGrid::PerDecade(10),
                &opts,
            );
            let points: Vec<_> = points.into_iter().filter(|p| p.woodman_ok()).collect();
            (axis, points)
        })
        .collect()
}

/// One gyro axis's simulated Allan curve and the model it came from, read as Woodman read his.
struct AxisReading<'a> {
    axis: usize,
    name: &'static str,
    model: &'a noise::AxisModel,
    dt_s: f64,
    log_hours: f64,
    readings: allan::fit::Readings,
    points: &'a [allan::AllanPoint],
}

impl AxisReading<'_> {
    fn at(&self, tau: f64) -> Option<&allan::AllanPoint> {
        self.points.iter().find(|p| p.tau_s == tau)
    }

    /// The exact Allan variance of the sampled model (noise crate), not the continuous one: at tau
    /// near dt they differ (e.g. the flicker band edge).
    fn closed(&self, tau: f64) -> f64 {
        self.model.allan_variance_sampled(tau, self.dt_s)
    }

    /// ARW: the slope -1/2 line touching the curve, read at 1 s (Woodman §5.1); not read when
    /// white noise is less than [`MASKED_SHARE`] of the Allan variance there.
    fn arw(&self, g: &mut GyroSpec) {
        let (axis, name) = (self.axis, self.name);
        let (Some(nv), Some(p)) = (
            self.model.white_noise_density(),
            self.at(self.readings.arw_tau_s),
        ) else {
            return;
        };
        let share = nv * nv / p.tau_s / self.closed(p.tau_s);
        if share >= MASKED_SHARE {
            let s = p.tau_s.sqrt();
            g.arw_sim[axis] = Some(self.readings.arw_at_1s);
            g.arw_sim_lo[axis] = Some(p.lo * s);
            g.arw_sim_hi[axis] = Some(p.hi * s);
            // The tangent line also collects the other terms at that tau: by the closed form
            // the reading exceeds N by 1/sqrt(share) - 1.
            let bias = 1.0 / share.sqrt() - 1.0;
            if bias > 0.005 {
                g.notes.push(format!(
                    "gyro {name}: the ARW reading at tau = {:.3} s includes {:.1} % from other terms (closed form)",
                    p.tau_s,
                    100.0 * bias
                ));
            }
        } else {
            g.notes.push(format!(
                "gyro {name}: ARW cannot be read back: at tau = {:.3} s white noise is only {:.0} % of the Allan variance",
                p.tau_s,
                100.0 * share
            ));
        }
    }

    /// Bias instability: the minimum of the simulated curve (Woodman §5.1). It cannot be read
    /// back when the model's curve is still falling at the longest usable tau (white noise hides
    /// the floor in a log this short); the spec value itself is the minimum of the whole curve, so
    /// other terms shaping that minimum only earn a note.
    fn bias_instability(&self, g: &mut GyroSpec) {
        let (axis, name) = (self.axis, self.name);
        let (Some(bi), Some(p), Some(last)) = (
            self.model.get::<BiasInstability>(),
            self.at(self.readings.bi_min_tau_s),
            self.points.last(),
        ) else {
            return;
        };
        // White noise hides the floor: the curve still falls at the longest usable tau and
        // white noise is most of it there.
        let white_share = self
            .model
            .white_noise_density()
            .map_or(0.0, |nv| nv * nv / last.tau_s)
            / self.closed(last.tau_s);
        let still_falling =
            self.closed(last.tau_s * 1.5) < self.closed(last.tau_s) && white_share >= MASKED_SHARE;
        if still_falling && p.tau_s >= last.tau_s {
            g.notes.push(format!(
                "gyro {name}: bias instability cannot be read back: the model's Allan deviation still falls at the longest usable tau ({:.0} s, 9 bins) of a {:.0} h log; white noise masks the floor",
                last.tau_s,
                self.log_hours
            ));
            return;
        }
        g.bi_sim[axis] = Some(self.readings.bi_min);
        g.bi_sim_lo[axis] = Some(p.lo);
        g.bi_sim_hi[axis] = Some(p.hi);
        g.bi_sim_tau_s[axis] = Some(p.tau_s);
        let share = bi.avar_sampled(p.tau_s, self.dt_s) / self.closed(p.tau_s);
        if share < MASKED_SHARE {
            g.notes.push(format!(
                "gyro {name}: at the minimum (tau = {:.0} s) bias instability is only {:.0} % of the Allan variance: the reading is shaped by other terms",
                p.tau_s,
                100.0 * share
            ));
        }
        if p.tau_s >= last.tau_s {
            g.notes.push(format!(
                "gyro {name}: the minimum is at the longest usable tau ({:.0} s, 9 bins): the floor may lie beyond this log, so the reading is an upper bound",
                p.tau_s
            ));
        }
        let window = plateau_window(self.model);
        if !(p.tau_s >= window.0 && p.tau_s <= window.1) {
            g.notes.push(format!(
                "gyro {name}: the minimum lies at tau = {:.3} s, outside the flicker plateau [{:.3} s, {:.0} s] where the model's band edge bends the curve",
                p.tau_s, window.0, window.1
            ));
        }
    }
}

/// The plateau window of a flicker bias instability: the averaging times where its Allan deviation
/// is flat (the noise crate's `allan_minimum` convention solves B over it); outside, the finite
/// band of Gauss-Markov components bends the curve (a model artifact).
fn plateau_window(m: &noise::AxisModel) -> (f64, f64) {
    match m.get::<BiasInstability>() {
        Some(BiasInstability::Flicker(f)) => (30.0 * f.tau_min_s(), f.tau_max_s() / 30.0),
        _ => (0.0, f64::INFINITY),
    }
}

/// The bias-instability spec value as the sensor file states it: the minimum of the model's
/// closed-form Allan deviation over the plateau window (Woodman's reading, TR-696 §5.1), on a
/// fine log grid independent of the log length (20 per decade); without a window, over `taus`.
fn bi_spec_value(m: &noise::AxisModel, dt_s: f64, taus: &[f64]) -> Option<f64> {
    let window = plateau_window(m);
    let grid: Vec<f64> = if window.1.is_finite() {
        let decades = (window.1 / window.0).log10();
        let n = (20.0 * decades).ceil().max(1.0) as usize;
        (0..=n)
            .map(|i| window.0 * 10f64.powf(decades * i as f64 / n as f64))
            .collect()
    } else {
        taus.to_vec()
    };
    grid.iter()
        .map(|&t| m.allan_variance_sampled(t, dt_s).sqrt())
        .min_by(f64::total_cmp)
}

/// The gyro spec values of `model` without a readback (the `*_sim` fields stay `None`): ARW as
/// configured and the bias instability as the minimum of the closed-form Allan deviation (for a
/// bias instability without a plateau window, over the taus a 12 h, 9-bin readback would use).
pub fn gyro_spec_values(model: &SensorModel, rate_hz: f64) -> GyroSpec {
    let dt_s = 1.0 / rate_hz;
    let tau_max = READBACK_DURATION_S / 9.0;
    let decades = (tau_max / dt_s).log10();
    let n = (10.0 * decades).floor() as usize;
    let taus: Vec<f64> = (0..=n)
        .map(|i| dt_s * 10f64.powf(i as f64 / 10.0))
        .collect();
    let mut g = GyroSpec::default();
    for axis in 0..3 {
        let m = model.axis(noise::Sensor::Gyro, axis);
        g.arw_spec[axis] = m.white_noise_density();
        if m.has(Effect::BiasInstability) {
            g.bi_spec[axis] = bi_spec_value(m, dt_s, &taus);
        }
    }
    g
}

/// A static, level drift scenario for the comparison (checkpoints at `times_s`, which must be
/// whole numbers of samples at `rate_hz`).
pub fn drift_scenario(
    times_s: &[f64],
    rate_hz: f64,
    runs: u64,
    seed: u64,
) -> Result<Scenario, crate::scenario::ScenarioError> {
    let duration = times_s.iter().cloned().fold(0.0, f64::max);
    let times = times_s
        .iter()
        .map(|t| format!("{t:?}"))
        .collect::<Vec<_>>()
        .join(", ");
    let text = format!(
        "sensor = \"(given)\"\nduration_s = {duration:?}\nrate_hz = {rate_hz:?}\nruns = {runs}\nseed = {seed}\n[checkpoints]\ntimes_s = [{times}]\n"
    );
    Scenario::from_toml_str(&text, "spec drift scenario")
}

/// Drift rows from a static Monte Carlo report.
pub fn drift_rows(report: &DriftReport) -> Vec<DriftRow> {
    report
        .checkpoints
        .iter()
        .map(|cp| {
            let yaw = &cp.quantities[NavQuantity::Yaw.name()];
            let h = &cp.quantities[NavQuantity::PosHorizontal.name()];
            DriftRow {
                t_s: cp.t_s,
                heading_rms_sim_rad: yaw.rms,
                heading_rms_law_rad: yaw.law_rms,
                horizontal_mean_sim_m: h.mean,
                horizontal_mean_law_m: h.law_mean,
                horizontal_rms_sim_m: h.rms,
                horizontal_rms_law_m: h.law_rms,
                horizontal_p95_sim_m: h.p95,
                law_note: h.law_note.clone().or_else(|| yaw.law_note.clone()),
            }
        })
        .collect()
}

/// Experiment for the drift part of the comparison.
pub fn drift_experiment(
    model: &SensorModel,
    times_s: &[f64],
    rate_hz: f64,
    runs: u64,
    seed: u64,
) -> Result<Experiment, crate::experiment::ExperimentError> {
    let scenario = drift_scenario(times_s, rate_hz, runs, seed)?;
    Experiment::new(scenario, model, &Overrides::default())
}
