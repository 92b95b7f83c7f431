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
//!         text: "name = \"toy\"\n[gyro]\nwhite_noise = \"0.1 deg/sqrt(h)\"\n".into(),
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
//! assert!(bad.validate().unwrap_err().render(&cli).starts_with("--rate -5"));
//! ```

pub mod allan;
pub mod diagnose;
pub mod error;
pub mod files;
pub mod generate;
pub mod logs;
pub mod pool;
pub mod setting;
pub mod simulate;

pub use error::{RequestError, Result};
pub use files::{SensorSource, TextFile};
pub use setting::{Names, Setting};
