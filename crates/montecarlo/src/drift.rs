//! The drift experiment: a sensor model flying a scenario's trajectory through the strapdown
//! mechanisation, one run per random stream, errors recorded at the checkpoints; and the list of
//! active terms with the law each one obeys.

use crate::laws::{Entry, LawContext, Term};
use crate::nav_quantity::NavQuantity;
use crate::runner::{RunError, RunKernel};
use crate::scenario::{Alignment, Scenario};
use nalgebra::Vector3;
use noise::{ImuErrors, LawSource, LawSourceContext, Sensor, SensorModel};
use rand_distr::{Distribution, StandardNormal};
use strapdown::{
    nav_error, Attitude, EarthModel, EarthTrajectory, NavState, Scheme, StrapdownLanes, Trajectory,
    TrajectorySpec,
};

/// Index of the per-run initial-alignment stream among the noise crate's extra streams
/// (`noise::extra_rng`: disjoint from every sensor-term stream by construction).
pub const ALIGNMENT_STREAM: u32 = 0;

/// Samples of sensor error generated at a time (any value gives the same result; this one keeps
/// the six channel buffers, 12 KB, and a moving IMU's ideal inputs, 12 KB, in L1).
const BLOCK: usize = 256;

/// A ready-to-run drift experiment (immutable, shared by all runs).
#[derive(Debug, Clone)]
pub struct DriftKernel {
    pub model: SensorModel,
    /// The trajectory on the scenario's Earth (its truth, its ideal IMU, the Earth the
    /// mechanisation runs on).
    pub trajectory: EarthTrajectory,
    pub scheme: Scheme,
    pub dt_s: f64,
    pub seed: u64,
    pub gravity_mps2: f64,
    pub alignment: Alignment,
    pub checkpoint_steps: Vec<u64>,
    /// The scenario's `terms.bias_calibrated_at_start` (`ImuErrors::with_calibrated_start`).
    pub bias_calibrated_at_start: bool,
    /// The scenario's `terms.bias_calibration_window_s` (`ImuErrors::with_calibration_window`).
    pub bias_calibration_window_s: Option<f64>,
}

impl DriftKernel {
    /// The kernel of `scenario` with the (already filtered) `model` and `seed`.
    pub fn new(scenario: &Scenario, model: SensorModel, seed: u64) -> DriftKernel {
        DriftKernel {
            model,
            trajectory: scenario.trajectory.clone(),
            scheme: scenario.scheme,
            dt_s: scenario.dt_s(),
            seed,
            gravity_mps2: scenario.gravity_mps2,
            alignment: scenario.alignment,
            checkpoint_steps: scenario.checkpoint_steps.clone(),
            bias_calibrated_at_start: scenario.bias_calibrated_at_start,
            bias_calibration_window_s: scenario.bias_calibration_window_s,
        }
    }

    /// The initial estimate of run `run`: the truth at t = 0 with the alignment error added to its
    /// Euler angles (fixed part plus a Gaussian draw from the run's own alignment stream).
    fn initial_estimate(&self, run: u64) -> NavState {
        let truth = self.trajectory.truth(0.0);
        if self.alignment.is_zero() {
            return truth;
        }
        let mut rng = noise::extra_rng(self.seed, run, ALIGNMENT_STREAM);
        let (r, p, y) = truth.attitude.euler_rad();
        let mut d = [0.0; 3];
        for (i, di) in d.iter_mut().enumerate() {
            let w: f64 = StandardNormal.sample(&mut rng);
            *di = self.alignment.fixed_rad[i] + self.alignment.std_rad[i] * w;
        }
        NavState {
            attitude: Attitude::from_euler_rad(r + d[0], p + d[1], y + d[2]),
            ..truth
        }
    }
}

impl RunKernel for DriftKernel {
    fn checkpoints(&self) -> usize {
        self.checkpoint_steps.len()
    }
    fn quantities(&self) -> usize {
        NavQuantity::ALL.len()
    }

    fn run(&self, run: u64, out: &mut [f64]) -> Result<(), RunError> {
        let mut results = [Ok(())];
        self.simulate::<1>(run, out, &mut results);
        let [result] = results;
        result
    }

    fn lanes(&self) -> usize {
        LANES
    }

    fn run_lanes(&self, first: u64, out: &mut [f64], results: &mut [Result<(), RunError>]) {
        if let Ok(group) = <&mut [_; LANES]>::try_from(&mut *results) {
            return self.simulate::<LANES>(first, out, group);
        }
        // A partial group (the end of a range): one run at a time.
        let width = out.len() / results.len().max(1);
        for (i, (row, result)) in out.chunks_mut(width).zip(results).enumerate() {
            *result = self.run(first + i as u64, row);
        }
    }
}

/// Runs a [`DriftKernel`] advances together: the lanes of one [`StrapdownLanes`] step (eight
/// doubles fill an AVX-512 register).
const LANES: usize = 8;

impl DriftKernel {
    /// The sensor errors of run `run`, with the scenario's bias calibration.
    fn errors(&self, run: u64) -> ImuErrors {
        let errors = ImuErrors::new(&self.model, self.dt_s, self.seed, run);
        if let Some(w) = self.bias_calibration_window_s {
            errors.with_calibration_window(w, self.seed, run)
        } else if self.bias_calibrated_at_start {
            errors.with_calibrated_start()
        } else {
            errors
        }
    }

    /// Runs `first .. first + L` in the lanes of one integrator: run `first + l` writes row l of
    /// `out` (checkpoints x quantities) and its outcome in `results[l]`. Each lane's numbers are
    /// those of the run alone (`StrapdownLanes` lanes are independent, the errors are per run).
    fn simulate<const L: usize>(
        &self,
        first: u64,
        out: &mut [f64],
        results: &mut [Result<(), RunError>; L],
    ) {
        let mut errors: [ImuErrors; L] = std::array::from_fn(|l| self.errors(first + l as u64));
        let initial: [NavState; L] =
            std::array::from_fn(|l| self.initial_estimate(first + l as u64));
        let mut nav: StrapdownLanes<L> = self.trajectory.earth().lanes(self.scheme, &initial);
        // Prime the coning correction with the (ideal) motion before t = 0 (the trajectory holds
        // its initial rate there), so a constant-rate start is not a spurious step.
        let (g_prev, _) = self.trajectory.imu_average(-self.dt_s, 0.0);
        nav.set_previous_gyro(&g_prev.0, self.dt_s);
        let width = NavQuantity::ALL.len();
        let row = self.checkpoints() * width;
        // A static IMU's ideal outputs do not change: compute them once (hot loop).
        let still = self
            .trajectory
            .is_static()
            .then(|| self.trajectory.ideal_imu(0, self.dt_s));
        // The sensor errors come in blocks (each term over a whole block, the same values as
        // sample by sample; noise's `ImuErrors::fill_static` / `fill_moving`), then the block is
        // integrated.
        let mut block = vec![[[0.0f64; BLOCK]; 6]; L];
        let mut ideal_g = [Vector3::zeros(); BLOCK];
        let mut ideal_a = [Vector3::zeros(); BLOCK];
        let mut k = 0u64;
        for (cp, &until) in self.checkpoint_steps.iter().enumerate() {
            while k < until {
                let n = (until - k).min(BLOCK as u64) as usize;
                if still.is_none() {
                    for i in 0..n {
                        let (gyro, accel) = self.trajectory.ideal_imu(k + i as u64, self.dt_s);
                        (ideal_g[i], ideal_a[i]) = (gyro.0, accel.0);
                    }
                }
                let mut outs: Vec<[&mut [f64]; 6]> = block
                    .iter_mut()
                    .map(|lane| lane.each_mut().map(|b| &mut b[..n]))
                    .collect();
                match &still {
                    Some((gyro, accel)) => {
                        ImuErrors::fill_static_lanes(&mut errors, k, &gyro.0, &accel.0, &mut outs)
                    }
                    None => ImuErrors::fill_moving_lanes(
                        &mut errors,
                        k,
                        &ideal_g[..n],
                        &ideal_a[..n],
                        &mut outs,
                    ),
                }
                for (l, result) in results.iter_mut().enumerate() {
                    if result.is_ok() {
                        if let Some(e) = insane_sample(&block[l], n, k, self.dt_s) {
                            *result =
                                Err(RunError::Kernel(format!("run {}: {e}", first + l as u64)));
                        }
                    }
                }
                integrate_fast(&mut nav, &block, n, self.dt_s);
                k += n as u64;
            }
            let t_s = k as f64 * self.dt_s;
            let truth = self.trajectory.truth(t_s);
            for (l, result) in results.iter_mut().enumerate() {
                if result.is_err() {
                    continue;
                }
                let values = NavQuantity::values(&nav_error(&nav.state(l), &truth));
                if let Some(i) = values.iter().position(|v| !v.is_finite()) {
                    *result = Err(RunError::NonFinite {
                        run: first + l as u64,
                        quantity: NavQuantity::ALL[i].name().to_string(),
                        t_s,
                    });
                    continue;
                }
                out[l * row + cp * width..l * row + (cp + 1) * width].copy_from_slice(&values);
            }
        }
    }
}

/// The largest angle the gyros may turn in one step, rad: a rotation vector longer than pi names
/// the same attitude as a shorter one about the opposite axis (Savage, *Strapdown Analytics*,
/// 2000, section 7.1.1.1), so a step beyond it cannot be integrated; real motion is sampled with
/// many samples per turn (a gyro's rate limit of 2000 deg/s at 100 Hz turns 0.35 rad a step).
pub const MAX_STEP_ROTATION_RAD: f64 = std::f64::consts::PI;

/// Why the first `n` samples of one run's block (`[channel][sample]`, gyro x y z then
/// accelerometer x y z; sample `i` at step `k + i`) cannot be integrated, if they cannot: a gyro
/// sample turning more than [`MAX_STEP_ROTATION_RAD`] in one step of `dt_s`, or a sample that is
/// not a value a sensor sample may have (`noise::limits::valid_value`, the readers' bound). One
/// vectorised pass over the block; only a bad block is searched for its first bad sample.
fn insane_sample(block: &[[f64; BLOCK]; 6], n: usize, k: u64, dt_s: f64) -> Option<String> {
    let max_rate_sq = (MAX_STEP_ROTATION_RAD / dt_s).powi(2);
    let [gx, gy, gz, ..] = block;
    // Not `<=`: a NaN rate is too fast as well.
    let too_fast = |i: usize| {
        (gx[i] * gx[i] + gy[i] * gy[i] + gz[i] * gz[i])
            .partial_cmp(&max_rate_sq)
            .is_none_or(|o| o == std::cmp::Ordering::Greater)
    };
    let insane = |c: &[f64; BLOCK], i: usize| !noise::limits::valid_value(c[i]);
    let bad = (0..n).fold(false, |bad, i| {
        bad | too_fast(i) | block.iter().fold(false, |b, c| b | insane(c, i))
    });
    if !bad {
        return None;
    }
    let i = (0..n).find(|&i| too_fast(i) || block.iter().any(|c| insane(c, i)))?;
    let t_s = (k + i as u64) as f64 * dt_s;
    let problem = match block.iter().position(|c| insane(c, i)) {
        Some(c) => format!(
            "sensor sample {} is {:e} at t = {t_s} s, beyond the magnitude a sample may have ({:e})",
            noise::Channel::ALL[c].name(),
            block[c][i],
            noise::limits::MAX_ABS_VALUE
        ),
        None => format!(
            "the gyros turn {:.3e} rad in one step at t = {t_s} s (|gyro| x dt; more than pi rad, which no step of the mechanisation can represent)",
            (gx[i] * gx[i] + gy[i] * gy[i] + gz[i] * gz[i]).sqrt() * dt_s
        ),
    };
    Some(problem)
}

/// Integrate `n` samples of every lane's block (`block[lane][channel][sample]`, gyro x y z then
/// accelerometer x y z), through [`StrapdownLanes::integrate`] (the widest vector unit the CPU
/// has, the same bits at every width).
fn integrate_fast<const L: usize>(
    nav: &mut StrapdownLanes<L>,
    block: &[[[f64; BLOCK]; 6]],
    n: usize,
    dt_s: f64,
) {
    nav.integrate(n, dt_s, |start, samples| {
        for (l, lane) in block.iter().enumerate() {
            for (c, channel) in lane.iter().enumerate() {
                for (j, s) in samples.iter_mut().enumerate() {
                    s[c][l] = channel[start + j];
                }
            }
        }
    });
}

/// The active terms of `model` with their law sources (each term's own,
/// `noise::ErrorTerm::law_sources`), and the conditions of the laws, for a scenario's trajectory
/// and alignment on `earth`, sampled every `dt_s` (the sinusoid's law depends on it).
pub fn law_terms(
    model: &SensorModel,
    spec: &TrajectorySpec,
    alignment: &Alignment,
    earth: &EarthModel,
    dt_s: f64,
) -> (Vec<Term>, LawContext) {
    let gravity_mps2 = earth.gravity_mps2();
    let (static_level, yaw_rate, reason, attitude) = law_conditions(spec, earth);
    // The ideal readings the terms see: on the round Earth a static IMU's (Earth rate and local
    // gravity in its body axes); on the flat Earth static level (a constant yaw rate on the z gyro).
    let (round_gyro, round_accel) = earth.static_imu(&attitude);
    let mut terms = Vec::new();
    for sensor in [Sensor::Gyro, Sensor::Accel] {
        let ideal: Vector3<f64> = match (earth, sensor) {
            (EarthModel::Round(_), Sensor::Gyro) => round_gyro.0,
            (EarthModel::Round(_), Sensor::Accel) => round_accel.0,
            (EarthModel::Flat { .. }, Sensor::Gyro) => {
                Vector3::new(0.0, 0.0, yaw_rate.unwrap_or(0.0))
            }
            (EarthModel::Flat { .. }, Sensor::Accel) => Vector3::new(0.0, 0.0, -gravity_mps2),
        };
        for axis in 0..3 {
            let entry = match sensor {
                Sensor::Gyro => Entry::Gyro(axis),
                Sensor::Accel => Entry::Accel(axis),
            };
            // The two other axes in misalignment order.
            let others = match axis {
                0 => [ideal.y, ideal.z],
                1 => [ideal.x, ideal.z],
                _ => [ideal.x, ideal.y],
            };
            let cx = LawSourceContext {
                ideal: ideal[axis],
                others,
                dt_s,
                temperature: &model.temperature,
                temperature_reference_c: model.temperature_reference_c,
            };
            for term in model.axis(sensor, axis).terms() {
                let name = format!("{}.{}", sensor.name(), term.effect().name());
                for source in term.as_error_term().law_sources(&cx) {
                    terms.push(Term {
                        name: name.clone(),
                        entry,
                        source,
                    });
                }
            }
        }
    }
    terms.extend(alignment_terms(alignment));
    let ctx = LawContext {
        static_level,
        yaw_rate_rad_s: yaw_rate,
        reason,
        gravity_mps2,
        earth: *earth,
        attitude,
    };
    (terms, ctx)
}

/// Whether the laws hold for a trajectory, and the static attitude. On the flat Earth: static,
/// level and north-facing (the laws of docs/model.md §4); or a constant rate about body z from
/// level, which keeps the z gyro error on the yaw channel (rotations about one axis commute), so
/// that only the yaw law holds (calibration errors ~ rate x duration, docs/model.md §1.5 Table 2),
/// with the rate. On the round Earth: static at any attitude (the error model takes it). Else why
/// not.
fn law_conditions(
    spec: &TrajectorySpec,
    earth: &EarthModel,
) -> (bool, Option<f64>, String, Attitude) {
    let round = matches!(earth, EarthModel::Round(_));
    match *spec {
        TrajectorySpec::Static {
            roll_deg,
            pitch_deg,
            yaw_deg,
        } => {
            let attitude = Attitude::from_euler_rad(
                roll_deg.to_radians(),
                pitch_deg.to_radians(),
                yaw_deg.to_radians(),
            );
            let level = roll_deg == 0.0 && pitch_deg == 0.0 && yaw_deg == 0.0;
            (
                level || round,
                None,
                "the laws assume a level, north-facing IMU".to_string(),
                attitude,
            )
        }
        TrajectorySpec::ConstantRate {
            roll_deg: 0.0,
            pitch_deg: 0.0,
            yaw_deg: 0.0,
            rate_deg_s,
        } if rate_deg_s[0] == 0.0 && rate_deg_s[1] == 0.0 && !round => (
            false,
            Some(rate_deg_s[2].to_radians()),
            "motion".to_string(),
            Attitude::identity(),
        ),
        _ => (false, None, "motion".to_string(), Attitude::identity()),
    }
}

/// The initial attitude errors: each axis' fixed part as a bias and its random part as a constant
/// drawn per run.
fn alignment_terms(alignment: &Alignment) -> Vec<Term> {
    let mut terms = Vec::new();
    for axis in 0..3 {
        let (fixed, std) = (alignment.fixed_rad[axis], alignment.std_rad[axis]);
        let name = ["alignment.roll", "alignment.pitch", "alignment.yaw"][axis];
        if fixed != 0.0 {
            terms.push(Term {
                name: name.into(),
                entry: Entry::InitialAttitude(axis),
                source: LawSource::Bias(fixed),
            });
        }
        if std != 0.0 {
            terms.push(Term {
                name: name.into(),
                entry: Entry::InitialAttitude(axis),
                source: LawSource::RandomConstant(std),
            });
        }
    }
    terms
}

/// The law sources of `terms` when the bias is calibrated at turn-on (`ImuErrors::with_calibrated_start`):
/// every stationary Gauss-Markov process (the Gauss-Markov term and the flicker components) becomes
/// the same process referenced to its value at t = 0; all other sources are unchanged (random walks
/// already start at zero).
///
/// With a calibration window of `window_s` seconds (`ImuErrors::with_calibration_window`), each
/// becomes the process referenced to its mean over the window instead.
pub fn calibrated_at_start(terms: Vec<Term>, window_s: Option<f64>) -> Vec<Term> {
    let referenced = |parts: Vec<(f64, f64)>| match window_s {
        Some(window_s) => LawSource::GaussMarkovSumFromWindow { parts, window_s },
        None => LawSource::GaussMarkovSumFromStart(parts),
    };
    terms
        .into_iter()
        .map(|t| Term {
            source: match t.source {
                LawSource::GaussMarkov { sigma, tc_s } => referenced(vec![(tc_s, sigma)]),
                LawSource::GaussMarkovSum(parts) => referenced(parts),
                other => other,
            },
            ..t
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kernel(scenario_extra: &str) -> DriftKernel {
        let scenario = Scenario::from_toml_str(
            &format!("sensor = \"x\"\nduration_s = 10.0\nrate_hz = 100.0\nruns = 1\nseed = 3\n{scenario_extra}"),
            "t.toml",
        )
        .unwrap();
        let model = SensorModel::from_toml_str("name = \"perfect\"\n", "perfect.toml").unwrap();
        DriftKernel::new(&scenario, model, 3)
    }

    fn run(k: &DriftKernel) -> Vec<f64> {
        let mut out = vec![f64::NAN; k.checkpoints() * k.quantities()];
        k.run(0, &mut out).unwrap();
        out
    }

    const FLAT: &str = "[earth]\nmodel = \"flat\"\n";

    #[test]
    fn perfect_sensor_has_no_drift_static_and_turning() {
        // Static level: gravity cancels bit-exactly (strapdown's Static), so every quantity is 0.
        assert!(run(&kernel(FLAT)).iter().all(|&v| v == 0.0));
        // A non-standard gravity: the ideal accelerometer reads it too, so still no drift.
        assert!(run(&kernel(&format!("gravity_mps2 = 9.78\n{FLAT}")))
            .iter()
            .all(|&v| v.abs() < 1e-12));
        // Turning at 30 deg/s about z with the accurate scheme: the exact-rotation update leaves
        // only rounding (1e-9 rad / m after 1000 steps is far above double rounding ~1e-13).
        let out = run(&kernel(&format!(
            "{FLAT}[trajectory]\nkind = \"constant_rate\"\nrate_deg_s = [0.0, 0.0, 30.0]\n"
        )));
        assert!(out.iter().all(|v| v.abs() < 1e-9), "{out:?}");
    }

    #[test]
    fn perfect_sensor_on_the_round_earth_errs_as_on_the_flat_one() {
        // The ideal IMU of the rotating Earth (Earth rate, local gravity) through the round-Earth
        // mechanisation, static and turning, at the default place and at 60 deg S, 1500 m: the
        // errors after 10 s are those of the same motion on the flat Earth (the scheme's own
        // sculling error of a specific force turning in three axes, 1e-4 m/s; zero at rest; a
        // profile accelerating to 30 m/s, turning and accelerating again) to
        // 1e-9 rad and 1e-6 m or m/s: what the Earth adds (the truth's quadrature, the
        // mechanisation's Earth quantities refreshed every few steps) is far below any sensor's
        // (the navigation-grade GG1320AN's position error at 10 s is about 1 mm).
        for place in ["", "[earth]\nlatitude_deg = -60.0\nheight_m = 1500.0\n"] {
            for motion in [
                "",
                "[trajectory]\nkind = \"constant_rate\"\nrate_deg_s = [5.0, -10.0, 30.0]\n",
                "[trajectory]\nkind = \"coning\"\nhalf_angle_deg = 2.0\nfrequency_hz = 1.0\n",
                // Moving: the place changes, transport rate and Coriolis act.
                "[trajectory]\nkind = \"profile\"\n\
                 [[trajectory.segments]]\nkind = \"accelerate\"\nduration_s = 3.0\naccel_body_mps2 = [8.0, 2.0, 0.0]\n\
                 [[trajectory.segments]]\nkind = \"rotate\"\nduration_s = 3.0\naxis = [0.0, 0.0, 1.0]\nrate_deg_s = 20.0\n\
                 [[trajectory.segments]]\nkind = \"accelerate\"\nduration_s = 4.0\naccel_body_mps2 = [0.0, 5.0, 0.0]\n",
            ] {
                let round = run(&kernel(&format!("{place}{motion}")));
                let flat = run(&kernel(&format!("{FLAT}{motion}")));
                for (i, (r, f)) in round.iter().zip(&flat).enumerate() {
                    let q = NavQuantity::ALL[i % NavQuantity::ALL.len()];
                    // A moving IMU: the round mechanisation takes the transport rate at each
                    // step's start, half a sample late, an attitude offset of (dt/2) dv / R
                    // (2e-8 rad for this profile's 30 m/s at 100 Hz; tenfold smaller at 1 kHz,
                    // so it is the integrator's, not the truth's) and micrometres of position.
                    let moving = motion.contains("profile");
                    let bound = match ((q as usize) < 3, moving) {
                        (true, false) => 1e-9,
                        (false, false) => 1e-6,
                        (true, true) => 5e-8,
                        (false, true) => 2e-5,
                    };
                    // The height is held on the round Earth: its vertical error is zero.
                    let f = if matches!(q, NavQuantity::PosDown | NavQuantity::VelDown) {
                        0.0
                    } else {
                        *f
                    };
                    assert!(
                        (r - f).abs() < bound,
                        "{place} {motion}: {} = {r} against {f} on the flat Earth",
                        q.name()
                    );
                }
            }
        }
    }

    #[test]
    fn fixed_alignment_error_is_the_initial_attitude_error() {
        let k = kernel(&format!(
            "{FLAT}[alignment]\nroll_deg = 0.1\n[checkpoints]\ntimes_s = [0.01]\n"
        ));
        let out = run(&k);
        let roll = out[NavQuantity::Roll as usize];
        assert!((roll - 0.1f64.to_radians()).abs() < 1e-12, "{roll}");
        // After one step the east velocity is g sin(eps) dt (docs/model.md §1.2), to rounding.
        let ve = out[NavQuantity::VelEast as usize];
        let expected = 9.80665 * 0.1f64.to_radians().sin() * 0.01;
        assert!((ve / expected - 1.0).abs() < 1e-9, "{ve} vs {expected}");
    }
}

#[cfg(test)]
mod lane_tests {
    use super::*;

    /// A noisy model on a turning trajectory with random alignment errors: every term kind the
    /// runner's static and moving paths use.
    fn noisy_kernel(scheme: &str, trajectory: &str) -> DriftKernel {
        let scenario = Scenario::from_toml_str(
            &format!(
                "sensor = \"x\"\nduration_s = 5.0\nrate_hz = 100.0\nruns = 1\nseed = 11\nscheme = \"{scheme}\"\n\
                 [alignment]\nroll_std_deg = 0.1\nyaw_std_deg = 0.5\n{trajectory}"
            ),
            "t.toml",
        )
        .unwrap();
        let model = SensorModel::from_toml_str(
            "name = \"noisy\"\n[gyro.all]\nwhite_noise = \"0.1 deg/sqrt(h)\"\nbias_instability = \"5 deg/h\"\n\
             rate_random_walk = \"1 deg/h/sqrt(h)\"\nsinusoidal = { amplitude = \"0.01 deg/s\", frequency = \"3 Hz\" }\n\
             [accel.all]\nwhite_noise = \"50 ug/sqrt(Hz)\"\n",
            "noisy.toml",
        )
        .unwrap();
        DriftKernel::new(&scenario, model, 11)
    }

    /// Each of eight runs advanced together gives, bit for bit, the row of the run alone, for
    /// both schemes, static and turning; a partial group (3 runs) too.
    #[test]
    fn eight_lanes_give_the_rows_of_single_runs() {
        for (scheme, trajectory) in [
            ("woodman", ""),
            (
                "accurate",
                "[trajectory]\nkind = \"constant_rate\"\nrate_deg_s = [0.0, 0.0, 30.0]\n",
            ),
        ] {
            let k = noisy_kernel(scheme, trajectory);
            let width = k.checkpoints() * k.quantities();
            for count in [LANES, 3] {
                let mut together = vec![f64::NAN; width * count];
                let mut results = vec![Ok(()); count];
                k.run_lanes(40, &mut together, &mut results);
                assert!(results.iter().all(|r| r.is_ok()), "{results:?}");
                for (l, row) in together.chunks(width).enumerate() {
                    let mut alone = vec![f64::NAN; width];
                    k.run(40 + l as u64, &mut alone).unwrap();
                    assert!(
                        row.iter()
                            .zip(&alone)
                            .all(|(a, b)| a.to_bits() == b.to_bits()),
                        "{scheme} {trajectory:?}: run {} of {count}",
                        40 + l
                    );
                    assert!(row.iter().any(|&v| v != 0.0), "the run drifts");
                }
            }
        }
    }
}
