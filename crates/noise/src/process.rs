//! The per-run error state: exact discretisation of every term at the sample interval
//! (theory.md §3), one random sub-stream per (channel, term) so adding a term does not reshuffle others.
//! The discrete processes take their RNG as an argument; `ChannelErrors` pairs each with its sub-stream.

use crate::effect::{Effect, Sensor};
use crate::model::{BiasInstability, SensorModel, TemperatureProfile};
use crate::{term_rng, ImuRng};
use nalgebra::Vector3;
use rand::Rng;
use rand_distr::StandardNormal;

/// Channel order of `ImuErrors` and of generated logs.
pub const CHANNEL_NAMES: [&str; 6] = ["gx", "gy", "gz", "ax", "ay", "az"];

#[inline]
fn normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    rng.sample(StandardNormal)
}

/// White noise of density N sampled every dt: n_k = (N / sqrt(dt)) w_k (theory.md §3; Kalibr
/// sigma_d = sigma / sqrt(dt); Woodman sigma = N / sqrt(dt)).
#[derive(Clone, Copy, Debug)]
pub struct WhiteNoise {
    sd: f64,
}

impl WhiteNoise {
    pub fn new(n: f64, dt_s: f64) -> WhiteNoise {
        WhiteNoise {
            sd: n / dt_s.sqrt(),
        }
    }
    #[inline]
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        self.sd * normal(rng)
    }
}

/// A bank of independent first-order Gauss-Markov processes, summed (one process, or flicker's band).
/// Exact discretisation (theory.md §3, rotors_simulator / Maybeck 4-114):
/// x_{k+1} = phi x_k + sigma sqrt(1 - phi^2) w_k, phi = e^{-dt/T}; started from the stationary distribution.
#[derive(Clone, Debug)]
pub struct GaussMarkovBank {
    phi: Vec<f64>,
    drive: Vec<f64>,
    state: Vec<f64>,
}

impl GaussMarkovBank {
    /// `components`: (correlation time s, stationary std); the initial state is drawn from `rng`.
    pub fn new<R: Rng + ?Sized>(components: &[(f64, f64)], dt_s: f64, rng: &mut R) -> Self {
        GaussMarkovBank {
            phi: components
                .iter()
                .map(|&(tc, _)| (-dt_s / tc).exp())
                .collect(),
            // sigma sqrt(1 - phi^2) = sigma sqrt(-expm1(-2 dt/T)), accurate for T >> dt.
            drive: components
                .iter()
                .map(|&(tc, s)| s * (-(-2.0 * dt_s / tc).exp_m1()).sqrt())
                .collect(),
            state: components.iter().map(|&(_, s)| s * normal(rng)).collect(),
        }
    }

    /// The current value (sum of the components), then advance one step.
    #[inline]
    pub fn next<R: Rng + ?Sized>(&mut self, rng: &mut R) -> f64 {
        let mut sum = 0.0;
        for ((x, &phi), &d) in self.state.iter_mut().zip(&self.phi).zip(&self.drive) {
            sum += *x;
            *x = phi * *x + d * normal(rng);
        }
        sum
    }
}

/// Random walk b_{k+1} = b_k + K sqrt(dt) w_k from b_0 = 0 (theory.md §3, Kalibr: sigma_bd = sigma_b sqrt(dt)).
#[derive(Clone, Copy, Debug)]
pub struct RandomWalk {
    step: f64,
    state: f64,
}

impl RandomWalk {
    pub fn new(k: f64, dt_s: f64) -> RandomWalk {
        RandomWalk {
            step: k * dt_s.sqrt(),
            state: 0.0,
        }
    }
    /// The current value, then advance one step.
    #[inline]
    pub fn next<R: Rng + ?Sized>(&mut self, rng: &mut R) -> f64 {
        let b = self.state;
        self.state += self.step * normal(rng);
        b
    }
}

/// Quantisation of the integrated output (DESIGN.md: so its Allan signature is the tau^-1 slope):
/// the output released in a sample is a whole number of LSBs of the integral, LSB = Q sqrt(12)
/// (Hou §4.3.1, Q = LSB/sqrt(12)). `residual` is the integral not yet released.
#[derive(Clone, Copy, Debug)]
pub struct Quantizer {
    lsb: f64,
    residual: f64,
}

impl Quantizer {
    /// The quantiser's phase on the LSB grid is drawn from `rng`, so no run starts on a step.
    pub fn new<R: Rng + ?Sized>(q: f64, rng: &mut R) -> Quantizer {
        let lsb = q * 12f64.sqrt();
        Quantizer {
            lsb,
            residual: lsb * (rng.gen::<f64>() - 0.5),
        }
    }
    #[inline]
    pub fn apply(&mut self, value: f64, dt_s: f64) -> f64 {
        self.residual += value * dt_s;
        let n = (self.residual / self.lsb).round();
        self.residual -= n * self.lsb;
        n * self.lsb / dt_s
    }
}

/// The error generator of one output channel (one axis of one triad) for one run.
#[derive(Clone, Debug)]
pub struct ChannelErrors {
    dt_s: f64,
    /// Row of (I + scale factor + misalignment) applied to the ideal triad input.
    row: [f64; 3],
    /// Constant bias plus this run's turn-on bias draw.
    bias: f64,
    white: Option<(WhiteNoise, ImuRng)>,
    flicker: Option<(GaussMarkovBank, ImuRng)>,
    bias_random_walk: Option<(RandomWalk, ImuRng)>,
    rate_random_walk: Option<(RandomWalk, ImuRng)>,
    ramp: f64,
    gauss_markov: Option<(GaussMarkovBank, ImuRng)>,
    /// amplitude, angular frequency (rad/s), phase (rad)
    sinusoid: Option<(f64, f64, f64)>,
    /// coefficient per degC, profile, reference degC
    temperature: Option<(f64, TemperatureProfile, f64)>,
    quantizer: Option<Quantizer>,
    /// The k the next call must bring (the states advance one step per call); checked in debug
    /// builds only (keeping it up to date costs ~30 % of the sample time in release).
    #[cfg(debug_assertions)]
    next_k: u64,
}

impl ChannelErrors {
    fn new(model: &SensorModel, channel: usize, dt_s: f64, seed: u64, run: u64) -> ChannelErrors {
        let sensor = if channel < 3 {
            Sensor::Gyro
        } else {
            Sensor::Accel
        };
        let axis_index = channel % 3;
        let axis = model.axis(sensor, axis_index);
        let rng = |effect: Effect| term_rng(seed, run, channel as u64, effect);

        let mut row = [0.0; 3];
        row[axis_index] = 1.0 + axis.scale_factor.unwrap_or(0.0);
        if let Some(m) = axis.misalignment {
            let others: Vec<usize> = (0..3).filter(|&j| j != axis_index).collect();
            row[others[0]] = m[0];
            row[others[1]] = m[1];
        }
        let turn_on = axis
            .turn_on_bias
            .map_or(0.0, |s| s * normal(&mut rng(Effect::TurnOnBias)));
        // Each process with its own sub-stream; initial states come from that stream first.
        let bank = |components: &[(f64, f64)], effect: Effect| {
            let mut r = rng(effect);
            (GaussMarkovBank::new(components, dt_s, &mut r), r)
        };
        let (flicker, bias_random_walk) = match &axis.bias_instability {
            Some(BiasInstability::Flicker(f)) => {
                (Some(bank(&f.components(), Effect::BiasInstability)), None)
            }
            // Woodman eq 9 / AirSim: K = BS / sqrt(T_BS), so BS·sqrt(dt/T_BS) per step.
            Some(BiasInstability::RandomWalk {
                stability,
                period_s,
            }) => (
                None,
                Some((
                    RandomWalk::new(stability / period_s.sqrt(), dt_s),
                    rng(Effect::BiasInstability),
                )),
            ),
            None => (None, None),
        };
        ChannelErrors {
            dt_s,
            row,
            bias: axis.constant_bias.unwrap_or(0.0) + turn_on,
            white: axis
                .white_noise
                .map(|n| (WhiteNoise::new(n, dt_s), rng(Effect::WhiteNoise))),
            flicker,
            bias_random_walk,
            rate_random_walk: axis
                .rate_random_walk
                .map(|k| (RandomWalk::new(k, dt_s), rng(Effect::RateRandomWalk))),
            ramp: axis.rate_ramp.unwrap_or(0.0),
            gauss_markov: axis
                .gauss_markov
                .map(|g| bank(&[(g.tau_s, g.sigma)], Effect::GaussMarkov)),
            sinusoid: axis.sinusoidal.map(|s| {
                let phase = s.phase_rad.unwrap_or_else(|| {
                    rng(Effect::Sinusoidal).gen_range(0.0..std::f64::consts::TAU)
                });
                (s.amplitude, std::f64::consts::TAU * s.frequency_hz, phase)
            }),
            temperature: axis
                .temperature_bias
                .map(|c| (c, model.temperature.clone(), model.temperature_reference_c)),
            quantizer: axis
                .quantization
                .map(|q| Quantizer::new(q, &mut rng(Effect::Quantization))),
            #[cfg(debug_assertions)]
            next_k: 0,
        }
    }

    /// The measured value of sample `k` (t = k·dt) given the ideal triad input. Calls must come with
    /// k = 0, 1, 2, ... in order: the stochastic states advance one step per call.
    #[inline]
    pub fn sample(&mut self, k: u64, ideal: &Vector3<f64>) -> f64 {
        #[cfg(debug_assertions)]
        {
            assert_eq!(k, self.next_k, "samples must be drawn in order");
            self.next_k = k + 1;
        }
        let t_s = k as f64 * self.dt_s;
        let mut v =
            self.row[0] * ideal.x + self.row[1] * ideal.y + self.row[2] * ideal.z + self.bias;
        if let Some((w, rng)) = &mut self.white {
            v += w.sample(rng);
        }
        if let Some((f, rng)) = &mut self.flicker {
            v += f.next(rng);
        }
        if let Some((w, rng)) = &mut self.bias_random_walk {
            v += w.next(rng);
        }
        if let Some((w, rng)) = &mut self.rate_random_walk {
            v += w.next(rng);
        }
        v += self.ramp * t_s;
        if let Some((g, rng)) = &mut self.gauss_markov {
            v += g.next(rng);
        }
        if let Some((a, omega, phase)) = self.sinusoid {
            v += a * (omega * t_s + phase).sin();
        }
        if let Some((c, profile, reference)) = &self.temperature {
            v += c * (profile.at(t_s) - reference);
        }
        if let Some(q) = &mut self.quantizer {
            v = q.apply(v, self.dt_s);
        }
        v
    }

    /// Samples `k0 .. k0 + out.len()` for a constant ideal input (a static IMU).
    pub fn fill_static(&mut self, k0: u64, ideal: &Vector3<f64>, out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.sample(k0 + i as u64, ideal);
        }
    }
}

/// Per-run error state of a whole IMU: six channels (gx gy gz ax ay az).
#[derive(Clone, Debug)]
pub struct ImuErrors {
    channels: [ChannelErrors; 6],
    temperature: TemperatureProfile,
    dt_s: f64,
}

impl ImuErrors {
    /// Draw run `run`'s per-run values (turn-on bias, initial states, phases) from `seed`.
    /// `dt_s` must be finite and > 0.
    pub fn new(model: &SensorModel, dt_s: f64, seed: u64, run: u64) -> ImuErrors {
        assert!(
            dt_s.is_finite() && dt_s > 0.0,
            "sample interval must be > 0, got {dt_s}"
        );
        ImuErrors {
            channels: std::array::from_fn(|c| ChannelErrors::new(model, c, dt_s, seed, run)),
            temperature: model.temperature.clone(),
            dt_s,
        }
    }

    /// Corrupt the ideal sample k (t = k·dt): (measured gyro rad/s, measured accel m/s^2), body frame.
    /// Calls must come with k = 0, 1, 2, ... in order.
    pub fn corrupt(
        &mut self,
        k: u64,
        ideal_gyro: &Vector3<f64>,
        ideal_accel: &Vector3<f64>,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let [g0, g1, g2, a0, a1, a2] = &mut self.channels;
        (
            Vector3::new(
                g0.sample(k, ideal_gyro),
                g1.sample(k, ideal_gyro),
                g2.sample(k, ideal_gyro),
            ),
            Vector3::new(
                a0.sample(k, ideal_accel),
                a1.sample(k, ideal_accel),
                a2.sample(k, ideal_accel),
            ),
        )
    }

    /// Sensor temperature at sample k, degC.
    pub fn temperature_c(&self, k: u64) -> f64 {
        self.temperature.at(k as f64 * self.dt_s)
    }

    /// The six channel generators, for generating channels independently (e.g. in parallel):
    /// each owns its random streams, so the result does not depend on how they are scheduled.
    pub fn channels_mut(&mut self) -> &mut [ChannelErrors; 6] {
        &mut self.channels
    }

    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }
}
