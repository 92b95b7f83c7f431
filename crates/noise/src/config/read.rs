//! Reading one config value: units parsed, ranges checked, errors naming the file, line, key and
//! what was expected. Used by the sensor file's own tables (`convert`) and by each term's reading
//! of its key (`terms/<effect>.rs`).

use super::error::ConfigError;
use crate::model_error::ModelError;
use crate::units::{parse_quantity, unit_part, Quantity, Signal};

/// A config value with its place in the file.
pub(crate) type Text = toml::Spanned<String>;

/// A whole number with its place in the file.
pub(crate) type Integer = toml::Spanned<i64>;

/// Conversion context: file name for errors.
pub(crate) struct Ctx<'a> {
    pub(crate) file: &'a str,
    pub(crate) source: &'a str,
}

impl Ctx<'_> {
    /// An error about `key`, at the line of `at` when the value exists.
    pub(crate) fn invalid_at(
        &self,
        key: &str,
        at: Option<&Text>,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> ConfigError {
        self.invalid_in_span(key, at.map(|t| t.span()), expected, found)
    }

    /// An error about `key`, at the line of the byte range `span` of the file when known.
    pub(crate) fn invalid_in_span(
        &self,
        key: &str,
        span: Option<std::ops::Range<usize>>,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> ConfigError {
        let line = span.map(|span| {
            let start = span.start.min(self.source.len());
            1 + self.source.as_bytes()[..start]
                .iter()
                .filter(|&&b| b == b'\n')
                .count()
        });
        ConfigError::Invalid {
            file: self.file.to_string(),
            line,
            key: key.to_string(),
            expected: expected.into(),
            found: found.into(),
        }
    }

    pub(crate) fn invalid(
        &self,
        key: &str,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> ConfigError {
        self.invalid_at(key, None, expected, found)
    }

    /// Parse a value with units; `nonneg` rejects negative values.
    pub(crate) fn value(
        &self,
        key: &str,
        text: &Text,
        q: Quantity,
        nonneg: bool,
    ) -> Result<f64, ConfigError> {
        let quoted = format!("\"{}\"", text.get_ref());
        let v = parse_quantity(text.get_ref(), q).map_err(|e| {
            self.invalid_at(
                key,
                Some(text),
                format!("a value in {} such as {} ({e})", q.si_unit(), q.example()),
                quoted.clone(),
            )
        })?;
        if nonneg && v < 0.0 {
            return Err(self.invalid_at(key, Some(text), "a value >= 0", quoted));
        }
        Ok(v)
    }

    /// A rate of events per hour: `"60 /h"`, `"2 /min"`, `"0.01 /s"`, any frequency unit
    /// (`"1/h"`, `"0.01 Hz"`), or a plain number meaning per hour. A value per hour keeps its bits.
    pub(crate) fn per_hour(&self, key: &str, text: &Text) -> Result<f64, ConfigError> {
        let quoted = format!("\"{}\"", text.get_ref());
        let err = |why: String| {
            self.invalid_at(
                key,
                Some(text),
                format!("a number of events per time such as \"60 /h\", \"2 /min\", \"0.01 /s\", or a plain number per hour ({why})"),
                quoted.clone(),
            )
        };
        let all = text.get_ref().trim();
        let unit = unit_part(all);
        let value = parse_quantity(&all[..all.len() - unit.len()], Quantity::Ratio)
            .map_err(|e| err(e.to_string()))?;
        let unit = unit.trim();
        let factor = if unit.is_empty() {
            1.0
        } else {
            // "/h" reads as "1/h".
            let expr = if unit.starts_with('/') {
                format!("1 1{unit}")
            } else {
                format!("1 {unit}")
            };
            let per_hour = 3600.0
                * parse_quantity(&expr, Quantity::Frequency).map_err(|e| err(e.to_string()))?;
            if (per_hour - 1.0).abs() < 1e-12 {
                1.0
            } else {
                per_hour
            }
        };
        let v = value * factor;
        if !v.is_finite() || v < 0.0 {
            return Err(self.invalid_at(key, Some(text), "a rate >= 0", quoted));
        }
        Ok(v)
    }

    pub(crate) fn positive(&self, key: &str, text: &Text, q: Quantity) -> Result<f64, ConfigError> {
        let v = self.value(key, text, q, true)?;
        if v == 0.0 {
            let quoted = format!("\"{}\"", text.get_ref());
            return Err(self.invalid_at(key, Some(text), "a value > 0", quoted));
        }
        Ok(v)
    }
}

/// What a term reads its key with: the file, the key's full name (`gyro.x.white_noise`, or
/// `gyro.all.white_noise` when the value comes from the `all` table), the axis' signal and the
/// terms of the axis read before it (bias instability's `allan_minimum` convention needs them),
/// with the position of the effect being read in `Effect::ALL`.
pub struct ReadContext<'a> {
    pub(crate) ctx: &'a Ctx<'a>,
    pub(crate) key: String,
    pub(crate) sig: Signal,
    pub(crate) others: &'a dyn OtherTerms,
    pub(crate) position: usize,
}

/// The terms of an axis read before a term that reads them, as that term sees them: the axis
/// model (`AxisModel`) implements it. A trait, as the terms cannot name the model made of them.
pub(crate) trait OtherTerms {
    /// The axis' closed-form Allan variance at `tau_s` (`AxisModel::allan_variance`, summed in
    /// `Effect` order) with `avar` as the Allan variance of the term at `position`.
    fn allan_variance_with(&self, position: usize, avar: Option<f64>, tau_s: f64) -> f64;
}

impl ReadContext<'_> {
    /// The name of a key inside this one's table, e.g. `gyro.x.gauss_markov.sigma`.
    pub(crate) fn sub(&self, name: &str) -> String {
        format!("{}.{name}", self.key)
    }

    /// This key's value with units (`nonneg` rejects negative values).
    pub(crate) fn value(&self, text: &Text, q: Quantity, nonneg: bool) -> Result<f64, ConfigError> {
        self.ctx.value(&self.key, text, q, nonneg)
    }

    /// The value of `name` inside this key's table.
    pub(crate) fn sub_value(
        &self,
        name: &str,
        text: &Text,
        q: Quantity,
        nonneg: bool,
    ) -> Result<f64, ConfigError> {
        self.ctx.value(&self.sub(name), text, q, nonneg)
    }

    /// The value of `name` inside this key's table, > 0.
    pub(crate) fn sub_positive(
        &self,
        name: &str,
        text: &Text,
        q: Quantity,
    ) -> Result<f64, ConfigError> {
        self.ctx.positive(&self.sub(name), text, q)
    }

    /// A value the term's constructor refuses, reported at `key`.
    pub(crate) fn refused(&self, key: &str, e: ModelError) -> ConfigError {
        self.ctx.invalid(
            key,
            e.expected,
            format!("{:.4e} in SI units ({})", e.found, e.what),
        )
    }
}

/// `value` (SI) written in the unit of `like` (a config value such as "0.01 deg/h"), for messages.
pub(crate) fn in_units_of(value: f64, like: &str, q: Quantity) -> String {
    let unit = like
        .trim()
        .trim_start_matches(|c: char| c.is_ascii_digit() || "+-.eE".contains(c))
        .trim();
    match parse_quantity(&format!("1 {unit}"), q) {
        Ok(factor) if !unit.is_empty() => format!("{:.4} {unit}", value / factor),
        _ => format!("{value:.4e} {}", q.si_unit()),
    }
}
