//! Growth laws on the scenario's Earth ([`all_laws`]); on the round, rotating Earth: every active term's contribution propagated through
//! the linearised psi-angle error model of a stationary navigator (`strapdown::error_model`:
//! Schuler loop, Earth-rate coupling, Coriolis and the vertical channel as the scenario treats it)
//! as an exact mean and covariance, summed over the independent terms. The counterpart of the
//! flat Earth's closed forms (`laws`), which it replaces whenever a scenario runs on `wgs84`.

use crate::laws::{
    channel_laws, horizontal_magnitude, Entry, Law, LawContext, Term, SMALL_ANGLE_LIMIT_RAD,
};
use crate::nav_quantity::NavQuantity;
use nalgebra::{Matrix3, Vector3};
use noise::LawSource;
use strapdown::error_model::{moments, window_reference, ErrorMoments, Sensor, Source};
use strapdown::{Attitude, EarthModel, RoundEarth, Vertical};

/// The laws of every channel at each of `times_s` (ascending), [time][`NavQuantity::ALL`]: the
/// flat Earth's closed forms ([`channel_laws`]) or the round Earth's error model
/// ([`round_laws`]).
pub fn all_laws(terms: &[Term], ctx: &LawContext, times_s: &[f64]) -> Vec<Vec<Law>> {
    match &ctx.earth {
        EarthModel::Flat { .. } => times_s
            .iter()
            .map(|&t| channel_laws(terms, ctx, t))
            .collect(),
        EarthModel::Round(e) => round_laws(terms, ctx, e, &ctx.attitude, times_s),
    }
}

/// [`all_laws`] of a run-to-run mixture (docs/model.md §2.3): with `mixture` empty, the laws of
/// `terms`; else each node's laws (`SensorModel::run_to_run_quadrature`, weights w summing to 1)
/// combined as the law of the mixture: mean = sum w m_i, mean square = sum w (m_i^2 + s_i^2)
/// (the moments of a mixture; exact for each node's Gaussian, and for the horizontal magnitude's
/// Rayleigh-type mean, which is linear in the mixing). A horizontal mean unknown at a node (NaN)
/// leaves the mixture's unknown; a node without a law gives none.
pub fn mixture_laws(
    terms: &[Term],
    mixture: &[(f64, Vec<Term>)],
    ctx: &LawContext,
    times_s: &[f64],
) -> Vec<Vec<Law>> {
    if mixture.is_empty() {
        return all_laws(terms, ctx, times_s);
    }
    let nodes: Vec<(f64, Vec<Vec<Law>>)> = mixture
        .iter()
        .map(|(w, t)| (*w, all_laws(t, ctx, times_s)))
        .collect();
    (0..times_s.len())
        .map(|ti| {
            (0..NavQuantity::ALL.len())
                .map(|q| {
                    let (mut mean, mut ms, mut allowance) = (0.0, 0.0, 0.0f64);
                    for (w, laws) in &nodes {
                        match &laws[ti][q] {
                            Law::Value {
                                mean: m,
                                std: s,
                                allowance: a,
                            } => {
                                // A NaN mean marks "mean unknown": std then holds the rms.
                                let m2 = if m.is_nan() { 0.0 } else { m * m };
                                mean += w * m;
                                ms += w * (m2 + s * s);
                                allowance = allowance.max(*a);
                            }
                            Law::NotApplicable(why) => return Law::NotApplicable(why.clone()),
                        }
                    }
                    let std = if mean.is_nan() {
                        ms.sqrt()
                    } else {
                        (ms - mean * mean).max(0.0).sqrt()
                    };
                    Law::Value {
                        mean,
                        std,
                        allowance,
                    }
                })
                .collect()
        })
        .collect()
}

/// The error-model sources of one term (a sum of Gauss-Markov processes gives one each), or why
/// it has no law.
fn sources(term: &Term, attitude: &Attitude) -> Result<Vec<Source>, String> {
    let (sensor, axis) = match term.entry {
        Entry::Gyro(a) => (Sensor::Gyro, a),
        Entry::Accel(a) => (Sensor::Accel, a),
        Entry::InitialAttitude(a) => return Ok(vec![alignment_source(&term.source, a, attitude)?]),
    };
    let one = |v: f64| {
        let mut x = [0.0; 3];
        x[axis] = v;
        x
    };
    // Unused axes get a harmless correlation time (their value states stay zero).
    let tau = |t: f64| {
        let mut x = [1.0; 3];
        x[axis] = t;
        x
    };
    let referenced = |parts: &[(f64, f64)], window_s: Option<f64>| -> Vec<Source> {
        parts
            .iter()
            .map(|&(tc_s, sigma)| {
                let (rho, vm) = window_s.map_or((1.0, 1.0), |w| window_reference(tc_s, w));
                Source::GaussMarkovReferenced {
                    sensor,
                    var: one(sigma * sigma),
                    tau_s: tau(tc_s),
                    rho: [rho; 3],
                    vm: [vm; 3],
                }
            })
            .collect()
    };
    Ok(match &term.source {
        LawSource::Bias(b) => vec![Source::Bias {
            sensor,
            value: one(*b),
        }],
        LawSource::RandomConstant(s) => vec![Source::RandomBias {
            sensor,
            var: one(s * s),
        }],
        LawSource::White(n) => vec![Source::White {
            sensor,
            n2: one(n * n),
        }],
        LawSource::RandomWalk(k) => vec![Source::RandomWalk {
            sensor,
            k2: one(k * k),
        }],
        LawSource::Ramp(r) => vec![Source::Ramp {
            sensor,
            rate: one(*r),
        }],
        LawSource::GaussMarkov { sigma, tc_s } => vec![Source::GaussMarkov {
            sensor,
            var: one(sigma * sigma),
            tau_s: tau(*tc_s),
        }],
        LawSource::GaussMarkovSum(parts) => parts
            .iter()
            .map(|&(tc_s, sigma)| Source::GaussMarkov {
                sensor,
                var: one(sigma * sigma),
                tau_s: tau(tc_s),
            })
            .collect(),
        LawSource::GaussMarkovSumFromStart(parts) => referenced(parts, None),
        LawSource::GaussMarkovSumFromWindow { parts, window_s } => {
            referenced(parts, Some(*window_s))
        }
        LawSource::Sinusoid {
            amplitude,
            freq_hz,
            phase,
            sample_interval_s,
        } => vec![Source::Sinusoid {
            sensor,
            amplitude: one(*amplitude),
            freq_hz: tau(*freq_hz),
            phase: *phase,
            dt_s: *sample_interval_s,
        }],
        LawSource::Resonance {
            sigma,
            frequency_hz,
            bandwidth_hz,
        } => vec![Source::Resonance {
            sensor,
            sigma: one(*sigma),
            freq_hz: tau(*frequency_hz),
            bandwidth_hz: {
                let mut x = [0.5; 3];
                x[axis] = *bandwidth_hz;
                x
            },
        }],
        LawSource::Transient {
            amplitude,
            tau_s,
            per_run,
        } => vec![Source::Transient {
            sensor,
            amplitude: one(*amplitude),
            tau_s: tau(*tau_s),
            per_run: *per_run,
        }],
        LawSource::NoLaw(why) => return Err(why.clone()),
    })
}

/// d psi / d(roll, pitch, yaw) at a body attitude: the z-y-x Euler angles perturbed,
/// Rz(y + dy) Ry(p + dp) Rx(r + dr) = exp([psi x]) Rz(y) Ry(p) Rx(r) to first order with
/// psi = dy e_z + dp Rz(y) e_y + dr Rz(y) Ry(p) e_x (columns roll, pitch, yaw).
fn euler_jacobian(attitude: &Attitude) -> Matrix3<f64> {
    let (_, p, y) = attitude.euler_rad();
    let (sy, cy) = y.sin_cos();
    let (sp, cp) = p.sin_cos();
    Matrix3::from_columns(&[
        Vector3::new(cy * cp, sy * cp, -sp),
        Vector3::new(-sy, cy, 0.0),
        Vector3::new(0.0, 0.0, 1.0),
    ])
}

/// An initial Euler-angle error on axis `axis` (0 roll, 1 pitch, 2 yaw) as an attitude source.
fn alignment_source(
    source: &LawSource,
    axis: usize,
    attitude: &Attitude,
) -> Result<Source, String> {
    let j = euler_jacobian(attitude).column(axis).into_owned();
    let (mean, var) = match source {
        LawSource::Bias(b) => (j * *b, 0.0),
        LawSource::RandomConstant(s) => (Vector3::zeros(), s * s),
        other => return Err(format!("an initial attitude error of kind {other:?}")),
    };
    let cov = j * j.transpose() * var;
    Ok(Source::Attitude {
        mean: mean.into(),
        cov: std::array::from_fn(|r| std::array::from_fn(|c| cov[(r, c)])),
    })
}

/// The laws of every channel at each of `times_s` (ascending), [time][`NavQuantity::ALL`], on
/// the round Earth `earth` for a static IMU of attitude `attitude`.
pub fn round_laws(
    terms: &[Term],
    ctx: &LawContext,
    earth: &RoundEarth,
    attitude: &Attitude,
    times_s: &[f64],
) -> Vec<Vec<Law>> {
    let n = NavQuantity::ALL.len();
    if !ctx.static_level {
        let why = format!("no closed-form law on the round Earth: {}", ctx.reason);
        return times_s
            .iter()
            .map(|_| vec![Law::NotApplicable(why.clone()); n])
            .collect();
    }
    let mut total = vec![ErrorMoments::zero(); times_s.len()];
    // A term without a law: a gyro's reaches every channel (Earth rate couples the attitude
    // errors, the attitude drives the velocity), an accelerometer's the velocity and position.
    let mut missing_all: Option<String> = None;
    let mut missing_nav: Option<String> = None;
    let mut not_gaussian = false;
    for term in terms {
        match sources(term, attitude) {
            Ok(list) => {
                for s in &list {
                    for (acc, m) in total.iter_mut().zip(moments(earth, attitude, s, times_s)) {
                        acc.add(&m);
                    }
                }
                not_gaussian |= matches!(term.source, LawSource::Sinusoid { phase: None, .. });
            }
            Err(why) => {
                let slot = if matches!(term.entry, Entry::Accel(_)) {
                    &mut missing_nav
                } else {
                    &mut missing_all
                };
                slot.get_or_insert_with(|| format!("{}: {why}", term.name));
            }
        }
    }
    // The vertical channel's response to a unit constant vertical specific-force error (for the
    // second-order tilt bound below); zero when the height is held.
    let unit_vertical = match earth.vertical {
        Vertical::Held => vec![ErrorMoments::zero(); times_s.len()],
        Vertical::Free => moments(
            earth,
            &Attitude::identity(),
            &Source::Bias {
                sensor: Sensor::Accel,
                value: [0.0, 0.0, 1.0],
            },
            times_s,
        ),
    };
    let (rn, re) = strapdown::earth::radii_m(earth.place.lat_rad);
    let frame = Frame {
        inv_rn: 1.0 / (rn + earth.place.height_m),
        inv_re: 1.0 / (re + earth.place.height_m),
        tan_lat: earth.place.lat_rad.tan(),
    };
    let jinv = euler_jacobian(attitude)
        .try_inverse()
        .unwrap_or_else(Matrix3::identity);
    total
        .iter()
        .zip(&unit_vertical)
        .zip(times_s)
        .map(|((m, unit), &t_s)| {
            channel_laws_of(
                t_s,
                m,
                &frame,
                unit,
                &jinv,
                ctx.gravity_mps2,
                missing_all.as_deref(),
                missing_nav.as_deref(),
                not_gaussian,
            )
        })
        .collect()
}

/// What turns a position error into the rotation between the computed and the true local frames.
struct Frame {
    inv_rn: f64,
    inv_re: f64,
    tan_lat: f64,
}

/// The laws of one time from the summed moments (NED states dr, dv, psi).
#[allow(clippy::too_many_arguments)]
fn channel_laws_of(
    t_s: f64,
    m: &ErrorMoments,
    frame: &Frame,
    unit_vertical: &ErrorMoments,
    jinv: &Matrix3<f64>,
    gravity_mps2: f64,
    missing_all: Option<&str>,
    missing_nav: Option<&str>,
    not_gaussian: bool,
) -> Vec<Law> {
    use NavQuantity::*;
    // The attitude error a navigator shows against the true local frame (what `nav_error`
    // measures: the estimate is relative to the frame at the computed place, the truth to the
    // frame at the true place) is phi = psi - dtheta in nav_error's sense (estimate =
    // exp([psi x]) truth): the computed frame is the true one turned by dtheta = (dr_E / (R_E + h),
    // -dr_N / (R_N + h), -dr_E tan L / (R_E + h)) (the transport rate integrated over the
    // position error), so the body's attitude relative to it, C_c = (I - [dtheta x]) C, carries
    // -dtheta (Titterton & Weston §12.2 relate the phi and psi angle forms the same way, in their
    // opposite sign convention). The Schuler feedback bounds the tilt phi while psi grows; the
    // Monte Carlo's roll and pitch follow phi (checked by the round-Earth tests). Euler errors from
    // phi.
    let mut readout = nalgebra::SMatrix::<f64, 3, 9>::zeros();
    for i in 0..3 {
        readout[(i, 6 + i)] = 1.0;
    }
    // -dtheta from (dr_N, dr_E).
    readout[(0, 1)] = -frame.inv_re;
    readout[(1, 0)] = frame.inv_rn;
    readout[(2, 1)] = frame.tan_lat * frame.inv_re;
    let readout = jinv * readout;
    let e_mean = readout * m.mean;
    let e_cov = readout * m.cov * readout.transpose();
    let value = |mean: f64, var: f64| Law::Value {
        mean,
        std: var.max(0.0).sqrt(),
        allowance: 0.0,
    };
    let worst_angle = (0..3)
        .map(|i| e_mean[i].hypot(e_cov[(i, i)].max(0.0).sqrt()))
        .fold(0.0, f64::max);
    let mut laws: Vec<Law> = NavQuantity::ALL
        .iter()
        .map(|&q| match q {
            Roll | Pitch | Yaw => {
                let i = q as usize;
                value(e_mean[i], e_cov[(i, i)])
            }
            PosNorth | PosEast | PosDown => {
                let i = q as usize - PosNorth as usize;
                value(m.mean[i], m.cov[(i, i)])
            }
            VelNorth | VelEast | VelDown => {
                let i = 3 + q as usize - VelNorth as usize;
                value(m.mean[i], m.cov[(i, i)])
            }
            PosHorizontal => horizontal(m, 0, not_gaussian),
            VelHorizontal => horizontal(m, 3, not_gaussian),
        })
        .collect();
    // The vertical channel's first-order law leaves out g (1 - cos eps) ~ g eps^2 / 2 of a tilt
    // eps (docs/model.md §1.2); with a free vertical channel it is driven like a vertical
    // specific-force error. Bound it with the final tilt mean square and withhold the law where
    // the bound exceeds 10 % of it.
    let tilt_ms = m.second_moment(6) + m.second_moment(7);
    let second_order = gravity_mps2 * tilt_ms / 2.0;
    for (q, i) in [(VelDown, 5), (PosDown, 2)] {
        if let Some(first) = laws[q as usize].rms() {
            let bound = second_order * unit_vertical.mean[i].abs();
            if bound > 0.1 * first {
                laws[q as usize] = Law::NotApplicable(format!(
                    "first-order law incomplete: the second-order tilt term g(1-cos eps) (docs/model.md §1.2) may reach {bound:.3e}, over 10 % of the law {first:.3e}"
                ));
            }
        }
    }
    // The other products the first-order model drops: an attitude error of size a composes with
    // another at O(a^2) (the angles' own readout) and turns the specific force by g a^2 / 2
    // (grown at most as on the flat Earth, t and t^2 / 2, the Schuler loop only bounds it). Where
    // a channel's first-order law is not far above them, as when it is driven only through Earth
    // rate (a heading error's roll, pitch and horizontal error early on), the law is withheld.
    let a2 = worst_angle * worst_angle;
    for (q, law) in NavQuantity::ALL.iter().zip(laws.iter_mut()) {
        let bound = match q {
            Roll | Pitch | Yaw => a2,
            VelNorth | VelEast | VelHorizontal => gravity_mps2 * a2 / 2.0 * t_s,
            PosNorth | PosEast | PosHorizontal => gravity_mps2 * a2 / 2.0 * t_s * t_s / 2.0,
            _ => 0.0,
        };
        if let Some(first) = law.rms() {
            if bound > 0.1 * first {
                *law = Law::NotApplicable(format!(
                    "first-order law incomplete: products of the attitude errors (up to {worst_angle:.3e} rad) may reach {bound:.3e}, over 10 % of the law {first:.3e}"
                ));
            } else if let Law::Value { allowance, .. } = law {
                // Below 10 %: the bound is the law's own stated uncertainty.
                *allowance = bound / first;
            }
        }
    }
    for (q, law) in NavQuantity::ALL.iter().zip(laws.iter_mut()) {
        let angle = matches!(q, Roll | Pitch | Yaw);
        if let Some(why) = missing_all.or(if angle { None } else { missing_nav }) {
            *law = Law::NotApplicable(format!("no closed-form law ({why})"));
        } else if worst_angle > SMALL_ANGLE_LIMIT_RAD {
            *law = Law::NotApplicable(format!(
                "small-angle law does not apply: predicted attitude error {worst_angle:.3} rad > {SMALL_ANGLE_LIMIT_RAD} rad"
            ));
        }
    }
    laws
}

/// Law of the horizontal magnitude of states `first` (north) and `first + 1` (east), correlated
/// on the rotating Earth (`laws::horizontal_magnitude`).
fn horizontal(m: &ErrorMoments, first: usize, not_gaussian: bool) -> Law {
    horizontal_magnitude(
        [m.mean[first], m.mean[first + 1]],
        [
            m.cov[(first, first)].max(0.0).sqrt(),
            m.cov[(first + 1, first + 1)].max(0.0).sqrt(),
        ],
        m.cov[(first, first + 1)],
        !not_gaussian,
    )
}
