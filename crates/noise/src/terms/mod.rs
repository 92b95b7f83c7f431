//! One home per error effect, and the registry that lists them.
//!
//! Each file `terms/<effect>.rs` holds one effect's validated parameters (SI, private fields) and
//! what they do ([`ErrorTerm`], [`TermKind`]): the Allan variances (continuous, sampled, behind an
//! output filter) with their sources (docs/model.md §2). The table at the end of this file, the
//! registry, is the one list of effects: from it come [`Effect`] (the names), [`Term`] (an effect
//! with its parameters) and the dispatch from a `Term` to its parameter type.

pub mod bias_instability;
pub mod constant_bias;
pub mod gauss_markov;
pub mod misalignment;
pub mod outliers;
pub mod output_filter;
pub mod output_white_noise;
pub mod power_law;
pub mod quantization;
pub mod rate_ramp;
pub mod rate_random_walk;
pub mod resonance;
pub mod scale_factor;
pub mod sinusoidal;
pub mod slow_gauss_markov;
pub mod temperature_bias;
pub mod term;
pub mod turn_on_bias;
pub mod warmup_transient;
pub mod white_noise;

pub use term::{ErrorTerm, GenContext, Generate, RawClock, Stage, TermKind, WriteContext};

/// Writes, from the table of rows `Variant => file::Type`, the [`Effect`] enum (the row order is
/// `Effect::ALL`; the file's name is the effect's name and config key), the [`Term`] enum and
/// [`Registered`] for each type.
macro_rules! registry {
    ($($(#[$doc:meta])* $effect:ident => $file:ident :: $ty:ident,)+) => {
        /// One error effect of an axis, named as in configs, on the command line and in JSON
        /// ([`Effect::name`], the name of its file under `terms/`). The order of [`Effect::ALL`] is
        /// the order of names in messages and reports and of the Allan-variance sum; the position
        /// in it is the index of the term's random sub-stream (stable: never reorder).
        /// Serialised as its name.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub enum Effect {
            $($(#[$doc])* $effect,)+
        }

        impl Effect {
            /// How many effects there are.
            pub const COUNT: usize = [$(stringify!($effect)),+].len();

            /// Every effect, in registry order.
            pub const ALL: [Effect; Effect::COUNT] = [$(Effect::$effect),+];

            /// The config / CLI / JSON name, e.g. `"white_noise"`.
            pub fn name(self) -> &'static str {
                match self {
                    $(Effect::$effect => stringify!($file),)+
                }
            }

            /// Stochastic terms (those with an Allan signature); the others are deterministic or
            /// drawn once per run.
            pub fn is_stochastic(self) -> bool {
                match self {
                    $(Effect::$effect => <$file::$ty as TermKind>::STOCHASTIC,)+
                }
            }

            /// Does a static log's Allan deviation show it ([`TermKind::SHOWS_IN_STATIC_LOG`])?
            pub fn shows_in_static_log(self) -> bool {
                match self {
                    $(Effect::$effect => <$file::$ty as TermKind>::SHOWS_IN_STATIC_LOG,)+
                }
            }

            /// Does it shape drift at long horizons ([`TermKind::LONG_TERM`])?
            pub fn is_long_term(self) -> bool {
                match self {
                    $(Effect::$effect => <$file::$ty as TermKind>::LONG_TERM,)+
                }
            }

            /// The parameters a fit of it adjusts ([`TermKind::FREE_PARAMETERS`]).
            pub fn free_parameters(self) -> usize {
                match self {
                    $(Effect::$effect => <$file::$ty as TermKind>::FREE_PARAMETERS,)+
                }
            }

            /// Is its key read after the axis' other terms ([`TermKind::READS_OTHER_TERMS`])?
            pub(crate) fn reads_other_terms(self) -> bool {
                match self {
                    $(Effect::$effect => <$file::$ty as TermKind>::READS_OTHER_TERMS,)+
                }
            }

            /// An example of its config key, for messages ([`TermKind::EXAMPLE`]).
            pub(crate) fn example(self) -> Option<&'static str> {
                match self {
                    $(Effect::$effect => <$file::$ty as TermKind>::EXAMPLE,)+
                }
            }

            /// Tell `note` the units its key's value is written in ([`TermKind::note_units`]).
            pub(crate) fn note_units(
                self,
                value: &toml::Value,
                sig: crate::units::Signal,
                note: &mut dyn FnMut(crate::units::Quantity, &toml::Value),
            ) {
                match self {
                    $(Effect::$effect => <$file::$ty as TermKind>::note_units(value, sig, note),)+
                }
            }
        }

        /// An axis table of a sensor TOML as written: each effect's key (its name) with the value
        /// its type reads ([`TermKind::Raw`]).
        #[derive(serde::Deserialize, Default, Clone)]
        #[serde(deny_unknown_fields)]
        pub(crate) struct RawAxis {
            $($file: Option<<$file::$ty as TermKind>::Raw>,)+
            /// The run-to-run spreads of the axis' terms (docs/model.md §2.3): effect name to
            /// a number or a string such as "30 %" (read by `config::convert`).
            pub(crate) run_to_run: Option<
                std::collections::BTreeMap<String, toml::Spanned<toml::Value>>,
            >,
        }

        impl RawAxis {
            /// Does the table set `effect`'s key?
            pub(crate) fn has(&self, effect: Effect) -> bool {
                match effect {
                    $(Effect::$effect => self.$file.is_some(),)+
                }
            }

            /// `effect`'s term read from its key ([`TermKind::from_raw`]), if the table sets it.
            pub(crate) fn read(
                &self,
                effect: Effect,
                cx: &crate::config::read::ReadContext,
            ) -> Option<Result<Term, crate::config::error::ConfigError>> {
                match effect {
                    $(Effect::$effect => self.$file.as_ref().map(|raw| {
                        <$file::$ty as TermKind>::from_raw(raw, cx).map(Term::$effect)
                    }),)+
                }
            }
        }

        /// One term of an axis with its validated parameters (SI): an effect and its values,
        /// used from the config to the growth laws to diagnose.
        #[derive(Clone, Debug, PartialEq)]
        pub enum Term {
            $($(#[$doc])* $effect($file::$ty),)+
        }

        impl Term {
            /// Which effect this is.
            pub fn effect(&self) -> Effect {
                match self {
                    $(Term::$effect(_) => Effect::$effect,)+
                }
            }

            /// What the parameters do.
            pub fn as_error_term(&self) -> &dyn ErrorTerm {
                match self {
                    $(Term::$effect(t) => t,)+
                }
            }

            /// Its level with the level's JSON name ([`ErrorTerm::level`]).
            pub fn level(&self) -> Option<(&'static str, f64)> {
                self.as_error_term().level()
            }

            /// Its level, then its shape parameters, with their JSON names ([`ErrorTerm::level`],
            /// [`ErrorTerm::shape`]).
            pub fn parameters(&self) -> Vec<(&'static str, f64)> {
                let t = self.as_error_term();
                t.level().into_iter().chain(t.shape()).collect()
            }

            /// The same term at another level ([`TermKind::with_level`]).
            pub fn with_level(&self, level: f64) -> Result<Term, crate::ModelError> {
                match self {
                    $(Term::$effect(t) => t.with_level(level).map(Term::$effect),)+
                }
            }

            /// This run's generator of the term ([`TermKind::generator`]).
            pub fn generator(&self, cx: &GenContext, rng: &dyn Fn() -> crate::ImuRng) -> Generator {
                match self {
                    $(Term::$effect(t) => Generator::$effect(t.generator(cx, rng)),)+
                }
            }
        }

        /// One valid term of each effect, in registry order (each file's `sample`), for tests.
        #[cfg(test)]
        pub(crate) fn samples() -> [Term; Effect::COUNT] {
            [$(Term::$effect($file::sample()),)+]
        }

        /// The per-run generator of one term: a closed enum, so the per-sample calls are static.
        #[derive(Clone, Debug)]
        pub enum Generator {
            $($effect(<$file::$ty as TermKind>::Generator),)+
        }

        impl Generate for Generator {
            fn stage(&self) -> Stage {
                match self {
                    $(Generator::$effect(g) => g.stage(),)+
                }
            }

            fn input(&self, row: &mut [f64; 3], bias: &mut f64) {
                match self {
                    $(Generator::$effect(g) => g.input(row, bias),)+
                }
            }

            #[inline(always)]
            fn add_raw(&mut self, clock: RawClock, out: &mut [f64], scratch: &mut Vec<f64>) {
                match self {
                    $(Generator::$effect(g) => g.add_raw(clock, out, scratch),)+
                }
            }

            #[inline]
            fn output(&mut self, k0: u64, dt_s: f64, out: &mut [f64]) {
                match self {
                    $(Generator::$effect(g) => g.output(k0, dt_s, out),)+
                }
            }

            fn calibrate_start(&mut self) {
                match self {
                    $(Generator::$effect(g) => g.calibrate_start(),)+
                }
            }

            fn calibrate_window(&mut self, window_s: f64, rng: &dyn Fn() -> crate::ImuRng) {
                match self {
                    $(Generator::$effect(g) => g.calibrate_window(window_s, rng),)+
                }
            }
        }

        impl Generator {
            /// Which effect it generates.
            pub fn effect(&self) -> Effect {
                match self {
                    $(Generator::$effect(_) => Effect::$effect,)+
                }
            }
        }

        /// A [`TermKind`] listed in the registry: which effect it is and how it sits in a
        /// [`Term`]. Implemented here for every row, never by hand.
        pub trait Registered: TermKind + Clone + Into<Term> {
            /// The effect this type is the parameters of.
            const EFFECT: Effect;
            /// The parameters, if `term` is this effect's.
            fn from_term(term: &Term) -> Option<&Self>;
        }

        $(
            impl From<$file::$ty> for Term {
                fn from(t: $file::$ty) -> Term {
                    Term::$effect(t)
                }
            }

            impl Registered for $file::$ty {
                const EFFECT: Effect = Effect::$effect;
                fn from_term(term: &Term) -> Option<&Self> {
                    match term {
                        Term::$effect(t) => Some(t),
                        _ => None,
                    }
                }
            }
        )+
    };
}

registry! {
    /// Quantisation of the integrated output.
    Quantization => quantization::Quantization,
    /// White noise (angle / velocity random walk).
    WhiteNoise => white_noise::WhiteNoise,
    /// Bias instability: flicker, or Woodman's bias random walk.
    BiasInstability => bias_instability::BiasInstability,
    /// Rate random walk.
    RateRandomWalk => rate_random_walk::RateRandomWalk,
    /// Rate ramp.
    RateRamp => rate_ramp::RateRamp,
    /// First-order Gauss-Markov bias.
    GaussMarkov => gauss_markov::GaussMarkov,
    /// A sinusoid.
    Sinusoidal => sinusoidal::Sinusoid,
    /// Bias proportional to the temperature's excursion from its reference.
    TemperatureBias => temperature_bias::TemperatureBias,
    /// Constant bias.
    ConstantBias => constant_bias::ConstantBias,
    /// Bias drawn once per run.
    TurnOnBias => turn_on_bias::TurnOnBias,
    /// Scale-factor error.
    ScaleFactor => scale_factor::ScaleFactor,
    /// Sensitivity to the two other axes.
    Misalignment => misalignment::Misalignment,
    /// Isolated spikes on the output register.
    Outliers => outliers::Outliers,
    /// Bias settling after turn-on.
    WarmupTransient => warmup_transient::WarmupTransient,
    /// The sensor's digital output filter (and decimation).
    OutputFilter => output_filter::OutputFilter,
    /// A narrow-band random vibration (second-order Gauss-Markov).
    Resonance => resonance::Resonance,
    /// A second first-order Gauss-Markov bias, for the slow wander.
    SlowGaussMarkov => slow_gauss_markov::SlowGaussMarkov,
    /// White noise on the output register, after the output filter.
    OutputWhiteNoise => output_white_noise::OutputWhiteNoise,
    /// Fractional power-law noise, S(f) ~ f^alpha (a band of Gauss-Markov processes).
    PowerLaw => power_law::PowerLaw,
}

/// The order a channel's terms act in within each [`Stage`] (`ChannelErrors`): the input terms, then
/// the raw ones in the order they are added (changing it changes the last bits of every output),
/// then those on the output register (after the filter: the filtered sinusoid, the output white
/// noise, the outliers, the quantiser).
pub const GENERATION_ORDER: [Effect; Effect::COUNT] = [
    Effect::ConstantBias,
    Effect::TurnOnBias,
    Effect::ScaleFactor,
    Effect::Misalignment,
    Effect::WhiteNoise,
    Effect::BiasInstability,
    Effect::RateRandomWalk,
    Effect::RateRamp,
    Effect::GaussMarkov,
    Effect::SlowGaussMarkov,
    Effect::PowerLaw,
    Effect::Resonance,
    Effect::Sinusoidal,
    Effect::TemperatureBias,
    Effect::WarmupTransient,
    Effect::OutputWhiteNoise,
    Effect::Outliers,
    Effect::Quantization,
    Effect::OutputFilter,
];

/// The order a sensor TOML writes an axis' keys in: the plain values, then the tables, the
/// misalignment last (the order written configs have always had).
pub const WRITE_ORDER: [Effect; Effect::COUNT] = [
    Effect::Quantization,
    Effect::WhiteNoise,
    Effect::OutputWhiteNoise,
    Effect::RateRandomWalk,
    Effect::RateRamp,
    Effect::TemperatureBias,
    Effect::ConstantBias,
    Effect::TurnOnBias,
    Effect::ScaleFactor,
    Effect::BiasInstability,
    Effect::GaussMarkov,
    Effect::SlowGaussMarkov,
    Effect::PowerLaw,
    Effect::Sinusoidal,
    Effect::OutputFilter,
    Effect::Outliers,
    Effect::WarmupTransient,
    Effect::Resonance,
    Effect::Misalignment,
];

/// Does `order` hold every effect once? (Checked for both orders when the crate compiles.)
const fn is_permutation(order: &[Effect; Effect::COUNT]) -> bool {
    let mut seen = [false; Effect::COUNT];
    let mut i = 0;
    while i < Effect::COUNT {
        let e = order[i] as usize;
        if seen[e] {
            return false;
        }
        seen[e] = true;
        i += 1;
    }
    true
}

const _: () = assert!(is_permutation(&GENERATION_ORDER), "GENERATION_ORDER");
const _: () = assert!(is_permutation(&WRITE_ORDER), "WRITE_ORDER");
