//! Bias instability: flicker (1/f) noise as IEEE 952 defines it, realised as a band of Gauss-Markov
//! processes, or Woodman's bias random walk (TR-696 §3.2.3).

use super::gauss_markov::BankGenerator;
use super::rate_random_walk::RandomWalkGenerator;
use super::term::{
    note_value_units, ErrorTerm, GenContext, Generate, RawClock, Stage, TermKind, WriteContext,
};
use crate::closed_form as cf;
use crate::config::error::ConfigError;
use crate::config::read::{in_units_of, OtherTerms, ReadContext, Text};
use crate::discrete::RandomWalk;
use crate::filter::FilteredAllan;
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check, ModelError};
use crate::units::{Quantity, Signal};
use crate::ImuRng;

/// Flicker (1/f) bias instability of IEEE coefficient B, generated as a sum of log-spaced
/// Gauss-Markov processes with correlation times spanning `[tau_min_s, tau_max_s]`
/// (docs/model.md §3, kshana `Flicker`: equal variance sigma_0^2 = B^2 ln(rho) / pi each).
/// The Allan plateau 0.664 B holds for averaging times in [30 tau_min, tau_max / 30] (see `per_decade`).
#[derive(Clone, Debug, PartialEq)]
pub struct Flicker {
    /// IEEE coefficient B (signal units); the Allan plateau is 0.6643 B.
    b: f64,
    /// Shortest correlation time of the band, s.
    tau_min_s: f64,
    /// Longest correlation time of the band, s.
    tau_max_s: f64,
    /// Gauss-Markov components per decade of correlation time. Over averaging times
    /// [30 tau_min, tau_max / 30] the closed-form Allan deviation of the sum stays within
    /// 0.987 .. 1.010 of 0.664 B with 1 per decade and 0.987 .. 1.000 with 2 (checked numerically).
    per_decade: u32,
}

impl Flicker {
    /// Default band: 0.1 s to 1e5 s, a plateau over 3 s .. 3333 s, covering the averaging times where a
    /// 12 h log of a MEMS sensor shows its bias instability.
    pub const DEFAULT_TAU_MIN_S: f64 = 0.1;
    pub const DEFAULT_TAU_MAX_S: f64 = 1e5;
    /// One per decade: as flat as two within the plateau (see `per_decade`), at half the cost per sample.
    pub const DEFAULT_PER_DECADE: u32 = 1;

    /// Checks B (finite, >= 0), the band (finite, > 0, end after start) and 1 to 20 components
    /// per decade.
    pub fn new(
        b: f64,
        tau_min_s: f64,
        tau_max_s: f64,
        per_decade: u32,
    ) -> Result<Flicker, ModelError> {
        check("flicker B", b, false)?;
        check_band(
            [
                "flicker band start",
                "flicker band end",
                "flicker per_decade",
            ],
            tau_min_s,
            tau_max_s,
            per_decade,
        )?;
        Ok(Flicker {
            b,
            tau_min_s,
            tau_max_s,
            per_decade,
        })
    }

    /// With the default band (B checked as in [`Flicker::new`]).
    pub fn with_b(b: f64) -> Result<Flicker, ModelError> {
        Flicker::new(
            b,
            Self::DEFAULT_TAU_MIN_S,
            Self::DEFAULT_TAU_MAX_S,
            Self::DEFAULT_PER_DECADE,
        )
    }

    /// The same band with coefficient `b` (checked as in [`Flicker::new`]).
    pub fn with_level(&self, b: f64) -> Result<Flicker, ModelError> {
        Ok(Flicker {
            b: check("flicker B", b, false)?,
            ..self.clone()
        })
    }

    /// IEEE coefficient B (signal units); the Allan plateau is 0.6643 B.
    pub fn b(&self) -> f64 {
        self.b
    }

    /// Shortest correlation time of the band, s.
    pub fn tau_min_s(&self) -> f64 {
        self.tau_min_s
    }

    /// Longest correlation time of the band, s.
    pub fn tau_max_s(&self) -> f64 {
        self.tau_max_s
    }

    /// Gauss-Markov components per decade of correlation time.
    pub fn per_decade(&self) -> u32 {
        self.per_decade
    }

    /// The Gauss-Markov components as (correlation time s, stationary std), shortest first.
    pub fn components(&self) -> Vec<(f64, f64)> {
        let decades = (self.tau_max_s / self.tau_min_s).log10();
        let intervals = ((decades * f64::from(self.per_decade)).round() as usize).max(1);
        let ln_rho = (self.tau_max_s / self.tau_min_s).ln() / intervals as f64;
        // docs/model.md §3: for IEEE B, sigma_0^2 = B^2 ln(rho) / pi per component.
        let sigma0 = self.b * (ln_rho / std::f64::consts::PI).sqrt();
        (0..=intervals)
            .map(|i| (self.tau_min_s * (ln_rho * i as f64).exp(), sigma0))
            .collect()
    }

    /// Allan variance of the component sum (docs/model.md §2 Gauss-Markov closed form, summed).
    pub fn avar(&self, tau_s: f64) -> f64 {
        self.avar_at(tau_s, None)
    }

    /// Exact Allan variance of the sampled component sum.
    pub fn avar_sampled(&self, tau_s: f64, dt_s: f64) -> f64 {
        self.avar_at(tau_s, Some(dt_s))
    }

    fn avar_at(&self, tau_s: f64, dt_s: Option<f64>) -> f64 {
        self.components()
            .iter()
            .map(|&(tc, s)| cf::gauss_markov_avar_at(s, tc, tau_s, dt_s))
            .sum()
    }

    /// Variance of the k-fold integral (k = 1..=3) of the component sum at time `t_s`: the sum of the
    /// components' exact Gauss-Markov forms (`closed_form::gauss_markov_kfold_variance`).
    pub fn integrated_variance(&self, t_s: f64, k: i32) -> Option<f64> {
        self.components()
            .iter()
            .map(|&(tc, s)| cf::gauss_markov_kfold_variance(s, tc, t_s, k))
            .sum()
    }
}

/// The checks every band of log-spaced Gauss-Markov components shares (flicker, the power law):
/// start and end finite and > 0, the end after the start, 1 to 20 components per decade.
/// `names`: what the start, the end and the density are called in messages.
pub(super) fn check_band(
    names: [&'static str; 3],
    tau_min_s: f64,
    tau_max_s: f64,
    per_decade: u32,
) -> Result<(), ModelError> {
    check(names[0], tau_min_s, true)?;
    check(names[1], tau_max_s, true)?;
    if tau_max_s <= tau_min_s {
        return Err(ModelError {
            what: names[1],
            expected: "a time longer than the band start",
            found: tau_max_s,
        });
    }
    if per_decade == 0 || per_decade > 20 {
        return Err(ModelError {
            what: names[2],
            expected: "1 to 20 components per decade",
            found: f64::from(per_decade),
        });
    }
    Ok(())
}

/// Bias instability in one of its two models.
#[derive(Clone, Debug, PartialEq)]
pub enum BiasInstability {
    /// Flicker noise, IEEE 952 (Allan plateau 0.664 B).
    Flicker(Flicker),
    /// Woodman's bias random walk (TR-696 §3.2.3, eq 9).
    RandomWalk(BiasRandomWalk),
}

/// Woodman's bias random walk (TR-696 §3.2.3, eq 9): the bias changes by `stability` (1 sigma)
/// over `period_s`, i.e. a random walk of density K = stability / sqrt(period).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BiasRandomWalk {
    stability: f64,
    period_s: f64,
}

impl BiasRandomWalk {
    /// Checks the stability (finite, >= 0) and the period (finite, > 0).
    pub fn new(stability: f64, period_s: f64) -> Result<BiasRandomWalk, ModelError> {
        Ok(BiasRandomWalk {
            stability: check("bias random walk stability", stability, false)?,
            period_s: check("bias random walk period", period_s, true)?,
        })
    }

    /// The bias change over the period (1 sigma, signal units).
    pub fn stability(&self) -> f64 {
        self.stability
    }

    /// The period, s.
    pub fn period_s(&self) -> f64 {
        self.period_s
    }

    /// The random walk's density K = stability / sqrt(period) (Woodman eq 9,
    /// `closed_form::woodman_bias_random_walk`).
    pub fn density(&self) -> f64 {
        cf::woodman_bias_random_walk(self.stability, self.period_s)
    }
}

impl BiasInstability {
    /// Allan variance (docs/model.md §2: flicker as GM sum; random walk K^2 tau/3).
    pub fn avar(&self, tau_s: f64) -> f64 {
        self.avar_at(tau_s, None)
    }

    /// Exact Allan variance of the sampled process.
    pub fn avar_sampled(&self, tau_s: f64, dt_s: f64) -> f64 {
        self.avar_at(tau_s, Some(dt_s))
    }

    /// Continuous (`dt_s` None) or sampled.
    fn avar_at(&self, tau_s: f64, dt_s: Option<f64>) -> f64 {
        match self {
            BiasInstability::Flicker(f) => f.avar_at(tau_s, dt_s),
            BiasInstability::RandomWalk(BiasRandomWalk {
                stability,
                period_s,
            }) => cf::rate_random_walk_avar_at(
                cf::woodman_bias_random_walk(*stability, *period_s),
                tau_s,
                dt_s,
            ),
        }
    }
}

// The `allan_minimum` convention: the IEEE coefficient B solved (bisection) so that the closed-form
// Allan deviation of the whole axis model has the stated minimum over the flicker plateau.

/// Log-spaced averaging times inside the flicker band's plateau, [30 tau_min, tau_max / 30], where the
/// component sum is within 1.3 % of 0.664 B (`Flicker::per_decade`); nearer the band edges it falls off
/// (0.55 B at 2 tau_min), which would make a curve without a rising term take its minimum there.
fn plateau_taus(f: &Flicker) -> Vec<f64> {
    let lo = 30.0 * f.tau_min_s;
    let hi = (f.tau_max_s / 30.0).max(lo);
    let n = ((hi / lo).log10() * 40.0).ceil().max(1.0) as usize;
    (0..=n)
        .map(|i| lo * (hi / lo).powf(i as f64 / n as f64))
        .collect()
}

/// Minimum over the plateau taus of the total closed-form Allan deviation.
/// `avar` is the axis' closed-form Allan variance at a tau (`AxisModel::allan_variance`).
pub(crate) fn model_adev_minimum(avar: &dyn Fn(f64) -> f64, band: &Flicker) -> (f64, f64) {
    plateau_taus(band)
        .into_iter()
        .map(|tau| (avar(tau).sqrt(), tau))
        .fold((f64::INFINITY, 0.0), |a, b| if b.0 < a.0 { b } else { a })
}

/// B such that the axis' total Allan-deviation minimum equals `target`. Err(floor) when the other
/// terms alone already exceed it. The minimum grows monotonically with B, so bisection converges.
fn solve_b_for_minimum(
    target: f64,
    others: &dyn OtherTerms,
    position: usize,
    flicker: &dyn Fn(f64) -> Flicker,
) -> Result<f64, f64> {
    let min_with = |b: f64| {
        let term = BiasInstability::Flicker(flicker(b));
        let avar = |tau: f64| others.allan_variance_with(position, term.allan_variance(tau), tau);
        model_adev_minimum(&avar, &flicker(b)).0
    };
    let floor = min_with(0.0);
    if floor >= target {
        return Err(floor);
    }
    let (mut lo, mut hi) = (0.0, 2.0 * target / cf::FLICKER_PLATEAU_PER_B);
    while min_with(hi) < target {
        hi *= 2.0;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if min_with(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// Most Gauss-Markov components a flicker bias instability may have (20 decades at 5 per decade).
const MAX_FLICKER_COMPONENTS: f64 = 100.0;

/// What `bias_instability` may be: a value with a unit (the Allan-deviation minimum, as spec
/// sheets quote "in-run bias stability") or the table form with its convention stated.
#[derive(Clone)]
pub enum RawBiasField {
    Plain(String),
    Table(Box<RawBiasInstability>),
}

/// The accepted forms, for error messages.
const BIAS_INSTABILITY_FORMS: &str = "a value with a unit, e.g. bias_instability = \"10 deg/h\" (the Allan-deviation minimum, as spec sheets quote in-run bias stability), or a table: { value = \"10 deg/h\", convention = \"allan_minimum\" | \"ieee\" }, or { model = \"random_walk\", stability = \"36 ug\", period = \"800 s\" }";

impl<'de> serde::Deserialize<'de> for RawBiasField {
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
                <RawBiasInstability as serde::Deserialize>::deserialize(
                    serde::de::value::MapAccessDeserializer::new(map),
                )
                .map(|t| RawBiasField::Table(Box::new(t)))
            }
        }
        d.deserialize_any(V)
    }
}

impl RawBiasField {
    /// The table form; a plain value becomes `{ value, convention = "allan_minimum" }` with the
    /// value's place in the file.
    fn table(field: &toml::Spanned<RawBiasField>) -> RawBiasInstability {
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

/// The table form of `bias_instability` as written.
#[derive(serde::Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawBiasInstability {
    model: Option<Text>,
    value: Option<Text>,
    convention: Option<Text>,
    band: Option<Vec<Text>>,
    per_decade: Option<i64>,
    stability: Option<Text>,
    period: Option<Text>,
}

/// `{ model = "random_walk", stability, period }`: Woodman's bias random walk (eq 9).
fn read_random_walk(
    raw: &RawBiasInstability,
    cx: &ReadContext,
) -> Result<BiasInstability, ConfigError> {
    for (name, present, at) in [
        ("value", raw.value.is_some(), raw.value.as_ref()),
        (
            "convention",
            raw.convention.is_some(),
            raw.convention.as_ref(),
        ),
        (
            "band",
            raw.band.is_some(),
            raw.band.as_ref().and_then(|b| b.first()),
        ),
        ("per_decade", raw.per_decade.is_some(), None),
    ] {
        if present {
            return Err(cx.ctx.invalid_at(
                &cx.sub(name),
                at,
                "only `stability` and `period` for model \"random_walk\"",
                "an extra key",
            ));
        }
    }
    let need = |name: &str, v: &Option<Text>| {
        v.clone().ok_or_else(|| {
            cx.ctx.invalid(
                &cx.sub(name),
                "a value (model \"random_walk\" needs stability and period)",
                "nothing",
            )
        })
    };
    let stability = cx.ctx.value(
        &cx.sub("stability"),
        &need("stability", &raw.stability)?,
        Quantity::Signal(cx.sig),
        true,
    )?;
    let period_s = cx.ctx.positive(
        &cx.sub("period"),
        &need("period", &raw.period)?,
        Quantity::Time,
    )?;
    BiasRandomWalk::new(stability, period_s)
        .map(BiasInstability::RandomWalk)
        .map_err(|e| cx.refused(&cx.key, e))
}

/// `{ value, convention, band?, per_decade? }`: flicker with B stated (`"ieee"`) or solved from the
/// axis' Allan minimum (`"allan_minimum"`).
fn read_flicker(
    raw: &RawBiasInstability,
    cx: &ReadContext,
) -> Result<BiasInstability, ConfigError> {
    for (name, at) in [("stability", &raw.stability), ("period", &raw.period)] {
        if let Some(at) = at {
            return Err(cx.ctx.invalid_at(
                &cx.sub(name),
                Some(at),
                "no `stability`/`period` for a flicker bias instability (use model = \"random_walk\" for Woodman's bias random walk)",
                "an extra key",
            ));
        }
    }
    let value_text = raw.value.as_ref().ok_or_else(|| {
        cx.ctx.invalid(
            &cx.sub("value"),
            "the bias instability value, e.g. \"0.010 deg/s\"",
            "nothing",
        )
    })?;
    let value = cx
        .ctx
        .value(&cx.sub("value"), value_text, Quantity::Signal(cx.sig), true)?;
    let (tau_min_s, tau_max_s, per_decade) = flicker_band(raw, cx)?;
    let flicker = |b: f64| Flicker {
        b,
        tau_min_s,
        tau_max_s,
        per_decade,
    };
    let b = match raw.convention.as_ref().map(|c| c.get_ref().as_str()) {
        Some("ieee") => value,
        Some("allan_minimum") => solve_b_for_minimum(value, cx.others, cx.position, &flicker).map_err(|floor| {
            cx.ctx.invalid_at(
                &cx.sub("value"),
                Some(value_text),
                format!(
                    "an Allan minimum above what the other terms of the axis already give ({} over the flicker band's plateau; widen `band`)",
                    in_units_of(floor, value_text.get_ref(), Quantity::Signal(cx.sig))
                ),
                format!("\"{}\"", value_text.get_ref()),
            )
        })?,
        Some(other) => {
            return Err(cx.ctx.invalid_at(
                &cx.sub("convention"),
                raw.convention.as_ref(),
                "\"ieee\" (value is B, Allan plateau 0.664 B) or \"allan_minimum\" (value is the Allan-deviation minimum, as Woodman reports it)",
                format!("\"{other}\""),
            ))
        }
        None => {
            return Err(cx.ctx.invalid(
                &cx.sub("convention"),
                "a stated convention: \"ieee\" (value is B, plateau 0.664 B) or \"allan_minimum\" (value is the Allan-deviation minimum)",
                "nothing",
            ))
        }
    };
    Ok(BiasInstability::Flicker(flicker(b)))
}

/// The flicker band and its density: `band = [shortest, longest]` correlation times (default
/// 0.1 s .. 1e5 s) and `per_decade` (default 1), at most [`MAX_FLICKER_COMPONENTS`] components.
fn flicker_band(
    raw: &RawBiasInstability,
    cx: &ReadContext,
) -> Result<(f64, f64, u32), ConfigError> {
    let (tau_min_s, tau_max_s) = match &raw.band {
        None => (Flicker::DEFAULT_TAU_MIN_S, Flicker::DEFAULT_TAU_MAX_S),
        Some(b) if b.len() == 2 => (
            cx.ctx
                .positive(&format!("{}[0]", cx.sub("band")), &b[0], Quantity::Time)?,
            cx.ctx
                .positive(&format!("{}[1]", cx.sub("band")), &b[1], Quantity::Time)?,
        ),
        Some(b) => {
            return Err(cx.ctx.invalid_at(
                &cx.sub("band"),
                b.first(),
                "two correlation times [shortest, longest], e.g. [\"0.1 s\", \"1e5 s\"]",
                format!("{} values", b.len()),
            ))
        }
    };
    if tau_max_s <= tau_min_s {
        return Err(cx.ctx.invalid_at(
            &cx.sub("band"),
            raw.band.as_ref().and_then(|b| b.first()),
            "the longest time after the shortest",
            format!("{tau_min_s} s .. {tau_max_s} s"),
        ));
    }
    let per_decade = match raw.per_decade {
        None => Flicker::DEFAULT_PER_DECADE,
        Some(n) if (1..=20).contains(&n) => n as u32,
        Some(n) => {
            return Err(cx.ctx.invalid(
                &cx.sub("per_decade"),
                "an integer from 1 to 20",
                n.to_string(),
            ))
        }
    };
    // One Gauss-Markov component per 1/per_decade decade of the band: bound their number,
    // which sets the cost of every sample.
    let components = (tau_max_s / tau_min_s).log10() * f64::from(per_decade);
    if components.is_nan() || components > MAX_FLICKER_COMPONENTS {
        return Err(cx.ctx.invalid_at(
            &cx.sub("band"),
            raw.band.as_ref().and_then(|b| b.first()),
            format!(
                "a band and per_decade giving at most {MAX_FLICKER_COMPONENTS} components (decades x per_decade), e.g. [\"0.1 s\", \"1e5 s\"] with per_decade = 1"
            ),
            format!("{components:.3e} components"),
        ));
    }
    Ok((tau_min_s, tau_max_s, per_decade))
}

impl ErrorTerm for BiasInstability {
    /// Flicker as realised, a sum of stationary Gauss-Markov components; Woodman's bias random
    /// walk as a random walk of density stability / sqrt(period).
    fn law_sources(&self, _cx: &LawSourceContext) -> Vec<LawSource> {
        vec![match self {
            BiasInstability::Flicker(f) => LawSource::GaussMarkovSum(f.components()),
            BiasInstability::RandomWalk(BiasRandomWalk {
                stability,
                period_s,
            }) => LawSource::RandomWalk(cf::woodman_bias_random_walk(*stability, *period_s)),
        }]
    }

    /// Flicker's B, named `b` (docs/cli.md; its band is a convention, not a shape), or the random
    /// walk's stability, named `stability`.
    fn level(&self) -> Option<(&'static str, f64)> {
        Some(match self {
            BiasInstability::Flicker(f) => ("b", f.b),
            BiasInstability::RandomWalk(BiasRandomWalk { stability, .. }) => {
                ("stability", *stability)
            }
        })
    }

    /// The random walk's period, named `period_s`; flicker has none.
    fn shape(&self) -> Vec<(&'static str, f64)> {
        match self {
            BiasInstability::Flicker(_) => Vec::new(),
            BiasInstability::RandomWalk(BiasRandomWalk { period_s, .. }) => {
                vec![("period_s", *period_s)]
            }
        }
    }

    fn allan_variance(&self, tau_s: f64) -> Option<f64> {
        Some(self.avar(tau_s))
    }

    fn allan_variance_sampled(&self, tau_s: f64, dt_s: f64) -> Option<f64> {
        Some(self.avar_sampled(tau_s, dt_s))
    }

    /// `{ value, convention = "ieee", band, per_decade }` (B itself, so it reads back bit for bit),
    /// or the random walk's table.
    fn config_value(&self, cx: &WriteContext) -> String {
        match self {
            BiasInstability::Flicker(f) => format!(
                "{{ value = {}, convention = \"ieee\", band = [{}, {}], per_decade = {} }}",
                cx.quoted(f.b, Quantity::Signal(cx.sig)),
                cx.quoted(f.tau_min_s, Quantity::Time),
                cx.quoted(f.tau_max_s, Quantity::Time),
                f.per_decade
            ),
            BiasInstability::RandomWalk(BiasRandomWalk {
                stability,
                period_s,
            }) => format!(
                "{{ model = \"random_walk\", stability = {}, period = {} }}",
                cx.quoted(*stability, Quantity::Signal(cx.sig)),
                cx.quoted(*period_s, Quantity::Time)
            ),
        }
    }

    /// Each flicker component, or the walk, behind the filter.
    fn allan_variance_filtered(&self, tau_s: f64, _dt_s: f64, fa: &FilteredAllan) -> Option<f64> {
        Some(match self {
            BiasInstability::Flicker(f) => f
                .components()
                .iter()
                .map(|&(tc, s)| fa.gauss_markov(s, tc, tau_s))
                .sum(),
            BiasInstability::RandomWalk(BiasRandomWalk {
                stability,
                period_s,
            }) => fa.random_walk(cf::woodman_bias_random_walk(*stability, *period_s), tau_s),
        })
    }
}

impl TermKind for BiasInstability {
    const STOCHASTIC: bool = true;
    const LONG_TERM: bool = true;
    const FREE_PARAMETERS: usize = 1;
    const SHOWS_IN_STATIC_LOG: bool = true;
    /// A plain value, or a table ([`RawBiasInstability`]).
    type Raw = toml::Spanned<RawBiasField>;
    /// The `allan_minimum` convention solves B against the axis' other terms.
    const READS_OTHER_TERMS: bool = true;

    /// Flicker's band, or the random walk's period, kept.
    fn with_level(&self, level: f64) -> Result<BiasInstability, ModelError> {
        Ok(match self {
            BiasInstability::Flicker(f) => BiasInstability::Flicker(f.with_level(level)?),
            BiasInstability::RandomWalk(w) => {
                BiasInstability::RandomWalk(BiasRandomWalk::new(level, w.period_s)?)
            }
        })
    }

    /// Flicker (`model` absent or `"flicker"`) or Woodman's random walk (`model = "random_walk"`).
    fn from_raw(
        field: &toml::Spanned<RawBiasField>,
        cx: &ReadContext,
    ) -> Result<BiasInstability, ConfigError> {
        let raw = RawBiasField::table(field);
        match raw
            .model
            .as_ref()
            .map_or("flicker", |m| m.get_ref().as_str())
        {
            "random_walk" => read_random_walk(&raw, cx),
            "flicker" => read_flicker(&raw, cx),
            other => Err(cx.ctx.invalid(
                &cx.sub("model"),
                "\"flicker\" (default) or \"random_walk\" (Woodman's bias random walk)",
                format!("\"{other}\""),
            )),
        }
    }

    /// A plain value is the Allan minimum, of the signal.
    fn note_units(value: &toml::Value, sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value)) {
        note_value_units(value, Quantity::Signal(sig), sig, note);
    }

    type Generator = BiasInstabilityGenerator;

    fn generator(&self, cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> BiasInstabilityGenerator {
        match self {
            BiasInstability::Flicker(f) => BiasInstabilityGenerator::Flicker(BankGenerator::new(
                &f.components(),
                cx.dt_raw_s,
                rng(),
            )),
            // Woodman eq 9 / AirSim: K = BS / sqrt(T_BS), so BS·sqrt(dt/T_BS) per step.
            BiasInstability::RandomWalk(BiasRandomWalk {
                stability,
                period_s,
            }) => BiasInstabilityGenerator::RandomWalk(RandomWalkGenerator {
                walk: RandomWalk::new(stability / period_s.sqrt(), cx.dt_raw_s),
                rng: crate::NormalStream::new(rng()),
            }),
        }
    }
}

/// Flicker's band of Gauss-Markov processes, or Woodman's random walk.
#[derive(Clone, Debug)]
pub enum BiasInstabilityGenerator {
    Flicker(BankGenerator),
    RandomWalk(RandomWalkGenerator),
}

impl Generate for BiasInstabilityGenerator {
    fn stage(&self) -> Stage {
        Stage::Raw
    }

    #[inline]
    fn add_raw(&mut self, clock: RawClock, out: &mut [f64], scratch: &mut Vec<f64>) {
        match self {
            BiasInstabilityGenerator::Flicker(g) => g.add_raw(clock, out, scratch),
            BiasInstabilityGenerator::RandomWalk(g) => g.add_raw(clock, out, scratch),
        }
    }

    /// The flicker band is referenced; a random walk already starts at 0.
    fn calibrate_start(&mut self) {
        if let BiasInstabilityGenerator::Flicker(g) = self {
            g.calibrate_start();
        }
    }

    fn calibrate_window(&mut self, window_s: f64, rng: &dyn Fn() -> ImuRng) {
        if let BiasInstabilityGenerator::Flicker(g) = self {
            g.calibrate_window(window_s, rng);
        }
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> BiasInstability {
    BiasInstability::Flicker(Flicker::with_b(3e-5).unwrap())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flicker_plateau_ripple_is_as_documented() {
        // `Flicker::per_decade` documents 0.987 .. 1.010 (1 per decade) and 0.987 .. 1.000 (2) of
        // 0.664 B over [30 tau_min, tau_max / 30]; checked on 400 taus of the default band.
        for (per_decade, lo, hi) in [(1, 0.987, 1.010), (2, 0.987, 1.000)] {
            let f = Flicker::new(1.0, 0.1, 1e5, per_decade).unwrap();
            let (a, b) = (30.0 * f.tau_min_s, f.tau_max_s / 30.0);
            for i in 0..=400 {
                let tau = a * (b / a).powf(i as f64 / 400.0);
                let r = f.avar(tau).sqrt() / cf::FLICKER_PLATEAU_PER_B;
                assert!(
                    r > lo - 1e-3 && r < hi + 1e-3,
                    "{per_decade}/decade, tau {tau}: {r}"
                );
            }
        }
    }
}
