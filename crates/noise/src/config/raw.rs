//! The TOML document as written (serde), before units and validation.

use super::read::Text;
use crate::terms::RawAxis;
use serde::Deserialize;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSensor {
    pub(super) name: String,
    pub(super) description: Option<String>,
    pub(super) temperature: Option<RawTemperature>,
    pub(super) gyro: Option<RawTriad>,
    pub(super) accel: Option<RawTriad>,
    /// What a fitted model's levels were estimated from (`imudrift diagnose` writes it): read by
    /// the diagnose crate (`diagnose::fitted_on`), not a part of the error model.
    #[allow(dead_code)]
    pub(super) fitted_on: Option<serde::de::IgnoredAny>,
    /// The structures a fitted model's evidence could not tell apart (`imudrift diagnose` writes
    /// them): read by the diagnose crate (`diagnose::alternatives`), not a part of the error model.
    #[allow(dead_code)]
    pub(super) alternatives: Option<serde::de::IgnoredAny>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTemperature {
    pub(super) profile: Text,
    pub(super) reference: Option<Text>,
    pub(super) value: Option<Text>,
    pub(super) start: Option<Text>,
    pub(super) end: Option<Text>,
    pub(super) rate: Option<Text>,
    pub(super) time_constant: Option<Text>,
    pub(super) mean: Option<Text>,
    pub(super) amplitude: Option<Text>,
    pub(super) period: Option<Text>,
    pub(super) at: Option<Text>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTriad {
    pub(super) all: Option<RawAxis>,
    pub(super) x: Option<RawAxis>,
    pub(super) y: Option<RawAxis>,
    pub(super) z: Option<RawAxis>,
}
