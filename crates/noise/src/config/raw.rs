//! The TOML document as written (serde), before units and validation.

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
}

/// A config value with its place in the file.
pub(super) type Text = toml::Spanned<String>;

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

#[derive(Deserialize, Default, Clone)]
#[serde(deny_unknown_fields)]
pub(super) struct RawAxis {
    pub(super) quantization: Option<Text>,
    pub(super) white_noise: Option<Text>,
    pub(super) bias_instability: Option<toml::Spanned<RawBiasField>>,
    pub(super) rate_random_walk: Option<Text>,
    pub(super) rate_ramp: Option<Text>,
    pub(super) gauss_markov: Option<RawGaussMarkov>,
    pub(super) sinusoidal: Option<RawSinusoid>,
    pub(super) temperature_bias: Option<Text>,
    pub(super) constant_bias: Option<Text>,
    pub(super) turn_on_bias: Option<Text>,
    pub(super) scale_factor: Option<Text>,
    pub(super) misalignment: Option<Vec<Text>>,
    pub(super) output_filter: Option<RawOutputFilter>,
    pub(super) outliers: Option<RawOutliers>,
    pub(super) warmup_transient: Option<RawWarmupTransient>,
    pub(super) resonance: Option<RawResonance>,
}

/// What `bias_instability` may be: a value with a unit (the Allan-deviation minimum, as spec
/// sheets quote "in-run bias stability") or the table form with its convention stated.
#[derive(Clone)]
pub(super) enum RawBiasField {
    Plain(String),
    Table(Box<RawBiasInstability>),
}

/// The accepted forms, for error messages.
pub(super) const BIAS_INSTABILITY_FORMS: &str = "a value with a unit, e.g. bias_instability = \"10 deg/h\" (the Allan-deviation minimum, as spec sheets quote in-run bias stability), or a table: { value = \"10 deg/h\", convention = \"allan_minimum\" | \"ieee\" }, or { model = \"random_walk\", stability = \"36 ug\", period = \"800 s\" }";

impl<'de> Deserialize<'de> for RawBiasField {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = RawBiasField;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(BIAS_INSTABILITY_FORMS)
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<RawBiasField, E> {
                Ok(RawBiasField::Plain(v.to_string()))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<RawBiasField, A::Error> {
                RawBiasInstability::deserialize(serde::de::value::MapAccessDeserializer::new(map))
                    .map(|t| RawBiasField::Table(Box::new(t)))
            }
        }
        d.deserialize_any(V)
    }
}

impl RawBiasField {
    /// The table form; a plain value becomes `{ value, convention = "allan_minimum" }` with the
    /// value's place in the file.
    pub(super) fn table(field: &toml::Spanned<RawBiasField>) -> RawBiasInstability {
        match field.get_ref() {
            RawBiasField::Table(t) => (**t).clone(),
            RawBiasField::Plain(v) => RawBiasInstability {
                model: None,
                value: Some(toml::Spanned::new(field.span(), v.clone())),
                convention: Some(toml::Spanned::new(field.span(), "allan_minimum".into())),
                band: None,
                per_decade: None,
                stability: None,
                period: None,
            },
        }
    }
}

#[derive(Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBiasInstability {
    pub(super) model: Option<Text>,
    pub(super) value: Option<Text>,
    pub(super) convention: Option<Text>,
    pub(super) band: Option<Vec<Text>>,
    pub(super) per_decade: Option<i64>,
    pub(super) stability: Option<Text>,
    pub(super) period: Option<Text>,
}

#[derive(Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub(super) struct RawGaussMarkov {
    pub(super) sigma: Text,
    pub(super) time_constant: Text,
}

#[derive(Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSinusoid {
    pub(super) amplitude: Text,
    pub(super) frequency: Text,
    pub(super) phase: Option<Text>,
}

/// A whole number with its place in the file.
pub(super) type Integer = toml::Spanned<i64>;

#[derive(Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub(super) struct RawOutputFilter {
    pub(super) kind: Text,
    pub(super) taps: Option<Integer>,
    pub(super) cutoff: Option<Text>,
    pub(super) decimation: Option<Integer>,
}

#[derive(Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub(super) struct RawOutliers {
    pub(super) rate: Text,
    pub(super) size: Text,
}

#[derive(Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub(super) struct RawWarmupTransient {
    pub(super) amplitude: Text,
    pub(super) time_constant: Text,
    pub(super) per_run: Option<bool>,
}

#[derive(Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub(super) struct RawResonance {
    pub(super) sigma: Text,
    pub(super) frequency: Text,
    pub(super) bandwidth: Text,
}
