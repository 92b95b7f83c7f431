//! Logs as every command that reads one takes them: the refusals every front end makes alike (no
//! gyro or accelerometer channel, a constant channel) and the log as diagnose and drift read it.

use crate::error::{LeaveOut, RequestError, Result};
use diagnose::input::LogInput;
use logio::Log;
use logio::Quantity;

/// A log from series a front end holds (`logio::Log::from_series`).
pub fn from_series(source: &str, rate_hz: f64, series: Vec<(String, Vec<f64>)>) -> Result<Log> {
    Log::from_series(source, rate_hz, series).map_err(RequestError::Series)
}

/// Refuse a log without a gyro or accelerometer channel, or with a constant one among them.
pub fn check_imu(log: &Log) -> Result<()> {
    if log.channels.iter().all(|(_, v)| v.is_none()) {
        return Err(RequestError::NoImuChannel {
            source_name: log.source.clone(),
            columns: log.order_names().join(", "),
        });
    }
    refuse_constant(
        log,
        log.order
            .iter()
            .copied()
            .filter(|q| matches!(q, Quantity::Imu(_))),
        LeaveOut::Column,
    )
}

/// Refuse a constant series among `quantities` of `log` (a stuck or disconnected sensor, a column
/// of zeros or of any one value, or values within `logio::MIN_SPREAD` of each other, whose
/// differences underflow when squared): it has no noise to analyse, and every command refuses it with
/// this one message; `leave_out` says how with the command's settings.
pub fn refuse_constant(
    log: &Log,
    quantities: impl IntoIterator<Item = Quantity>,
    leave_out: LeaveOut,
) -> Result<()> {
    for q in quantities {
        let Some((_, d)) = log.series().find(|(s, _)| *s == q) else {
            continue;
        };
        if let Some(&first) = d.first() {
            if !logio::has_spread(d) {
                return Err(RequestError::Constant {
                    source_name: log.source.clone(),
                    channel: q.channel(),
                    value: first,
                    spread: logio::spread(d),
                    leave_out,
                });
            }
        }
    }
    Ok(())
}

/// Refuse a run given twice: two of `logs` with the same samples in every gyro and accelerometer
/// channel (the same file twice, a link to it, a copy, or the same arrays) would count as two
/// runs and make every interval about sqrt(2) too narrow. Each log's samples are fingerprinted
/// (a hash of their bits, one pass); logs whose fingerprints agree are compared sample by sample,
/// so only identical content is refused.
pub fn refuse_repeated<'a>(logs: impl IntoIterator<Item = &'a Log>) -> Result<()> {
    let logs: Vec<&Log> = logs.into_iter().collect();
    let prints: Vec<u64> = logs.iter().map(|l| fingerprint(l)).collect();
    for (j, later) in logs.iter().enumerate() {
        for (i, earlier) in logs[..j].iter().enumerate() {
            if prints[i] == prints[j] && same_samples(earlier, later) {
                return Err(RequestError::RepeatedLog {
                    first: earlier.source.clone(),
                    second: later.source.clone(),
                });
            }
        }
    }
    Ok(())
}

/// A hash of the bits of every gyro and accelerometer sample of `log`, channel by channel (an
/// FNV-1a-style multiply and xor: a fingerprint for finding equal logs, which
/// [`same_samples`] then confirms; not a cryptographic hash).
fn fingerprint(log: &Log) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for (c, values) in log.channels.iter() {
        h = (h ^ c as u64).wrapping_mul(0x0000_0100_0000_01b3);
        for v in values.iter().flat_map(|v| v.iter()) {
            h = (h ^ v.to_bits()).wrapping_mul(0x0000_0100_0000_01b3);
        }
        h = (h ^ values.as_ref().map_or(u64::MAX, |v| v.len() as u64))
            .wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// Whether two logs hold the same gyro and accelerometer channels with the same samples.
fn same_samples(a: &Log, b: &Log) -> bool {
    a.channels
        .iter()
        .zip(b.channels.iter())
        .all(|((_, x), (_, y))| match (x, y) {
            (Some(x), Some(y)) => {
                x.len() == y.len() && x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits())
            }
            (None, None) => true,
            _ => false,
        })
}

/// The log as diagnose and drift read it (its temperature only where asked for).
pub fn log_input(log: &Log, temperature: bool) -> LogInput<'_> {
    LogInput {
        dt_s: log.dt_s(),
        channels: noise::ImuChannels::from_fn(|c| log.channel(c)),
        temperature_c: if temperature {
            log.temperature_c.as_deref()
        } else {
            None
        },
    }
}
