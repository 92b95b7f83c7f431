//! Trajectory specifications from TOML (raw serde structs, validated into [`AnyTrajectory`]).
//!
//! Units are in the key names (plain numbers): angles `*_deg`, rates `*_deg_s`, times `*_s`,
//! accelerations `*_mps2`, velocities `*_mps`, positions `*_m`, frequencies `*_hz`. Example:
//!
//! ```toml
//! kind = "profile"
//! [initial]
//! yaw_deg = 90.0
//! [[segments]]
//! kind = "hold"
//! duration_s = 10.0
//! [[segments]]
//! kind = "rotate"
//! duration_s = 9.0
//! axis = [0.0, 0.0, 1.0]     # body frame, normalised on load
//! rate_deg_s = 10.0
//! [[segments]]
//! kind = "accelerate"
//! duration_s = 5.0
//! accel_body_mps2 = [2.0, 0.0, 0.0]
//! ```

use crate::frames::{Attitude, BodyVector, NavVector};
use crate::mechanisation::NavState;
use crate::trajectory::{AnyTrajectory, Coning, ConstantRate, Profile, Segment, Static};
use crate::STANDARD_GRAVITY_MPS2;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// A trajectory as written in a scenario file, tagged by `kind`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum TrajectorySpec {
    /// At rest; level unless roll/pitch are given.
    Static {
        #[serde(default)]
        roll_deg: f64,
        #[serde(default)]
        pitch_deg: f64,
        #[serde(default)]
        yaw_deg: f64,
    },
    /// At rest, rotating at a constant body rate from the given initial attitude.
    ConstantRate {
        #[serde(default)]
        roll_deg: f64,
        #[serde(default)]
        pitch_deg: f64,
        #[serde(default)]
        yaw_deg: f64,
        rate_deg_s: [f64; 3],
    },
    /// Classical coning at rest.
    Coning {
        half_angle_deg: f64,
        frequency_hz: f64,
    },
    /// Piecewise hold / rotate / accelerate.
    Profile {
        #[serde(default)]
        initial: InitialSpec,
        segments: Vec<SegmentSpec>,
    },
}

/// Initial state of a profile.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialSpec {
    #[serde(default)]
    pub roll_deg: f64,
    #[serde(default)]
    pub pitch_deg: f64,
    #[serde(default)]
    pub yaw_deg: f64,
    #[serde(default)]
    pub velocity_ned_mps: [f64; 3],
    #[serde(default)]
    pub position_ned_m: [f64; 3],
}

/// One profile segment as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum SegmentSpec {
    Hold {
        duration_s: f64,
    },
    Rotate {
        duration_s: f64,
        axis: [f64; 3],
        rate_deg_s: f64,
    },
    Accelerate {
        duration_s: f64,
        accel_body_mps2: [f64; 3],
    },
}

/// The profile part of a file: `[initial]` and `[[segments]]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ProfileFile {
    #[serde(default)]
    initial: InitialSpec,
    segments: Vec<SegmentSpec>,
}

/// A trajectory configuration error, naming the source and/or key and what was expected.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TrajectoryError {
    /// The TOML did not parse or did not match the schema (the message carries line and key).
    #[error("{source_name}: {message}")]
    Parse {
        source_name: String,
        message: String,
    },
    /// A value is out of range.
    #[error("key `{key}`: expected {expected}, got {got}")]
    Invalid {
        key: String,
        expected: String,
        got: String,
    },
}

impl TrajectoryError {
    /// Prefix the key (e.g. `trajectory.`) when the spec sits inside a larger file.
    pub fn with_key_prefix(self, prefix: &str) -> TrajectoryError {
        match self {
            TrajectoryError::Invalid { key, expected, got } => TrajectoryError::Invalid {
                key: format!("{prefix}{key}"),
                expected,
                got,
            },
            other => other,
        }
    }
}

fn invalid(key: impl Into<String>, expected: &str, got: impl std::fmt::Debug) -> TrajectoryError {
    TrajectoryError::Invalid {
        key: key.into(),
        expected: expected.into(),
        got: format!("{got:?}"),
    }
}

fn finite(key: &str, x: f64) -> Result<f64, TrajectoryError> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(invalid(key, "a finite number", x))
    }
}

fn positive(key: &str, x: f64) -> Result<f64, TrajectoryError> {
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(invalid(key, "a positive finite number", x))
    }
}

fn finite3(key: &str, v: [f64; 3]) -> Result<Vector3<f64>, TrajectoryError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(Vector3::from(v))
    } else {
        Err(invalid(key, "three finite numbers", v))
    }
}

fn attitude(
    prefix: &str,
    roll_deg: f64,
    pitch_deg: f64,
    yaw_deg: f64,
) -> Result<Attitude, TrajectoryError> {
    let r = finite(&format!("{prefix}roll_deg"), roll_deg)?;
    let p = finite(&format!("{prefix}pitch_deg"), pitch_deg)?;
    let y = finite(&format!("{prefix}yaw_deg"), yaw_deg)?;
    Ok(Attitude::from_euler_rad(
        r.to_radians(),
        p.to_radians(),
        y.to_radians(),
    ))
}

fn parse_toml<T: serde::de::DeserializeOwned>(
    text: &str,
    source_name: &str,
) -> Result<T, TrajectoryError> {
    toml::from_str(text).map_err(|e| TrajectoryError::Parse {
        source_name: source_name.to_string(),
        message: e.to_string(),
    })
}

fn build_profile(
    initial: &InitialSpec,
    segments: &[SegmentSpec],
) -> Result<Profile, TrajectoryError> {
    let state = NavState {
        attitude: attitude(
            "initial.",
            initial.roll_deg,
            initial.pitch_deg,
            initial.yaw_deg,
        )?,
        velocity: NavVector(finite3(
            "initial.velocity_ned_mps",
            initial.velocity_ned_mps,
        )?),
        position: NavVector(finite3("initial.position_ned_m", initial.position_ned_m)?),
    };
    let mut out = Vec::with_capacity(segments.len());
    for (i, seg) in segments.iter().enumerate() {
        let key = |name: &str| format!("segments[{i}].{name}");
        out.push(match *seg {
            SegmentSpec::Hold { duration_s } => Segment::Hold {
                duration_s: positive(&key("duration_s"), duration_s)?,
            },
            SegmentSpec::Rotate {
                duration_s,
                axis,
                rate_deg_s,
            } => {
                let axis_v = finite3(&key("axis"), axis)?;
                let norm = axis_v.norm();
                if norm == 0.0 {
                    return Err(invalid(key("axis"), "a non-zero body-frame axis", axis));
                }
                Segment::Rotate {
                    duration_s: positive(&key("duration_s"), duration_s)?,
                    axis_body: BodyVector(axis_v / norm),
                    rate_rad_s: finite(&key("rate_deg_s"), rate_deg_s)?.to_radians(),
                }
            }
            SegmentSpec::Accelerate {
                duration_s,
                accel_body_mps2,
            } => Segment::Accelerate {
                duration_s: positive(&key("duration_s"), duration_s)?,
                accel_body_mps2: BodyVector(finite3(&key("accel_body_mps2"), accel_body_mps2)?),
            },
        });
    }
    Ok(Profile::new(state, out))
}

impl TrajectorySpec {
    /// Parse a TOML table that is a trajectory spec (with `kind = ...`).
    pub fn from_toml_str(text: &str, source_name: &str) -> Result<TrajectorySpec, TrajectoryError> {
        parse_toml(text, source_name)
    }

    /// Validate into a trajectory with standard gravity. Keys in errors are relative to the trajectory
    /// table (prefix them with [`TrajectoryError::with_key_prefix`]).
    pub fn build(&self) -> Result<AnyTrajectory, TrajectoryError> {
        self.build_with_gravity(STANDARD_GRAVITY_MPS2)
    }

    /// [`TrajectorySpec::build`] with another gravity magnitude (m/s^2, key `gravity_mps2` if invalid):
    /// the ideal accelerometer outputs must use the gravity the mechanisation compensates.
    pub fn build_with_gravity(&self, gravity_mps2: f64) -> Result<AnyTrajectory, TrajectoryError> {
        let g = positive("gravity_mps2", gravity_mps2)?;
        Ok(match self {
            TrajectorySpec::Static {
                roll_deg,
                pitch_deg,
                yaw_deg,
            } => AnyTrajectory::Static(Static {
                attitude: attitude("", *roll_deg, *pitch_deg, *yaw_deg)?,
                gravity_mps2: g,
            }),
            TrajectorySpec::ConstantRate {
                roll_deg,
                pitch_deg,
                yaw_deg,
                rate_deg_s,
            } => AnyTrajectory::ConstantRate(ConstantRate {
                initial: attitude("", *roll_deg, *pitch_deg, *yaw_deg)?,
                rate_body_rad_s: BodyVector(
                    finite3("rate_deg_s", *rate_deg_s)?.map(f64::to_radians),
                ),
                gravity_mps2: g,
            }),
            TrajectorySpec::Coning {
                half_angle_deg,
                frequency_hz,
            } => {
                let th = finite("half_angle_deg", *half_angle_deg)?;
                if !(th > 0.0 && th < 90.0) {
                    return Err(invalid(
                        "half_angle_deg",
                        "a cone half-angle in (0, 90) degrees",
                        th,
                    ));
                }
                AnyTrajectory::Coning(Coning {
                    half_angle_rad: th.to_radians(),
                    frequency_rad_s: std::f64::consts::TAU
                        * positive("frequency_hz", *frequency_hz)?,
                    gravity_mps2: g,
                })
            }
            TrajectorySpec::Profile { initial, segments } => {
                AnyTrajectory::Profile(build_profile(initial, segments)?.with_gravity(g))
            }
        })
    }
}

impl Profile {
    /// Parse a profile file (`[initial]` table and `[[segments]]` array) and validate it.
    pub fn from_toml_str(text: &str, source_name: &str) -> Result<Profile, TrajectoryError> {
        let file: ProfileFile = parse_toml(text, source_name)?;
        build_profile(&file.initial, &file.segments).map_err(|e| match e {
            TrajectoryError::Invalid { key, expected, got } => TrajectoryError::Invalid {
                key: format!("{source_name}: {key}"),
                expected,
                got,
            },
            other => other,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Trajectory;

    #[test]
    fn parses_every_kind() {
        let s =
            TrajectorySpec::from_toml_str("kind = \"static\"\npitch_deg = 10.0", "t.toml").unwrap();
        assert!(s.build().unwrap().is_static());
        let s =
            TrajectorySpec::from_toml_str("kind = \"constant_rate\"\nrate_deg_s = [0, 0, 10]", "t")
                .unwrap();
        assert!(matches!(s.build().unwrap(), AnyTrajectory::ConstantRate(_)));
        let s = TrajectorySpec::from_toml_str(
            "kind = \"coning\"\nhalf_angle_deg = 5\nfrequency_hz = 1",
            "t",
        )
        .unwrap();
        assert!(matches!(s.build().unwrap(), AnyTrajectory::Coning(_)));
        let text = "kind = \"profile\"\n[initial]\nyaw_deg = 90\n[[segments]]\nkind = \"hold\"\nduration_s = 1\n\
                    [[segments]]\nkind = \"rotate\"\nduration_s = 2\naxis = [0, 0, 2]\nrate_deg_s = 45\n\
                    [[segments]]\nkind = \"accelerate\"\nduration_s = 3\naccel_body_mps2 = [1, 0, 0]\n";
        match TrajectorySpec::from_toml_str(text, "t")
            .unwrap()
            .build()
            .unwrap()
        {
            AnyTrajectory::Profile(p) => {
                assert_eq!(p.segments().len(), 3);
                assert_eq!(p.duration_s(), 6.0);
            }
            other => panic!("expected a profile, got {other:?}"),
        }
    }

    #[test]
    fn spec_round_trips_through_toml() {
        let text = include_str!("../tests/data/profile.toml");
        let spec =
            TrajectorySpec::from_toml_str(&format!("kind = \"profile\"\n{text}"), "t").unwrap();
        let written = toml::to_string(&spec).unwrap();
        assert_eq!(
            TrajectorySpec::from_toml_str(&written, "written").unwrap(),
            spec,
            "{written}"
        );
    }

    #[test]
    fn errors_name_the_key() {
        let e = TrajectorySpec::from_toml_str(
            "kind = \"coning\"\nhalf_angle_deg = 5\nfreq = 1",
            "scn.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("scn.toml") && e.contains("freq"), "{e}");
        let e = TrajectorySpec::from_toml_str("kind = \"spinning\"", "scn.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("spinning"), "{e}");
        let text = "kind = \"profile\"\n[[segments]]\nkind = \"hold\"\nduration_s = -1\n";
        let e = TrajectorySpec::from_toml_str(text, "t")
            .unwrap()
            .build()
            .unwrap_err();
        let msg = e.clone().with_key_prefix("trajectory.").to_string();
        assert!(
            msg.contains("trajectory.segments[0].duration_s") && msg.contains("positive"),
            "{msg}"
        );
        let text =
            "[[segments]]\nkind = \"rotate\"\nduration_s = 1\naxis = [0, 0, 0]\nrate_deg_s = 1\n";
        let msg = Profile::from_toml_str(text, "p.toml")
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("p.toml") && msg.contains("segments[0].axis"),
            "{msg}"
        );
        let text = "[[segments]]\nkind = \"hold\"\nduration_s = 1\nrate = 3\n";
        let msg = Profile::from_toml_str(text, "p.toml")
            .unwrap_err()
            .to_string();
        assert!(msg.contains("rate") && msg.contains("line"), "{msg}");
    }
}
