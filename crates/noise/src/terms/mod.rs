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
pub mod quantization;
pub mod rate_ramp;
pub mod rate_random_walk;
pub mod resonance;
pub mod scale_factor;
pub mod sinusoidal;
pub mod temperature_bias;
pub mod term;
pub mod turn_on_bias;
pub mod warmup_transient;
pub mod white_noise;

pub use term::{ErrorTerm, GenContext, Generate, RawClock, Stage, TermKind};

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

            /// This run's generator of the term ([`TermKind::generator`]).
            pub fn generator(&self, cx: &GenContext, rng: &dyn Fn() -> crate::ImuRng) -> Generator {
                match self {
                    $(Term::$effect(t) => Generator::$effect(t.generator(cx, rng)),)+
                }
            }
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

            #[inline]
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
}

/// The order a channel's terms act in within each [`Stage`] (`ChannelErrors`): the input terms, then
/// the raw ones in the order they are added (changing it changes the last bits of every output),
/// then those on the output register (after the filter: the filtered sinusoid, the outliers, the
/// quantiser).
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
    Effect::Resonance,
    Effect::Sinusoidal,
    Effect::TemperatureBias,
    Effect::WarmupTransient,
    Effect::Outliers,
    Effect::Quantization,
    Effect::OutputFilter,
];

/// Every effect once in [`GENERATION_ORDER`] (checked when the crate compiles).
const _: () = {
    let mut seen = [false; Effect::COUNT];
    let mut i = 0;
    while i < Effect::COUNT {
        let e = GENERATION_ORDER[i] as usize;
        assert!(!seen[e], "an effect twice in GENERATION_ORDER");
        seen[e] = true;
        i += 1;
    }
};
