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
