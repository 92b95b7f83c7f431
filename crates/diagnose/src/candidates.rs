//! The candidate effects of diagnose step 4 and their Allan-variance signatures per unit squared
//! parameter, from the noise crate's closed forms (docs/model.md §2; the `_sampled` forms are exact for the
//! discrete generator at the log's sample interval).

use crate::model_terms::{fitted_term, flicker_band};
use noise::closed_form as cf;
use noise::filter::FilteredAllan;
use noise::{
    BiasInstability, Channel, Effect, ErrorTerm, FilterKind, Flicker, ModelError, OutputFilter,
    OutputWhiteNoise, PowerLaw, Quantization, RateRamp, RateRandomWalk, SensorModel,
    TemperatureBias, Term, WhiteNoise,
};

/// A one-level term at a level on a channel that lacks it ([`level_term`]).
type AtLevel = fn(&SensorModel, Channel, f64) -> Result<Term, ModelError>;
/// Allan variance per unit squared level at tau, sample interval dt, with B = 1 in the flicker
/// band, behind the channel's output filter where it has one ([`unit_signature`]).
type UnitSignature = fn(f64, f64, &Flicker, Option<&FilteredAllan>) -> f64;
/// Allan variance per unit squared level at a shape parameter, tau, sample interval dt, behind the
/// channel's output filter where it has one ([`unit_family_signature`]).
type FamilySignature = fn(f64, f64, f64, Option<&FilteredAllan>) -> f64;
/// A family's shape grid (lowest, highest, per decade, or per unit on a linear grid) from the
/// shortest and longest measured tau and the sample interval ([`shape_grid`]).
type ShapeRange = fn(f64, f64, f64) -> (f64, f64, f64);

/// What diagnose does with an effect: [`role`] is the one place that names every effect of the
/// noise crate's registry for diagnose (an exhaustive match, so an effect added there does not
/// compile until it has its row here). Its free parameters are the term's own
/// (`TermKind::FREE_PARAMETERS`, [`Effect::free_parameters`]).
#[derive(Clone, Copy)]
pub struct Role {
    /// Its place in diagnose's order of effects: the Allan-gap candidates are tried, and the
    /// bootstrap's levels drawn, in this order ([`candidates`], [`drawn`]).
    pub order: u8,
    /// Fitted to the Allan gap (step 4, [`candidates`]).
    pub candidate: bool,
    /// Its place among the drift loop's candidates ([`drift_candidates`]), if it is one.
    pub drift: Option<u8>,
    /// Its level is drawn by the parametric bootstrap (`bootstrap`, [`drawn`]).
    pub drawn: bool,
    /// Its level has a sign (a ramp, a temperature coefficient): its squared level loses it, so
    /// the joint re-level leaves it out (`relevel`).
    pub signed: bool,
    /// The term at a level where the model has none ([`level_term`]).
    pub at_level: Option<AtLevel>,
    /// Its Allan variance per unit squared level ([`unit_signature`]).
    pub unit_signature: Option<UnitSignature>,
    /// Its Allan variance per unit squared level at a shape ([`unit_family_signature`]).
    pub family_signature: Option<FamilySignature>,
    /// Its shape grid ([`shape_grid`]).
    pub shape_range: Option<ShapeRange>,
    /// The grid is linear in the shape (a power law's slope alpha, negative), not log-spaced.
    pub linear_shapes: bool,
}

impl Role {
    /// An effect diagnose neither fits nor draws, after those it does.
    const NONE: Role = Role {
        order: u8::MAX,
        candidate: false,
        drift: None,
        drawn: false,
        signed: false,
        at_level: None,
        unit_signature: None,
        family_signature: None,
        shape_range: None,
        linear_shapes: false,
    };
}

/// Diagnose's row of `effect` (docs/diagnose.md). The candidates of the Allan gap: the output filter
/// is tried beside them; white noise on the output register only on a channel that has one (without
/// a filter it is the same process as `white_noise`). The temperature bias is not among them: it is
/// regressed on the log's temperature column in the time domain (`detect`, step 0), where its phase
/// is seen; its Allan signature alone cannot tell it from a slow bias wander. The drift loop's
/// Gauss-Markov candidate goes into the channel's `gauss_markov` slot when that is free or already
/// holds a slow term, else into `slow_gauss_markov` (`drift_fit`). Drawn by the bootstrap: the
/// stochastic levels.
pub fn role(effect: Effect) -> Role {
    match effect {
        Effect::Quantization => Role {
            order: 0,
            candidate: true,
            drawn: true,
            at_level: Some(|_, _, level| Ok(Quantization::new(level)?.into())),
            unit_signature: Some(|tau_s, _, _, _| cf::quantization_avar(1.0, tau_s)),
            ..Role::NONE
        },
        Effect::WhiteNoise => Role {
            order: 1,
            candidate: true,
            drawn: true,
            at_level: Some(|_, _, level| Ok(WhiteNoise::new(level)?.into())),
            unit_signature: Some(|tau_s, _, _, fa| match fa {
                Some(fa) => fa.white_noise(1.0, tau_s),
                None => cf::white_noise_avar(1.0, tau_s),
            }),
            ..Role::NONE
        },
        Effect::OutputWhiteNoise => Role {
            order: 2,
            candidate: true,
            drawn: true,
            at_level: Some(|_, _, level| Ok(OutputWhiteNoise::new(level)?.into())),
            unit_signature: Some(|tau_s, _, _, _| cf::white_noise_avar(1.0, tau_s)),
            ..Role::NONE
        },
        Effect::BiasInstability => Role {
            order: 3,
            candidate: true,
            drift: Some(1),
            drawn: true,
            at_level: Some(|model, ch, level| {
                Ok(BiasInstability::Flicker(flicker_band(model, ch).with_level(level)?).into())
            }),
            unit_signature: Some(|tau_s, dt_s, flicker, fa| match fa {
                Some(fa) => BiasInstability::Flicker(flicker.clone())
                    .allan_variance_filtered(tau_s, dt_s, fa)
                    .unwrap_or(f64::NAN),
                None => flicker.avar_sampled(tau_s, dt_s),
            }),
            ..Role::NONE
        },
        Effect::RateRandomWalk => Role {
            order: 4,
            candidate: true,
            drift: Some(0),
            drawn: true,
            at_level: Some(|_, _, level| Ok(RateRandomWalk::new(level)?.into())),
            unit_signature: Some(|tau_s, dt_s, _, fa| match fa {
                Some(fa) => fa.random_walk(1.0, tau_s),
                None => cf::rate_random_walk_avar_sampled(1.0, tau_s, dt_s),
            }),
            ..Role::NONE
        },
        Effect::RateRamp => Role {
            order: 5,
            candidate: true,
            drift: Some(2),
            signed: true,
            at_level: Some(|_, _, level| Ok(RateRamp::new(level)?.into())),
            unit_signature: Some(|tau_s, _, _, _| cf::rate_ramp_avar(1.0, tau_s)),
            ..Role::NONE
        },
        Effect::GaussMarkov => Role {
            order: 6,
            candidate: true,
            drift: Some(3),
            drawn: true,
            family_signature: Some(gauss_markov_signature),
            shape_range: Some(|tau_min_s, tau_max_s, _| {
                let p = cf::GAUSS_MARKOV_ADEV_PEAK_TAU_PER_TC;
                (tau_min_s / (3.0 * p), 3.0 * tau_max_s / p, 8.0)
            }),
            ..Role::NONE
        },
        Effect::SlowGaussMarkov => Role {
            order: 7,
            drawn: true,
            family_signature: Some(gauss_markov_signature),
            ..Role::NONE
        },
        Effect::Sinusoidal => Role {
            order: 8,
            candidate: true,
            drawn: true,
            family_signature: Some(|shape, tau_s, dt_s, fa| match fa {
                Some(fa) => fa.sinusoid(1.0, shape, tau_s),
                None => cf::sinusoid_avar_sampled(1.0, shape, tau_s, dt_s),
            }),
            shape_range: Some(|tau_min_s, tau_max_s, dt_s| {
                (
                    1.0 / (4.0 * tau_max_s),
                    0.25 / dt_s.max(tau_min_s / 4.0),
                    200.0,
                )
            }),
            ..Role::NONE
        },
        Effect::Resonance => Role {
            order: 9,
            candidate: true,
            drawn: true,
            ..Role::NONE
        },
        Effect::PowerLaw => Role {
            order: 10,
            candidate: true,
            drawn: true,
            family_signature: Some(power_law_signature),
            shape_range: Some(|_, _, _| {
                (
                    PowerLaw::ALPHA_MIN,
                    PowerLaw::ALPHA_MAX,
                    POWER_LAW_ALPHAS_PER_UNIT,
                )
            }),
            linear_shapes: true,
            ..Role::NONE
        },
        Effect::TemperatureBias => Role {
            signed: true,
            at_level: Some(|_, _, level| Ok(TemperatureBias::new(level)?.into())),
            ..Role::NONE
        },
        Effect::ConstantBias
        | Effect::TurnOnBias
        | Effect::ScaleFactor
        | Effect::Misalignment
        | Effect::Outliers
        | Effect::WarmupTransient
        | Effect::OutputFilter => Role::NONE,
    }
}

/// A Gauss-Markov process' signature at correlation time `shape` (both Gauss-Markov slots).
fn gauss_markov_signature(shape: f64, tau_s: f64, dt_s: f64, fa: Option<&FilteredAllan>) -> f64 {
    match fa {
        Some(fa) => fa.gauss_markov(1.0, shape, tau_s),
        None => cf::gauss_markov_avar_sampled(1.0, shape, tau_s, dt_s),
    }
}

/// The power law's slopes tried: alpha from -1.9 to -0.1 in steps of 0.025 (73 values, a search
/// cost of 2 ln 73 = 8.6). The step is a fraction of the slope's interval (0.15-0.20 wide at
/// alpha = -1.5 beside white noise on 2^18 samples, about 0.4 on 2^16; tests/power_law.rs), so
/// the grid's widening to the next slope outside adds little.
const POWER_LAW_ALPHAS_PER_UNIT: f64 = 40.0;

/// A power law's signature at slope `alpha`, level 1 at tau = 1 s on the default band (a new
/// term's; `PowerLaw::with_alpha`), behind the channel's filter where it has one.
fn power_law_signature(alpha: f64, tau_s: f64, dt_s: f64, fa: Option<&FilteredAllan>) -> f64 {
    power_law_like(None, alpha, tau_s, dt_s, fa)
}

/// A power law at slope `alpha` and level 1 with the conventions (reference time, band) of
/// `own`, the model's term, or a new term's (tau = 1 s, default band) without one: its Allan
/// variance at `tau_s`, behind the channel's filter where it has one. NaN for a slope the noise
/// crate refuses.
pub fn power_law_like(
    own: Option<&PowerLaw>,
    alpha: f64,
    tau_s: f64,
    dt_s: f64,
    fa: Option<&FilteredAllan>,
) -> f64 {
    let Ok(p) = power_law_at(own, alpha, 1.0) else {
        return f64::NAN;
    };
    match fa {
        Some(fa) => p
            .allan_variance_filtered(tau_s, dt_s, fa)
            .unwrap_or(f64::NAN),
        None => p.avar_at(tau_s, Some(dt_s)),
    }
}

/// A power law of slope `alpha` and `level` with `own`'s reference time and band, or a new
/// term's (tau = 1 s, the default band).
pub fn power_law_at(
    own: Option<&PowerLaw>,
    alpha: f64,
    level: f64,
) -> Result<PowerLaw, ModelError> {
    match own {
        Some(o) => PowerLaw::new(
            alpha,
            level,
            o.tau_ref_s(),
            o.tau_min_s(),
            o.tau_max_s(),
            o.per_decade(),
        ),
        None => PowerLaw::with_alpha(alpha, level, 1.0),
    }
}

/// The effects of `keep`'s rows in `place` order.
fn effects_by(keep: impl Fn(&Role) -> Option<u8>) -> Vec<Effect> {
    let mut v: Vec<(u8, Effect)> = Effect::ALL
        .into_iter()
        .filter_map(|e| keep(&role(e)).map(|at| (at, e)))
        .collect();
    v.sort_by_key(|&(at, _)| at);
    v.into_iter().map(|(_, e)| e).collect()
}

/// Effects diagnose fits to the Allan gap, in the order tried ([`Role::candidate`]).
pub fn candidates() -> Vec<Effect> {
    effects_by(|r| r.candidate.then_some(r.order))
}

/// The candidates of the drift loop, in the order tried ([`Role::drift`]).
pub fn drift_candidates() -> Vec<Effect> {
    effects_by(|r| r.drift)
}

/// The effects whose level the bootstrap draws, in diagnose's order ([`Role::drawn`]).
pub fn drawn() -> Vec<Effect> {
    effects_by(|r| r.drawn.then_some(r.order))
}

/// A one-level candidate `effect` (quantisation, white noise before or after the output filter,
/// flicker bias instability, rate random walk, rate ramp, temperature coefficient) at `level` on channel `ch`: the model's own term at
/// that level (its other parameters kept, e.g. flicker's band), else a new one (flicker on the
/// channel's band), through the term's validating constructor ([`Role::at_level`]).
pub fn level_term(
    model: &SensorModel,
    ch: Channel,
    effect: Effect,
    level: f64,
) -> Result<Term, ModelError> {
    if let Some(own) = fitted_term(model, ch, effect) {
        return own.with_level(level);
    }
    match role(effect).at_level {
        Some(at_level) => at_level(model, ch, level),
        None => Err(ModelError {
            what: "level",
            expected: "a one-level effect",
            found: level,
        }),
    }
}

/// The docs/cli.md parameters of a candidate's term, with the white-noise density `n` an output
/// filter is fitted with (the filter reshapes the white noise, so the two are fitted together).
pub fn named(term: &Term, white_n: Option<f64>) -> Vec<(&'static str, f64)> {
    let mut v = term.parameters();
    v.extend(white_n.map(|n| ("n", n)));
    v
}

/// Allan variance per unit squared level at tau (for the one-level terms), for sample interval dt,
/// as the channel generates the term: behind the channel's output filter `fa` where the term acts
/// before it (`ErrorTerm::allan_variance_filtered`, noise::filter), as it is without one. White
/// noise on the output register, quantisation and a ramp are the same either way (the first two act
/// after the filter; unit DC gain keeps a ramp a ramp). Bias instability is flicker as the noise
/// crate realises it (a Gauss-Markov sum over a band of correlation times, plateau 0.664 B inside
/// it), with B = 1 in `flicker` ([`Role::unit_signature`]; NaN for an effect without one).
pub fn unit_signature(
    effect: Effect,
    tau_s: f64,
    dt_s: f64,
    flicker: &Flicker,
    fa: Option<&FilteredAllan>,
) -> f64 {
    role(effect)
        .unit_signature
        .map_or(f64::NAN, |f| f(tau_s, dt_s, flicker, fa))
}

/// Allan variance per unit squared level for a shaped term at shape parameter `shape` (a
/// Gauss-Markov correlation time, a sinusoid's frequency), behind the channel's output filter `fa`
/// where it has one (both act before the filter; the generator adds a filtered sinusoid's output;
/// [`Role::family_signature`], NaN for an effect without one).
pub fn unit_family_signature(
    effect: Effect,
    shape: f64,
    tau_s: f64,
    dt_s: f64,
    fa: Option<&FilteredAllan>,
) -> f64 {
    role(effect)
        .family_signature
        .map_or(f64::NAN, |f| f(shape, tau_s, dt_s, fa))
}

/// The Allan-variance view of channel `ch`'s output filter at sample interval `dt_s`, if it has one.
pub fn filtered_allan(model: &SensorModel, ch: Channel, dt_s: f64) -> Option<FilteredAllan> {
    crate::model_terms::output_filter(model, ch).map(|f| FilteredAllan::new(&f, dt_s))
}

/// Shape grid for a family over the measured tau range.
/// Gauss-Markov: correlation times whose ADEV peak (at 1.8927 T, docs/model.md §2) lies between a third of
/// the shortest and three times the longest tau, 8 per decade. Sinusoid: frequencies from 1/(4 tau_max)
/// to 1/(4 dt) (at least four samples per period: faster sinusoids alias on an octave grid, where their
/// Allan lobes are indistinguishable from quantisation; the PSD is the tool for those, Hou 4.64 note),
/// 200 per decade, because the Allan lobes of a sinusoid at tau >> 1/f0 move with small changes of f0.
/// Power law: its slope alpha over the range the noise crate accepts, linear in steps of 0.025
/// ([`Role::shape_range`], [`Role::linear_shapes`]).
pub fn shape_grid(effect: Effect, tau_min_s: f64, tau_max_s: f64, dt_s: f64) -> Vec<f64> {
    let r = role(effect);
    let Some(range) = r.shape_range else {
        return Vec::new();
    };
    let (lo, hi, per_decade) = range(tau_min_s, tau_max_s, dt_s);
    if hi <= lo {
        return Vec::new();
    }
    if r.linear_shapes {
        // Evenly spaced, rounded to 1e-9 so that a slope is written as its decimal (-1.05, not
        // -1.0499999999999998) and clamped so that the ends stay inside the range.
        let n = ((hi - lo) * per_decade).round().max(1.0) as usize;
        return (0..=n)
            .map(|j| {
                let v = lo + (hi - lo) * j as f64 / n as f64;
                ((v * 1e9).round() / 1e9).clamp(lo, hi)
            })
            .collect();
    }
    let n = ((hi / lo).log10() * per_decade).ceil().max(1.0) as usize;
    (0..=n)
        .map(|j| lo * (hi / lo).powf(j as f64 / n as f64))
        .collect()
}

/// The resonance shapes (frequency, bandwidth) tried around a broad spectral peak: frequency at the
/// peak's plus {-1, -3/4, ..., +1} times its bandwidth, bandwidth at {0.15, 0.2, 0.3, 0.5, 0.7, 1, 1.4,
/// 2, 3} times the peak's (the peak of a whole log is wider than the mode when its frequency wanders);
/// only underdamped shapes below the Nyquist frequency (81 at most).
pub fn resonance_grid(peak: crate::spectrum::SpectralPeak, dt_s: f64) -> Vec<(f64, f64)> {
    let nyquist = 0.5 / dt_s;
    let mut out = Vec::new();
    for i in -4..=4 {
        let f = peak.frequency_hz + f64::from(i) / 4.0 * peak.bandwidth_hz;
        for s in [0.15, 0.2, 0.3, 0.5, 0.7, 1.0, 1.4, 2.0, 3.0] {
            let b = s * peak.bandwidth_hz;
            if f > 0.0 && f < nyquist && b < 2.0 * f {
                out.push((f, b));
            }
        }
    }
    out
}

/// The shapes tried around a resonance shape (f0, bw): frequency moved by {-2, -1, 0, 1, 2} x
/// `step` / 8 of the bandwidth, bandwidth at (1 + {-2, -1, 0, 1, 2} x `step` x 0.15) times its own
/// (25 at most; `step` 2 gives quarter bandwidths and 0.4-1.6 times).
pub fn resonance_refinement((f0, bw): (f64, f64), step: f64, dt_s: f64) -> Vec<(f64, f64)> {
    let nyquist = 0.5 / dt_s;
    let mut out = vec![(f0, bw)];
    for i in -2..=2 {
        let f = f0 + f64::from(i) * step / 8.0 * bw;
        for j in -2..=2 {
            let b = bw * (1.0 + f64::from(j) * step * 0.15);
            if (i, j) != (0, 0) && f > 0.0 && f < nyquist && b > 0.0 && b < 2.0 * f {
                out.push((f, b));
            }
        }
    }
    out
}

/// Allan variance per unit variance of a resonance (f0, bandwidth) at each tau, through `filter`.
pub fn resonance_signature(
    filter: Option<&OutputFilter>,
    (f0_hz, bandwidth_hz): (f64, f64),
    taus_s: &[f64],
    dt_s: f64,
) -> Vec<f64> {
    match filter {
        Some(f) => {
            let fa = noise::filter::FilteredAllan::new(f, dt_s);
            taus_s
                .iter()
                .map(|&t| fa.resonance(1.0, f0_hz, bandwidth_hz, t))
                .collect()
        }
        None => taus_s
            .iter()
            .map(|&t| cf::resonance_avar_sampled(1.0, f0_hz, bandwidth_hz, t, dt_s))
            .collect(),
    }
}

/// Look-elsewhere cost of a shape chosen from `n` grid values, on the chi2 (-2 ln L) scale: the
/// description length of the choice, 2 ln n (minimum description length, Rissanen 1978). Without it the
/// best of hundreds of sinusoid frequencies fits noise often enough to name effects on clean logs.
pub fn shape_search_penalty(n: usize) -> f64 {
    if n > 1 {
        2.0 * (n as f64).ln()
    } else {
        0.0
    }
}

/// The output filters diagnose tries, at output interval `dt_s`: for decimations 1, 2, 4, 8, 10 and 16,
/// moving averages of 1..8 output intervals, Bartlett windows of 1.5..16 output intervals, first- and
/// second-order low-passes with cutoffs from 0.005 to 0.4 times the internal rate, 10 of each,
/// log-spaced (the Allan signature depends on the filter's response measured in output intervals, so
/// this spans the filters that shape the shortest taus). Duplicates removed.
pub fn filter_grid(dt_s: f64) -> Vec<OutputFilter> {
    let mut out: Vec<OutputFilter> = Vec::new();
    let log = |lo: f64, hi: f64, j: usize| lo * (hi / lo).powf(j as f64 / 9.0);
    for d in [1u32, 2, 4, 8, 10, 16] {
        let f_int = f64::from(d) / dt_s;
        for j in 0..10 {
            let ma = (f64::from(d) * log(1.0, 8.0, j)).round() as u32;
            let bt = (f64::from(d) * log(1.5, 16.0, j)).round() as u32;
            let fc = f_int * log(0.005, 0.4, j);
            let kinds = [
                (ma >= 2).then_some(FilterKind::MovingAverage { taps: ma }),
                (bt >= 3).then_some(FilterKind::Bartlett { taps: bt }),
                Some(FilterKind::LowPass1 { cutoff_hz: fc }),
                Some(FilterKind::LowPass2 { cutoff_hz: fc }),
            ];
            for kind in kinds.into_iter().flatten() {
                if let Ok(f) = OutputFilter::new(kind, d) {
                    if f.check_rate(dt_s).is_ok() && !out.contains(&f) {
                        out.push(f);
                    }
                }
            }
        }
    }
    out
}

/// Allan variance per unit squared white-noise density at each tau, through `filter` (None: 1/tau).
pub fn white_signature(filter: Option<&OutputFilter>, taus_s: &[f64], dt_s: f64) -> Vec<f64> {
    match filter {
        Some(f) => {
            let fa = noise::filter::FilteredAllan::new(f, dt_s);
            taus_s.iter().map(|&t| fa.white_noise(1.0, t)).collect()
        }
        None => taus_s
            .iter()
            .map(|&t| cf::white_noise_avar(1.0, t))
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use noise::{AxisModel, GaussMarkov, Sensor, Sinusoid};

    /// On a filtered channel every candidate's signature is the Allan variance the generator gives
    /// it (the axis model's own sampled form, filter included): a candidate fitted unfiltered but
    /// simulated filtered once made a stand-in that fitted on paper and added nothing. The filter is
    /// the S5's shape (a first-order low-pass at a hundredth of the rate), where the two differ by
    /// orders of magnitude at tau = dt; agreement to 1e-9 relative (rounding of the same sums).
    #[test]
    fn signatures_go_through_the_channel_filter_as_generated() {
        let dt = 0.1;
        let filter = OutputFilter::new(FilterKind::LowPass1 { cutoff_hz: 0.1 }, 1).unwrap();
        let mut model = SensorModel::default();
        model.axis_mut(Sensor::Gyro, 0).set_term(filter);
        let ch = Channel::Gx;
        let fa = filtered_allan(&model, ch, dt).expect("the channel has a filter");
        let flicker = flicker_band(&model, ch);
        let as_generated = |term: Term, tau: f64| {
            AxisModel::default()
                .with(filter)
                .with(term)
                .allan_variance_sampled(tau, dt)
        };
        for tau in [dt, 1.0, 12.8, 409.6] {
            let close = |a: f64, b: f64| ((a - b) / b).abs() < 1e-9;
            for (effect, term) in [
                (Effect::WhiteNoise, WhiteNoise::new(1.0).unwrap().into()),
                (
                    Effect::OutputWhiteNoise,
                    OutputWhiteNoise::new(1.0).unwrap().into(),
                ),
                (
                    Effect::RateRandomWalk,
                    RateRandomWalk::new(1.0).unwrap().into(),
                ),
                (
                    Effect::BiasInstability,
                    BiasInstability::Flicker(flicker.clone()).into(),
                ),
            ] {
                let f = unit_signature(effect, tau, dt, &flicker, Some(&fa));
                assert!(close(f, as_generated(term, tau)), "{effect} at {tau} s");
            }
            let gm = unit_family_signature(Effect::GaussMarkov, 0.02, tau, dt, Some(&fa));
            assert!(close(
                gm,
                as_generated(GaussMarkov::new(1.0, 0.02).unwrap().into(), tau)
            ));
            let sine = unit_family_signature(Effect::Sinusoidal, 0.3, tau, dt, Some(&fa));
            let s0 = Sinusoid::new(1.0, 0.3, None).unwrap().into();
            assert!(close(sine, as_generated(s0, tau)), "sinusoid at {tau} s");
        }
        // The filter matters here: a fast Gauss-Markov process loses most of its short-tau variance.
        let unfiltered = unit_family_signature(Effect::GaussMarkov, 0.02, dt, dt, None);
        let filtered = unit_family_signature(Effect::GaussMarkov, 0.02, dt, dt, Some(&fa));
        assert!(filtered < 0.01 * unfiltered, "{filtered} vs {unfiltered}");
    }
}
