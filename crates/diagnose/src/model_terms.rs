//! Reading and changing one term of one channel of a `SensorModel` in diagnose's parameterisation.

use crate::candidates::TermParams;
use noise::{BiasInstability, Channel, Effect, Flicker, GaussMarkov, SensorModel, Sinusoid, Term};

/// The level the model has for `effect` on channel `ch` (None when absent, or when the term is not in a
/// form diagnose fits: a Woodman random-walk bias instability is read as absent flicker).
pub fn term_level(model: &SensorModel, ch: Channel, effect: Effect) -> Option<TermParams> {
    let (sensor, axis) = (ch.sensor(), ch.axis());
    Some(match model.axis(sensor, axis).term(effect)? {
        Term::Quantization(v)
        | Term::WhiteNoise(v)
        | Term::RateRandomWalk(v)
        | Term::RateRamp(v)
        | Term::TemperatureBias(v) => TermParams::Level(v),
        Term::BiasInstability(BiasInstability::Flicker(f)) => TermParams::Level(f.b),
        Term::GaussMarkov(g) => TermParams::GaussMarkov {
            sigma: g.sigma,
            tau_s: g.tau_s,
        },
        Term::Sinusoidal(s) => TermParams::Sinusoid {
            amplitude: s.amplitude,
            frequency_hz: s.frequency_hz,
        },
        Term::Resonance(r) => TermParams::Resonance {
            sigma: r.sigma,
            frequency_hz: r.frequency_hz,
            bandwidth_hz: r.bandwidth_hz,
        },
        Term::OutputFilter(filter) => TermParams::Filter {
            filter,
            n: model.axis(sensor, axis).white_noise.unwrap_or(0.0),
        },
        _ => return None,
    })
}

/// The output filter channel `ch` has, if any.
pub fn output_filter(model: &SensorModel, ch: Channel) -> Option<noise::OutputFilter> {
    let (sensor, axis) = (ch.sensor(), ch.axis());
    model.axis(sensor, axis).output_filter
}

/// Does channel `ch` model its bias instability as Woodman's random walk (TR-696 eq 9)?
pub fn has_random_walk_bias_instability(model: &SensorModel, ch: Channel) -> bool {
    let (sensor, axis) = (ch.sensor(), ch.axis());
    matches!(
        model.axis(sensor, axis).bias_instability,
        Some(BiasInstability::RandomWalk { .. })
    )
}

/// The flicker band the model uses on channel `ch` (its own, or the noise crate's default).
pub fn flicker_band(model: &SensorModel, ch: Channel) -> Flicker {
    let (sensor, axis) = (ch.sensor(), ch.axis());
    match &model.axis(sensor, axis).bias_instability {
        Some(BiasInstability::Flicker(f)) => Flicker {
            b: 1.0,
            ..f.clone()
        },
        _ => Flicker::with_b(1.0),
    }
}

/// Set `effect` on channel `ch` to `params` (adding it if absent); parameters that do not fit the
/// effect change nothing.
pub fn set_term(model: &mut SensorModel, ch: Channel, effect: Effect, params: &TermParams) {
    let band = flicker_band(model, ch);
    let (sensor, axis) = (ch.sensor(), ch.axis());
    let a = model.axis_mut(sensor, axis);
    let term = match (effect, *params) {
        (Effect::Quantization, TermParams::Level(v)) => Term::Quantization(v),
        (Effect::WhiteNoise, TermParams::Level(v)) => Term::WhiteNoise(v),
        (Effect::BiasInstability, TermParams::Level(v)) => {
            Term::BiasInstability(BiasInstability::Flicker(Flicker { b: v, ..band }))
        }
        (Effect::RateRandomWalk, TermParams::Level(v)) => Term::RateRandomWalk(v),
        (Effect::RateRamp, TermParams::Level(v)) => Term::RateRamp(v),
        (Effect::TemperatureBias, TermParams::Level(v)) => Term::TemperatureBias(v),
        (Effect::GaussMarkov, TermParams::GaussMarkov { sigma, tau_s }) => {
            Term::GaussMarkov(GaussMarkov { sigma, tau_s })
        }
        (
            Effect::Sinusoidal,
            TermParams::Sinusoid {
                amplitude,
                frequency_hz,
            },
        ) => Term::Sinusoidal(Sinusoid {
            amplitude,
            frequency_hz,
            phase_rad: a.sinusoidal.and_then(|s| s.phase_rad),
        }),
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
            a.white_noise = Some(n);
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
