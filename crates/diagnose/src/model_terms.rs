//! Reading and changing one term of one channel of a `SensorModel` in diagnose's parameterisation.

use crate::candidates::TermParams;
use noise::{BiasInstability, Effect, Flicker, GaussMarkov, Sensor, SensorModel, Sinusoid};

/// Channel index (gx gy gz ax ay az) to (sensor, axis).
pub fn channel_axis(ch: usize) -> (Sensor, usize) {
    if ch < 3 {
        (Sensor::Gyro, ch)
    } else {
        (Sensor::Accel, ch - 3)
    }
}

/// The level the model has for `effect` on channel `ch` (None when absent, or when the term is not in a
/// form diagnose fits: a Woodman random-walk bias instability is read as absent flicker).
pub fn term_level(model: &SensorModel, ch: usize, effect: Effect) -> Option<TermParams> {
    let (sensor, axis) = channel_axis(ch);
    let a = model.axis(sensor, axis);
    match effect {
        Effect::Quantization => a.quantization.map(TermParams::Level),
        Effect::WhiteNoise => a.white_noise.map(TermParams::Level),
        Effect::BiasInstability => match &a.bias_instability {
            Some(BiasInstability::Flicker(f)) => Some(TermParams::Level(f.b)),
            _ => None,
        },
        Effect::RateRandomWalk => a.rate_random_walk.map(TermParams::Level),
        Effect::RateRamp => a.rate_ramp.map(TermParams::Level),
        Effect::GaussMarkov => a.gauss_markov.map(|g| TermParams::GaussMarkov {
            sigma: g.sigma,
            tau_s: g.tau_s,
        }),
        Effect::Sinusoidal => a.sinusoidal.map(|s| TermParams::Sinusoid {
            amplitude: s.amplitude,
            frequency_hz: s.frequency_hz,
        }),
        Effect::TemperatureBias => a.temperature_bias.map(TermParams::Level),
        _ => None,
    }
}

/// Does channel `ch` model its bias instability as Woodman's random walk (TR-696 eq 9)?
pub fn has_random_walk_bias_instability(model: &SensorModel, ch: usize) -> bool {
    let (sensor, axis) = channel_axis(ch);
    matches!(
        model.axis(sensor, axis).bias_instability,
        Some(BiasInstability::RandomWalk { .. })
    )
}

/// The flicker band the model uses on channel `ch` (its own, or the noise crate's default).
pub fn flicker_band(model: &SensorModel, ch: usize) -> Flicker {
    let (sensor, axis) = channel_axis(ch);
    match &model.axis(sensor, axis).bias_instability {
        Some(BiasInstability::Flicker(f)) => Flicker {
            b: 1.0,
            ..f.clone()
        },
        _ => Flicker::with_b(1.0),
    }
}

/// Set `effect` on channel `ch` to `params` (adding it if absent).
pub fn set_term(model: &mut SensorModel, ch: usize, effect: Effect, params: &TermParams) {
    let band = flicker_band(model, ch);
    let (sensor, axis) = channel_axis(ch);
    let a = model.axis_mut(sensor, axis);
    match (effect, *params) {
        (Effect::Quantization, TermParams::Level(v)) => a.quantization = Some(v),
        (Effect::WhiteNoise, TermParams::Level(v)) => a.white_noise = Some(v),
        (Effect::BiasInstability, TermParams::Level(v)) => {
            a.bias_instability = Some(BiasInstability::Flicker(Flicker { b: v, ..band }))
        }
        (Effect::RateRandomWalk, TermParams::Level(v)) => a.rate_random_walk = Some(v),
        (Effect::RateRamp, TermParams::Level(v)) => a.rate_ramp = Some(v),
        (Effect::TemperatureBias, TermParams::Level(v)) => a.temperature_bias = Some(v),
        (Effect::GaussMarkov, TermParams::GaussMarkov { sigma, tau_s }) => {
            a.gauss_markov = Some(GaussMarkov { sigma, tau_s })
        }
        (
            Effect::Sinusoidal,
            TermParams::Sinusoid {
                amplitude,
                frequency_hz,
            },
        ) => {
            let phase_rad = a.sinusoidal.and_then(|s| s.phase_rad);
            a.sinusoidal = Some(Sinusoid {
                amplitude,
                frequency_hz,
                phase_rad,
            })
        }
        _ => {}
    }
}

/// Remove `effect` from channel `ch`.
pub fn clear_term(model: &mut SensorModel, ch: usize, effect: Effect) {
    let (sensor, axis) = channel_axis(ch);
    model.axis_mut(sensor, axis).remove(effect);
}
