//! The request layer: what a front end (the `imudrift` CLI, the Python package) asks of a command,
//! as a typed request with one `validate()`, one set of defaults and one error type
//! ([`RequestError`]) that names each setting through the front end's own names ([`Names`]: the
//! CLI's flags, the Python arguments). The front ends parse their arguments into a request and
//! render the answer; every rule between (file size limits, how a scenario and its sensor are
//! found, rates, run counts, memory and work limits, the thread pool) is written here once.
//!
//! Besides `logio`, this is the one library crate that reads files: the inputs a request names
//! (sensor models, scenarios), each with its size bound ([`files`]).
//!
//! ```
//! use request::{generate::GenerateRequest, Setting};
//! // A sensor's text, 2 s at 100 Hz: checked once, the same way for every front end.
//! let req = GenerateRequest {
//!     sensor: request::SensorSource::Text {
//!         text: "name = \"toy\"\n[gyro.all]\nwhite_noise = \"0.1 deg/sqrt(h)\"\n".into(),
//!         source: "toy.toml".into(),
//!     },
//!     duration_s: 2.0,
//!     rate_hz: 100.0,
//!     ..GenerateRequest::default()
//! };
//! let plan = req.validate().unwrap();
//! assert_eq!(plan.samples, 200);
//! // A bad rate names the setting the way the front end calls it.
//! let bad = GenerateRequest { rate_hz: -5.0, ..req };
//! let cli = |s: Setting| if s == Setting::Rate { "--rate" } else { "?" };
//! assert!(bad.validate().unwrap_err().render(&cli).starts_with("--rate: expected a sample rate"));
//! ```

pub mod allan;
pub mod diagnose;
pub mod error;
pub mod files;
pub mod generate;
pub mod logs;
pub mod pool;
pub mod setting;
mod shipped;
pub mod simulate;

pub use error::{RequestError, Result};
pub use files::{SensorSource, TextFile};
pub use setting::{Names, Setting};

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn shipped(path: &str) -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../..")
            .join(path)
    }

    /// A scenario file and a sensor file give the same experiment through the request as the
    /// shard format stores it; edits reach the scenario.
    #[test]
    fn a_simulate_request_builds_its_experiment_once() {
        let mut req = simulate::SimulateRequest::new(simulate::Subject::Path(shipped(
            "configs/scenarios/mtx-static-60s.toml",
        )));
        req.runs = Some(7);
        req.duration_s = Some(120.0);
        let job = req.validate().unwrap();
        assert_eq!(job.exp.runs, 7);
        assert_eq!(job.exp.scenario.duration_s, 120.0);
        assert!(job.sensor_path.unwrap().ends_with("sensors/mtx.toml"));
        assert!(job.inputs.scenario_toml.contains("duration_s = 120.0"));
        let sensor = simulate::SimulateRequest::new(simulate::Subject::Path(shipped(
            "configs/sensors/mtx.toml",
        )))
        .validate()
        .unwrap();
        assert!(sensor
            .inputs
            .scenario_source
            .starts_with("default static scenario for"));
    }

    /// Each setting is named the front end's way; a missing file is a file error that says so.
    #[test]
    fn errors_name_settings_through_the_front_end() {
        let mut req = simulate::SimulateRequest::new(simulate::Subject::Path(shipped(
            "configs/scenarios/mtx-static-60s.toml",
        )));
        req.rate_hz = Some(-1.0);
        let e = req.validate().err().unwrap();
        let cli = |s: Setting| if s == Setting::Rate { "--rate" } else { "?" };
        assert_eq!(
            e.render(&cli),
            "--rate: expected a sample rate in Hz > 0, found -1"
        );
        assert_eq!(
            e.to_string(),
            "rate_hz: expected a sample rate in Hz > 0, found -1"
        );
        req.rate_hz = None;
        req.runs = Some(0);
        let e = req.validate().err().unwrap();
        assert_eq!(e.render(&Setting::name), "runs: expected an integer >= 1");
        let missing = simulate::SimulateRequest::new(simulate::Subject::Path(shipped(
            "configs/no-such-file.toml",
        )))
        .validate()
        .err()
        .unwrap();
        assert!(missing.is_unreadable(), "{missing}");
        assert!(missing.to_string().contains("cannot read"), "{missing}");
    }

    /// The defaults are diagnose's own; the drift check runs by default with several logs.
    #[test]
    fn diagnose_and_drift_defaults_are_held_once() {
        let d = ::diagnose::Settings::default();
        let one = diagnose::DiagnoseRequest {
            logs: 1,
            ..Default::default()
        }
        .validate()
        .unwrap();
        assert_eq!(
            (one.seed, one.seeds, one.max_rounds),
            (d.seed, d.seeds, d.max_rounds)
        );
        assert_eq!(one.horizons_s, d.horizons_s);
        assert!(one.drift_protocol.is_none());
        let two = diagnose::DiagnoseRequest {
            logs: 2,
            ..Default::default()
        }
        .validate()
        .unwrap();
        assert!(two.drift_protocol.is_some());
        let seeds = diagnose::DiagnoseRequest {
            seeds: Some(1),
            ..Default::default()
        }
        .validate()
        .err()
        .unwrap();
        assert!(
            seeds.to_string().starts_with("seeds 1: at least 2"),
            "{seeds}"
        );
        let drift = diagnose::DriftRequest::default().validate().unwrap();
        assert_eq!(
            drift.protocol.horizons_s,
            diagnose::DRIFT_HORIZONS_S.to_vec()
        );
        assert_eq!(drift.replicates, diagnose::DRIFT_REPLICATES);
        let far = diagnose::DriftRequest {
            protocol: diagnose::ProtocolRequest {
                earth: diagnose::Earth::Latitude(95.0),
                ..Default::default()
            },
            ..Default::default()
        };
        assert!(far
            .validate()
            .err()
            .unwrap()
            .to_string()
            .starts_with("latitude 95"));
    }

    /// Samples an analysis cannot use are refused before it starts.
    #[test]
    fn unusable_samples_are_refused() {
        assert!(allan::check_samples(&[1.0, 2.0]).is_ok());
        for bad in [
            vec![0.0; 100],
            vec![1.0],
            vec![1.0, f64::NAN],
            vec![1.0, 1e200],
        ] {
            assert!(allan::check_samples(&bad).is_err(), "{bad:?}");
        }
        assert!(allan::check_samples_with_gaps(&[1.0, f64::NAN, 2.0]).is_ok());
        for bad in [
            vec![f64::NAN, 1.0, f64::NAN],
            vec![1.0, f64::NAN, 1.0],
            vec![1.0, f64::INFINITY, 2.0],
        ] {
            assert!(allan::check_samples_with_gaps(&bad).is_err(), "{bad:?}");
        }
        assert!(allan::check_rate(1e300).is_err());
        assert_eq!(allan::parse_confidence("95%").unwrap(), 0.95);
        assert!(allan::parse_confidence("1.5").is_err());
    }

    /// Tau lists in seconds: a time that is no time is refused by its index; times the samples
    /// cannot hold are dropped (allantools); a curve needs 2 usable taus and normal variances.
    #[test]
    fn tau_lists_and_curves_are_checked_once() {
        let grid = allan::factors_of_seconds(&[0.01, 0.02, 1e300], 100.0, 1000).unwrap();
        assert_eq!(grid, ::allan::TauGrid::Explicit(vec![1, 2]));
        for (bad, shown) in [(0.0, "0"), (-1.0, "-1"), (f64::NAN, "NaN"), (1e-300, "")] {
            let r = allan::factors_of_seconds(&[0.01, bad], 100.0, 1000);
            if shown.is_empty() {
                // 1e-300 s is a time: its factor rounds to 0 and is dropped, as allantools does.
                assert_eq!(r.unwrap(), ::allan::TauGrid::Explicit(vec![1]));
            } else {
                let e = r.err().unwrap().to_string();
                assert!(e.starts_with(&format!("taus[1] is {shown}: ")), "{e}");
            }
        }
        // Uniform noise from a multiplicative hash of the index (no generator needed: any
        // series that is not constant gives positive deviations).
        let white: Vec<f64> = (0..4000u64)
            .map(|i| {
                (i.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect();
        let curve = |scale: f64| {
            let x: Vec<f64> = white.iter().map(|v| v * scale).collect();
            ::allan::deviation(
                &x,
                ::allan::DataKind::Rate,
                0.01,
                ::allan::Estimator::Overlapping,
                &::allan::TauGrid::Octave,
            )
        };
        assert!(allan::check_curve("log", Some("gx"), 4000, &curve(1.0)).is_ok());
        let tiny = allan::check_curve("log", Some("gx"), 4000, &curve(1e-160))
            .err()
            .unwrap()
            .to_string();
        assert!(
            tiny.starts_with("log: the deviation of channel gx at tau 0.01 s is 0: its square"),
            "{tiny}"
        );
        let one = allan::check_curve("log", None, 4000, &curve(1.0)[..1])
            .err()
            .unwrap()
            .to_string();
        assert!(one.contains("give 1 averaging time(s)"), "{one}");
        assert!(allan::check_points("oadev", 3, &[]).is_err());
    }

    /// A model named by one text: an existing path is the file, TOML text is text, anything
    /// else a missing file (an unreadable one, like a directory).
    #[test]
    fn a_model_argument_is_a_path_or_a_text() {
        let dir = env!("CARGO_MANIFEST_DIR");
        assert!(matches!(
            SensorSource::of_argument(dir).unwrap(),
            SensorSource::Path(_)
        ));
        assert!(SensorSource::of_argument(dir).unwrap().read().is_err());
        assert!(matches!(
            SensorSource::of_argument("name = \"x\"").unwrap(),
            SensorSource::Text { .. }
        ));
        let missing = SensorSource::of_argument("no/such/model").err().unwrap();
        assert!(missing.is_unreadable());
        assert!(missing.to_string().contains("no such file"), "{missing}");
    }

    /// Series a front end holds become a log only when they are one: known names, one length.
    #[test]
    fn series_become_a_log_only_when_they_are_one() {
        let ok = logs::from_series(
            "<arrays>",
            100.0,
            vec![
                ("gx".into(), vec![0.1, 0.2, 0.3]),
                ("temp".into(), vec![20.0; 3]),
            ],
        )
        .unwrap();
        assert_eq!(ok.channel(noise::Channel::Gx), Some(&[0.1, 0.2, 0.3][..]));
        assert_eq!(ok.temperature_c.as_deref(), Some(&[20.0; 3][..]));
        let uneven = logs::from_series(
            "<arrays>",
            100.0,
            vec![("gx".into(), vec![0.1, 0.2, 0.3]), ("gy".into(), vec![0.1])],
        );
        assert!(uneven
            .err()
            .unwrap()
            .to_string()
            .contains("gy has 1 samples"));
        let constant =
            logs::from_series("<arrays>", 100.0, vec![("gx".into(), vec![0.0; 10])]).unwrap();
        let e = logs::check_imu(&constant).err().unwrap();
        assert!(e.to_string().contains("channel gx is constant"), "{e}");
    }
}
