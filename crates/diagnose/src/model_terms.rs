//! Reading and changing one term of one channel of a `SensorModel` in diagnose's parameterisation.

use crate::candidates::TermParams;
use noise::{
    BiasInstability, Channel, Effect, Flicker, GaussMarkov, OutputFilter, Quantization, RateRamp,
    RateRandomWalk, SensorModel, Sinusoid, TemperatureBias, Term, WhiteNoise,
};

/// The level the model has for `effect` on channel `ch` (None when absent, or when the term is not in a
/// form diagnose fits: a Woodman random-walk bias instability is read as absent flicker).
pub fn term_level(model: &SensorModel, ch: Channel, effect: Effect) -> Option<TermParams> {
    let (sensor, axis) = (ch.sensor(), ch.axis());
    Some(match model.axis(sensor, axis).term(effect)?.clone() {
        Term::Quantization(q) => TermParams::Level(q.coefficient()),
        Term::WhiteNoise(n) => TermParams::Level(n.density()),
        Term::RateRandomWalk(k) => TermParams::Level(k.density()),
        Term::RateRamp(r) => TermParams::Level(r.rate()),
        Term::TemperatureBias(c) => TermParams::Level(c.per_degree()),
        Term::BiasInstability(BiasInstability::Flicker(f)) => TermParams::Level(f.b()),
        Term::GaussMarkov(g) => TermParams::GaussMarkov {
            sigma: g.sigma(),
            tau_s: g.tau_s(),
        },
        Term::Sinusoidal(s) => TermParams::Sinusoid {
            amplitude: s.amplitude(),
            frequency_hz: s.frequency_hz(),
        },
        Term::Resonance(r) => TermParams::Resonance {
            sigma: r.sigma(),
            frequency_hz: r.frequency_hz(),
            bandwidth_hz: r.bandwidth_hz(),
        },
        Term::OutputFilter(filter) => TermParams::Filter {
            filter,
            n: model
                .axis(sensor, axis)
                .get::<WhiteNoise>()
                .map_or(0.0, WhiteNoise::density),
        },
        _ => return None,
    })
}

/// The output filter channel `ch` has, if any.
pub fn output_filter(model: &SensorModel, ch: Channel) -> Option<noise::OutputFilter> {
    let (sensor, axis) = (ch.sensor(), ch.axis());
    model.axis(sensor, axis).get::<OutputFilter>().copied()
}

/// Does channel `ch` model its bias instability as Woodman's random walk (TR-696 eq 9)?
pub fn has_random_walk_bias_instability(model: &SensorModel, ch: Channel) -> bool {
    let (sensor, axis) = (ch.sensor(), ch.axis());
    matches!(
        model.axis(sensor, axis).get::<BiasInstability>(),
        Some(BiasInstability::RandomWalk { .. })
    )
}

/// The flicker band the model uses on channel `ch` (its own, or the noise crate's default).
pub fn flicker_band(model: &SensorModel, ch: Channel) -> Flicker {
    let (sensor, axis) = (ch.sensor(), ch.axis());
    match model.axis(sensor, axis).get::<BiasInstability>() {
        Some(BiasInstability::Flicker(f)) => f.with_level(1.0),
        _ => Flicker::with_b(1.0),
    }
    .expect("B = 1 is a valid level")
}

/// Set `effect` on channel `ch` to `params` (adding it if absent); parameters that do not fit the
/// effect change nothing.
pub fn set_term(model: &mut SensorModel, ch: Channel, effect: Effect, params: &TermParams) {
    let band = flicker_band(model, ch);
    let (sensor, axis) = (ch.sensor(), ch.axis());
    let a = model.axis_mut(sensor, axis);
    // A value the term's constructor refuses changes nothing, as a mismatched effect.
    let level = |v: f64, term: fn(f64) -> Option<Term>| term(v);
    let term = match (effect, *params) {
        (Effect::Quantization, TermParams::Level(v)) => {
            match level(v, |v| Some(Quantization::new(v).ok()?.into())) {
                Some(t) => t,
                None => return,
            }
        }
        (Effect::WhiteNoise, TermParams::Level(v)) => {
            match level(v, |v| Some(WhiteNoise::new(v).ok()?.into())) {
                Some(t) => t,
                None => return,
            }
        }
        (Effect::BiasInstability, TermParams::Level(v)) => match band.with_level(v) {
            Ok(f) => Term::BiasInstability(BiasInstability::Flicker(f)),
            Err(_) => return,
        },
        (Effect::RateRandomWalk, TermParams::Level(v)) => {
            match level(v, |v| Some(RateRandomWalk::new(v).ok()?.into())) {
                Some(t) => t,
                None => return,
            }
        }
        (Effect::RateRamp, TermParams::Level(v)) => {
            match level(v, |v| Some(RateRamp::new(v).ok()?.into())) {
                Some(t) => t,
                None => return,
            }
        }
        (Effect::TemperatureBias, TermParams::Level(v)) => {
            match level(v, |v| Some(TemperatureBias::new(v).ok()?.into())) {
                Some(t) => t,
                None => return,
            }
        }
        (Effect::GaussMarkov, TermParams::GaussMarkov { sigma, tau_s }) => {
            match GaussMarkov::new(sigma, tau_s) {
                Ok(g) => Term::GaussMarkov(g),
                Err(_) => return,
            }
        }
        (
            Effect::Sinusoidal,
            TermParams::Sinusoid {
                amplitude,
                frequency_hz,
            },
        ) => match Sinusoid::new(
            amplitude,
            frequency_hz,
            a.get::<Sinusoid>().and_then(|s| s.phase_rad()),
        ) {
            Ok(s) => Term::Sinusoidal(s),
            Err(_) => return,
        },
        (
            Effect::Resonance,
            TermParams::Resonance {
                sigma,
                frequency_hz,
                bandwidth_hz,
            },
        ) => match noise::Resonance::new(sigma, frequency_hz, bandwidth_hz) {
            Ok(r) => Term::Resonance(r),
            Err(_) => return,
        },
        (Effect::OutputFilter, TermParams::Filter { filter, n }) => {
            let Ok(n) = WhiteNoise::new(n) else { return };
            a.set_term(n);
            Term::OutputFilter(filter)
        }
        _ => return,
    };
    a.set_term(term);
}

/// Remove `effect` from channel `ch`.
pub fn clear_term(model: &mut SensorModel, ch: Channel, effect: Effect) {
    let (sensor, axis) = (ch.sensor(), ch.axis());
    model.axis_mut(sensor, axis).remove(effect);
}
