//! Unit plausibility: what a log's values say about the units it was read in. A warning (on
//! stderr, the command goes on) where the data tell: a static accelerometer's magnitude near
//! 1 m/s^2 (a log in g read as m/s^2) or near 96 m/s^2 (in m/s^2 read as g); a gyro whose noise
//! density or rates no gyro has in the unit it was read in (a log in deg/s read as rad/s).

use logio::{Log, Quantity};
use noise::{Channel, Sensor};

/// Standard gravity, m/s^2 (noise::units, CGPM 1901).
const G: f64 = noise::units::STANDARD_GRAVITY_MPS2;

/// The noisiest gyro datasheets give about 0.1 deg/s/sqrt(Hz) (consumer MEMS, e.g. 0.07 for the
/// MPU-6050 class, 0.05 for the ADIS16405); ten times that, in rad/s/sqrt(Hz), is no gyro's.
const MAX_GYRO_NOISE_RAD_PER_SQRT_S: f64 = 1.0 * std::f64::consts::PI / 180.0;

/// The widest MEMS gyro range is +-2000 deg/s (34.9 rad/s): a typical |rate| beyond it is no
/// gyro's reading in rad/s.
const MAX_GYRO_RATE_RAD_S: f64 = 2000.0 * std::f64::consts::PI / 180.0;

/// The warnings a log's values raise about its units (empty when they look right).
pub fn warnings(log: &Log) -> Vec<String> {
    let mut w = Vec::new();
    if let Some(text) = accel_magnitude(log) {
        w.push(text);
    }
    for ch in Channel::of(Sensor::Gyro) {
        if let Some(text) = log.channel(ch).and_then(|d| gyro_check(log, ch, d)) {
            w.push(text);
        }
    }
    w
}

/// Print the warnings on stderr (`warning: ...`), the convention for warnings (docs/cli.md).
pub fn print(log: &Log) {
    for w in warnings(log) {
        tell!("warning: {w}");
    }
}

/// How a channel's unit was chosen, for the message ("the unit deg/s from the column name").
fn unit_said(log: &Log, ch: Channel) -> String {
    log.columns
        .iter()
        .find(|c| c.quantity == Quantity::Imu(ch))
        .map_or_else(String::new, |c| {
            format!(" (column {}, read as {})", c.column, c.unit)
        })
}

/// The mean magnitude of the accelerometer vector over the log (samples with all three axes):
/// standard gravity on a log at rest, about it on a moving one.
fn accel_magnitude(log: &Log) -> Option<String> {
    let [x, y, z] = Channel::of(Sensor::Accel).map(|c| log.channel(c));
    let (x, y, z) = (x?, y?, z?);
    let n = x.len().min(y.len()).min(z.len());
    if n == 0 {
        return None;
    }
    // The mean magnitude summed as the samples come (`stats::mean`'s order) rather than through
    // a copy of the log's length: a log may fill most of the memory its reader allowed.
    let mean = (0..n)
        .map(|k| (x[k] * x[k] + y[k] * y[k] + z[k] * z[k]).sqrt())
        .sum::<f64>()
        / n as f64;
    let ratio = mean / G;
    let near = |target: f64| (ratio / target).ln().abs() < 0.25f64.ln_1p();
    let said = unit_said(log, Channel::Ax);
    let hint = if near(1.0) {
        return None;
    } else if near(1.0 / G) {
        "near 1, as a log in g reads: if it is in g, say so with --accel-unit g"
    } else if near(G) {
        "near 9.8 g: a log in m/s^2 read as g? say --accel-unit m/s^2"
    } else if near(1e3) {
        "near 1000 g: a log in mg read as g? say --accel-unit mg"
    } else if near(1e-3) {
        "near 1 mg: a log in g read as mg? say --accel-unit g"
    } else {
        "far from standard gravity (9.807 m/s^2); check the accelerometer unit (--accel-unit)"
    };
    Some(format!(
        "{}: the accelerometer's mean magnitude is {} m/s^2 ({} g){said}, {hint}",
        log.source,
        crate::fmt::sig(mean, 4),
        crate::fmt::sig(ratio, 4),
    ))
}

/// A gyro channel whose noise density (from sample-to-sample differences: Var(y_k+1 - y_k) =
/// 2 N^2 / dt for white rate noise, IEEE 952 Annex C) or typical rate no gyro has in rad/s.
fn gyro_check(log: &Log, ch: Channel, d: &[f64]) -> Option<String> {
    if d.len() < 3 {
        return None;
    }
    let dt = 1.0 / log.rate_hz;
    // The mean square of the differences (about 0, not their sample variance), summed as they
    // come rather than through a copy for `stats::mean_square` (as the mean magnitude above).
    let diff_var = d.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>() / (d.len() - 1) as f64;
    let n = (diff_var * dt / 2.0).sqrt();
    let rms = stats::rms(d);
    let said = unit_said(log, ch);
    if rms > MAX_GYRO_RATE_RAD_S {
        return Some(format!(
            "{}: {ch} has an rms rate of {} rad/s{said}, beyond any gyro's range (+-2000 deg/s = 34.9 rad/s): is the log in deg/s? say so with --gyro-unit deg/s",
            log.source,
            crate::fmt::sig(rms, 3)
        ));
    }
    if n > MAX_GYRO_NOISE_RAD_PER_SQRT_S {
        return Some(format!(
            "{}: {ch} reads a white noise of {} deg/s/sqrt(Hz) ({} deg/sqrt(h)){said}, ten times the noisiest gyro datasheets (about 0.1 deg/s/sqrt(Hz)): is the log in deg/s? say so with --gyro-unit deg/s",
            log.source,
            crate::fmt::sig(n.to_degrees(), 3),
            crate::fmt::sig(n.to_degrees() * 60.0, 3)
        ));
    }
    None
}
