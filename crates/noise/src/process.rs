//! The per-run error state: exact discretisation of every term at the sample interval
//! (docs/model.md §3), one random sub-stream per (channel, term) so adding a term does not reshuffle others.
//! The discrete processes take their RNG as an argument; `ChannelErrors` pairs each with its sub-stream.

use crate::effect::{Effect, Sensor};
use crate::model::SensorModel;
use crate::temperature::TemperatureProfile;
use crate::terms::bias_instability::BiasInstability;
use crate::terms::constant_bias::ConstantBias;
use crate::terms::gauss_markov::GaussMarkov;
use crate::terms::misalignment::Misalignment;
use crate::terms::outliers::Outliers;
use crate::terms::output_filter::OutputFilter;
use crate::terms::quantization::Quantization;
use crate::terms::rate_ramp::RateRamp;
use crate::terms::rate_random_walk::RateRandomWalk;
use crate::terms::resonance::Resonance;
use crate::terms::scale_factor::ScaleFactor;
use crate::terms::sinusoidal::Sinusoid;
use crate::terms::temperature_bias::TemperatureBias;
use crate::terms::turn_on_bias::TurnOnBias;
use crate::terms::warmup_transient::WarmupTransient;
use crate::terms::white_noise::WhiteNoise as WhiteNoiseTerm;
use crate::{calibration_rng, term_rng, ImuRng};
use nalgebra::Vector3;
use rand::Rng;

/// Channel order of `ImuErrors` and of generated logs.
pub const CHANNEL_NAMES: [&str; 6] = ["gx", "gy", "gz", "ax", "ay", "az"];

/// One standard normal (rand_distr's `StandardNormal`, bit for bit; inlined, see `ziggurat`).
#[inline]
fn normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    crate::ziggurat::standard_normal(rng)
}

/// `out.len()` standard normals from `rng`, in order: the same values as that many `normal` calls.
/// One tight loop with the ziggurat inlined (perf: about 2.0 ns per draw with Xoshiro256++ on the
/// 2-core CI machine, against 2.6 ns for rand_distr's out-of-line sampler).
#[inline(never)]
fn fill_normals(rng: &mut ImuRng, out: &mut [f64]) {
    for w in out {
        *w = crate::ziggurat::standard_normal(rng);
    }
}

/// `n` fresh normals of `rng` in `scratch` (grown as needed).
fn draws<'a>(rng: &mut ImuRng, scratch: &'a mut Vec<f64>, n: usize) -> &'a [f64] {
    if scratch.len() < n {
        scratch.resize(n, 0.0);
    }
    fill_normals(rng, &mut scratch[..n]);
    &scratch[..n]
}

/// White noise of density N sampled every dt: n_k = (N / sqrt(dt)) w_k (docs/model.md §3; Kalibr
/// sigma_d = sigma / sqrt(dt); Woodman sigma = N / sqrt(dt)).
#[derive(Clone, Copy, Debug)]
pub struct WhiteNoiseSampler {
    sd: f64,
}

impl WhiteNoiseSampler {
    pub fn new(n: f64, dt_s: f64) -> WhiteNoiseSampler {
        WhiteNoiseSampler {
            sd: n / dt_s.sqrt(),
        }
    }
    #[inline]
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        self.sd * normal(rng)
    }
    /// Add the next `out.len()` values to `out` (the values of as many `sample` calls).
    fn add_block(&self, rng: &mut ImuRng, out: &mut [f64], scratch: &mut Vec<f64>) {
        let n = out.len();
        for (v, w) in out.iter_mut().zip(draws(rng, scratch, n)) {
            *v += self.sd * w;
        }
    }
}

/// A bank of independent first-order Gauss-Markov processes, summed (one process, or flicker's band).
/// Exact discretisation (docs/model.md §3, rotors_simulator / Maybeck 4-114):
/// x_{k+1} = phi x_k + sigma sqrt(1 - phi^2) w_k, phi = e^{-dt/T}; started from the stationary distribution.
///
/// Multi-rate option ([`GaussMarkovBank::multirate`]): a component whose correlation time T is at
/// least `1 / HOLD_FRACTION` = 1000 samples is advanced exactly only every `m = floor(HOLD_FRACTION T / dt)`
/// samples, x_{j+m} = phi^m x_j + sigma sqrt(1 - phi^(2m)) w (the same exact discretisation at interval
/// m dt, so its values on the coarse grid are an exact sample of the process) and held in between.
/// Over a hold interval M = m dt <= T / 1000 such a component moves like a random walk of density
/// K^2 = 2 sigma^2 / T (docs/model.md §2); a random walk updated every m samples with m times the step
/// variance has, averaged over the grid's phase (which the overlapping estimator does), exactly the
/// same Allan variance K^2 dt (2n^2 + 1)/(6n) at every tau = n dt as one updated every sample, so
/// the hold changes that component's Allan variance only at relative order M/T <= 1e-3
/// (computed exactly in `tests/held_gauss_markov.rs`: at most 5.0e-4 relative, about M/(2T), at
/// every tau); its k-fold integrals change at most at relative order M/T (the held value lags the
/// process by less than M; not computed exactly, the montecarlo crate's law tests cover flicker
/// alone). It saves the draws of the slow components:
/// the default flicker band 0.1 s .. 1e5 s at 100 Hz needs 3.1 instead of 7 normals per sample.
/// The draws remain a pure function of the sample index, so results do not depend on scheduling.
#[derive(Clone, Debug)]
pub struct GaussMarkovBank {
    /// Components advanced every sample.
    phi: Vec<f64>,
    drive: Vec<f64>,
    state: Vec<f64>,
    /// Components advanced every `every` samples and held in between.
    held: Vec<HeldComponent>,
    /// Sum of the held components' states (changes only when one of them is updated).
    held_sum: f64,
    /// Samples between the last and the next update of any held component, and samples left until it.
    event_span: u32,
    until_event: u32,
    /// Subtracted from every value: 0 by default (bit-identical output), the value at t = 0 after
    /// [`GaussMarkovBank::reference_to_start`].
    offset: f64,
    /// (correlation time s, stationary std, initial state) of each component, in component order:
    /// what [`GaussMarkovBank::reference_to_window_mean`] conditions on.
    start: Vec<(f64, f64, f64)>,
}

#[derive(Clone, Copy, Debug)]
struct HeldComponent {
    /// phi^m and sigma sqrt(1 - phi^(2m)) for the hold of m = `every` samples.
    phi: f64,
    drive: f64,
    state: f64,
    every: u32,
    /// Samples left before the next update.
    left: u32,
}

/// Largest hold interval of a [`GaussMarkovBank::multirate`] component, as a fraction of its
/// correlation time.
pub const HOLD_FRACTION: f64 = 1e-3;

impl GaussMarkovBank {
    /// `components`: (correlation time s, stationary std); the initial state is drawn from `rng`.
    /// Every component is advanced every sample.
    pub fn new<R: Rng + ?Sized>(components: &[(f64, f64)], dt_s: f64, rng: &mut R) -> Self {
        Self::with_holds(components, dt_s, rng, |_| 1)
    }

    /// As [`GaussMarkovBank::new`], but a component of correlation time T >= 1000 dt is updated
    /// exactly every m = floor(T / (1000 dt)) samples and held in between (see the type's docs).
    pub fn multirate<R: Rng + ?Sized>(components: &[(f64, f64)], dt_s: f64, rng: &mut R) -> Self {
        Self::with_holds(components, dt_s, rng, |tc| {
            (HOLD_FRACTION * tc / dt_s)
                .floor()
                .clamp(1.0, f64::from(u32::MAX)) as u32
        })
    }

    /// The hold of each component from its correlation time; initial states drawn in component order.
    fn with_holds<R: Rng + ?Sized>(
        components: &[(f64, f64)],
        dt_s: f64,
        rng: &mut R,
        hold: impl Fn(f64) -> u32,
    ) -> Self {
        let mut bank = GaussMarkovBank {
            phi: Vec::new(),
            drive: Vec::new(),
            state: Vec::new(),
            held: Vec::new(),
            held_sum: 0.0,
            event_span: u32::MAX,
            until_event: u32::MAX,
            offset: 0.0,
            start: Vec::with_capacity(components.len()),
        };
        for &(tc, s) in components {
            let x0 = s * normal(rng);
            bank.start.push((tc, s, x0));
            let every = hold(tc);
            let step = f64::from(every) * dt_s;
            let phi = (-step / tc).exp();
            // sigma sqrt(1 - phi^2) = sigma sqrt(-expm1(-2 step/T)), accurate for T >> step.
            let drive = s * (-(-2.0 * step / tc).exp_m1()).sqrt();
            if every == 1 {
                bank.phi.push(phi);
                bank.drive.push(drive);
                bank.state.push(x0);
            } else {
                bank.held.push(HeldComponent {
                    phi,
                    drive,
                    state: x0,
                    every,
                    left: every,
                });
            }
        }
        bank.sync_held(0);
        bank
    }

    /// Count down `span` samples on every held component (the next event: one of them reaches 0),
    /// update the ones that are due (in component order, each with one value of `draw`), and
    /// recompute the held sum and the next event.
    #[inline]
    fn sync_held(&mut self, span: u32) {
        self.sync_held_with(span, || {
            unreachable!("no held component is due at construction")
        });
    }

    #[inline]
    fn sync_held_with(&mut self, span: u32, mut draw: impl FnMut() -> f64) {
        let mut sum = 0.0;
        let mut next = u32::MAX;
        for h in &mut self.held {
            h.left -= span;
            if h.left == 0 {
                h.left = h.every;
                h.state = h.phi * h.state + h.drive * draw();
            }
            sum += h.state;
            next = next.min(h.left);
        }
        self.held_sum = sum;
        self.event_span = next;
        self.until_event = next;
    }

    /// One sample: the current value (every-sample components in order, then the held sum), then
    /// advance, with the sample's draws from `draw` in order: the every-sample components, then the
    /// held ones that are due, each in component order.
    #[inline(always)]
    fn step(&mut self, mut draw: impl FnMut() -> f64) -> f64 {
        let mut sum = 0.0;
        for ((x, &phi), &d) in self.state.iter_mut().zip(&self.phi).zip(&self.drive) {
            sum += *x;
            *x = phi * *x + d * draw();
        }
        sum += self.held_sum;
        // x - 0.0 == x bit for bit: the default (offset 0) output is unchanged.
        sum -= self.offset;
        if !self.held.is_empty() {
            self.until_event -= 1;
            if self.until_event == 0 {
                self.sync_held_with(self.event_span, draw);
            }
        }
        sum
    }

    /// Reference the process to its value at t = 0: from now on every value is b(t) - b(0), as seen
    /// by a user who estimates the bias perfectly at turn-on and subtracts it (Woodman TR-696
    /// §3.2.1). Call before the first sample (it takes the current value as b(0)); the draws do
    /// not change.
    pub fn reference_to_start(&mut self) {
        // The value `step` returns next, summed in the same order, so the first value is exactly 0.
        let mut sum = 0.0;
        for &x in &self.state {
            sum += x;
        }
        sum += self.held_sum;
        self.offset = sum;
    }

    /// Reference the process to its mean over a calibration window of length `window_s` before
    /// t = 0: from now on every value is b(t) - m, m = (1/W) int_{-W}^0 b(s) ds, as seen by a user
    /// who averages the static output for W seconds before the run and subtracts that estimate.
    /// Each component's window mean is drawn exactly given its value at t = 0 (the window is not
    /// simulated): m_i | b_i(0) ~ N(rho b_i(0), sigma_i^2 c), with (rho, c) from
    /// [`crate::closed_form::gauss_markov_window_mean_moments`] (the conditional Gaussian, \[derived\]
    /// there). One standard normal per component from `rng`, in component order: pass a stream
    /// other than the process's own, so the process's draws (and so b(t)) are unchanged.
    /// Call before the first sample.
    pub fn reference_to_window_mean<R: Rng + ?Sized>(&mut self, window_s: f64, rng: &mut R) {
        let mut m = 0.0;
        for &(tc, s, x0) in &self.start {
            let (rho, _, cond) = crate::closed_form::gauss_markov_window_mean_moments(tc, window_s);
            m += rho * x0 + s * cond.max(0.0).sqrt() * normal(rng);
        }
        self.offset = m;
    }

    /// The current value (sum of the components), then advance one step. Draw order within a step:
    /// the every-sample components, then the held ones that are due, each in component order.
    #[inline]
    pub fn next<R: Rng + ?Sized>(&mut self, rng: &mut R) -> f64 {
        self.step(|| normal(rng))
    }

    /// Add the next `out.len()` values to `out`: the values of as many `next` calls, from the same
    /// draws in the same order (the block's draws are made first, then consumed in that order).
    fn add_block(&mut self, rng: &mut ImuRng, out: &mut [f64], scratch: &mut Vec<f64>) {
        let n = out.len();
        // Held updates within the block: component h is next due in left - (span - until) samples.
        let elapsed = self.event_span - self.until_event;
        let held_draws: usize = self
            .held
            .iter()
            .map(|h| {
                let (left, every) = ((h.left - elapsed) as usize, h.every as usize);
                if n >= left {
                    1 + (n - left) / every
                } else {
                    0
                }
            })
            .sum();
        let w = draws(rng, scratch, n * self.state.len() + held_draws);
        let mut j = 0;
        for v in out.iter_mut() {
            *v += self.step(|| {
                j += 1;
                w[j - 1]
            });
        }
        debug_assert_eq!(j, w.len());
    }
}

/// A resonance (second-order Gauss-Markov: x'' + 2 zeta w0 x' + w0^2 x = w), exactly discretised: the
/// state (x, x') advances by Phi = e^{A dt}, A = [[0, 1], [-w0^2, -2 zeta w0]], plus a normal draw of
/// covariance Q = P - Phi P Phi^T, P = diag(sigma^2, w0^2 sigma^2) the stationary covariance (Lyapunov:
/// A P + P A^T + diag(0, 4 zeta w0^3 sigma^2) = 0), applied through its Cholesky factor; started from
/// P. For the underdamped case, with a = zeta w0, wd = w0 sqrt(1 - zeta^2), c = cos wd dt, s = sin wd dt:
/// Phi = e^{-a dt} [[c + (a/wd) s, s/wd], [-(w0^2/wd) s, c - (a/wd) s]] (van Loan 1978 for the
/// discretisation; Maybeck vol. 1 §4.9 for the process). The output is x, point-sampled.
#[derive(Clone, Copy, Debug)]
pub struct Resonator {
    phi: [[f64; 2]; 2],
    /// Lower Cholesky factor of Q: (l11, l21, l22).
    chol: (f64, f64, f64),
    state: [f64; 2],
}

impl Resonator {
    pub fn new<R: Rng + ?Sized>(
        r: &crate::terms::resonance::Resonance,
        dt_s: f64,
        rng: &mut R,
    ) -> Resonator {
        let w0 = std::f64::consts::TAU * r.frequency_hz;
        let zeta = r.damping();
        let a = zeta * w0;
        let wd = w0 * (1.0 - zeta * zeta).sqrt();
        let (s, c) = (wd * dt_s).sin_cos();
        let e = (-a * dt_s).exp();
        let phi = [
            [e * (c + a / wd * s), e * s / wd],
            [-e * w0 * w0 / wd * s, e * (c - a / wd * s)],
        ];
        let p = [r.sigma * r.sigma, w0 * w0 * r.sigma * r.sigma];
        // Q = P - Phi P Phi^T.
        let q11 = p[0] - (phi[0][0] * phi[0][0] * p[0] + phi[0][1] * phi[0][1] * p[1]);
        let q21 = -(phi[1][0] * phi[0][0] * p[0] + phi[1][1] * phi[0][1] * p[1]);
        let q22 = p[1] - (phi[1][0] * phi[1][0] * p[0] + phi[1][1] * phi[1][1] * p[1]);
        let l11 = q11.max(0.0).sqrt();
        let l21 = if l11 > 0.0 { q21 / l11 } else { 0.0 };
        let l22 = (q22 - l21 * l21).max(0.0).sqrt();
        let state = [p[0].sqrt() * normal(rng), p[1].sqrt() * normal(rng)];
        Resonator {
            phi,
            chol: (l11, l21, l22),
            state,
        }
    }

    /// Add the next `out.len()` values (two normals per sample, in sample order).
    fn add_block(&mut self, rng: &mut ImuRng, out: &mut [f64], scratch: &mut Vec<f64>) {
        let n = out.len();
        let w = draws(rng, scratch, 2 * n);
        let (l11, l21, l22) = self.chol;
        let [x, v] = &mut self.state;
        for (o, d) in out.iter_mut().zip(w.chunks_exact(2)) {
            *o += *x;
            let nx = self.phi[0][0] * *x + self.phi[0][1] * *v + l11 * d[0];
            let nv = self.phi[1][0] * *x + self.phi[1][1] * *v + l21 * d[0] + l22 * d[1];
            *x = nx;
            *v = nv;
        }
    }
}

/// Random walk b_{k+1} = b_k + K sqrt(dt) w_k from b_0 = 0 (docs/model.md §3, Kalibr: sigma_bd = sigma_b sqrt(dt)).
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
    /// Add the next `out.len()` values to `out` (the values of as many `next` calls).
    fn add_block(&mut self, rng: &mut ImuRng, out: &mut [f64], scratch: &mut Vec<f64>) {
        let n = out.len();
        for (v, w) in out.iter_mut().zip(draws(rng, scratch, n)) {
            *v += self.state;
            self.state += self.step * w;
        }
    }
}

/// Quantisation of the integrated output (docs/cli.md: so its Allan signature is the tau^-1 slope):
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

/// Samples per sub-block of `ChannelErrors::fill_static` (any value gives the same values).
const FILL_CHUNK: usize = 512;
/// Raw (internal-rate) samples per sub-block behind an output filter, at least one output sample's
/// worth (any value gives the same values; bounds the memory a large decimation needs).
const RAW_CHUNK: usize = 4096;

/// The error generator of one output channel (one axis of one triad) for one run.
#[derive(Clone, Debug)]
pub struct ChannelErrors {
    dt_s: f64,
    /// Row of (I + scale factor + misalignment) applied to the ideal triad input.
    row: [f64; 3],
    /// Constant bias plus this run's turn-on bias draw.
    bias: f64,
    white: Option<(WhiteNoiseSampler, ImuRng)>,
    flicker: Option<(GaussMarkovBank, ImuRng)>,
    bias_random_walk: Option<(RandomWalk, ImuRng)>,
    rate_random_walk: Option<(RandomWalk, ImuRng)>,
    ramp: f64,
    gauss_markov: Option<(GaussMarkovBank, ImuRng)>,
    resonance: Option<(Resonator, ImuRng)>,
    /// amplitude, angular frequency (rad/s), phase (rad)
    sinusoid: Option<(f64, f64, f64)>,
    /// The sinusoid after the output filter, added at the output rate: a linear filter turns
    /// A sin(w t + p) into A |H| sin(w t + p + arg H), H = sum_j h_j e^{-i w j dt_i} (exact once the
    /// pre-roll has filled the filter), so it is not generated at the internal rate.
    sinusoid_out: Option<(f64, f64, f64)>,
    /// coefficient per degC, profile, reference degC
    temperature: Option<(f64, TemperatureProfile, f64)>,
    quantizer: Option<Quantizer>,
    /// Warm-up transient: this run's amplitude and the time constant, s.
    transient: Option<(f64, f64)>,
    /// Interval of the raw error processes: the output interval, or the output filter's internal one.
    dt_raw: f64,
    /// The output filter's state (None: the raw samples are the output).
    filter: Option<FilterState>,
    outliers: Option<OutlierState>,
    /// A block's normal draws (reused; its contents never outlive a call).
    scratch: Vec<f64>,
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
        // The raw processes run at the filter's internal interval.
        let dt_out = dt_s;
        let output_filter = axis.get::<OutputFilter>().copied();
        let filter = output_filter.map(|f| FilterState::new(&f, dt_out));
        let dt_s = output_filter.map_or(dt_s, |f| f.internal_dt(dt_out));

        let mut row = [0.0; 3];
        row[axis_index] = 1.0 + axis.get::<ScaleFactor>().map_or(0.0, ScaleFactor::ratio);
        if let Some(m) = axis.get::<Misalignment>().map(Misalignment::angles_rad) {
            let others: Vec<usize> = (0..3).filter(|&j| j != axis_index).collect();
            row[others[0]] = m[0];
            row[others[1]] = m[1];
        }
        let turn_on = axis
            .get::<TurnOnBias>()
            .map(TurnOnBias::sigma)
            .map_or(0.0, |s| s * normal(&mut rng(Effect::TurnOnBias)));
        // Each process with its own sub-stream; initial states come from that stream first.
        let bank = |components: &[(f64, f64)], effect: Effect| {
            let mut r = rng(effect);
            (GaussMarkovBank::multirate(components, dt_s, &mut r), r)
        };
        let (flicker, bias_random_walk) = match axis.get::<BiasInstability>() {
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
        let sinusoid = axis.get::<Sinusoid>().map(|s| {
            let phase = s
                .phase_rad
                .unwrap_or_else(|| rng(Effect::Sinusoidal).gen_range(0.0..std::f64::consts::TAU));
            (s.amplitude, std::f64::consts::TAU * s.frequency_hz, phase)
        });
        let transient = axis.get::<WarmupTransient>().map(|w| {
            let a = if w.per_run {
                w.amplitude * normal(&mut rng(Effect::WarmupTransient))
            } else {
                w.amplitude
            };
            (a, w.tau_s)
        });
        let outliers = axis
            .get::<Outliers>()
            .map(|o| OutlierState::new(o.probability(dt_out), o.size, rng(Effect::Outliers)));
        ChannelErrors {
            dt_s: dt_out,
            dt_raw: dt_s,
            transient,
            filter,
            outliers,
            row,
            bias: axis.get::<ConstantBias>().map_or(0.0, ConstantBias::bias) + turn_on,
            white: axis
                .get::<WhiteNoiseTerm>()
                .map(WhiteNoiseTerm::density)
                .map(|n| (WhiteNoiseSampler::new(n, dt_s), rng(Effect::WhiteNoise))),
            flicker,
            bias_random_walk,
            rate_random_walk: axis
                .get::<RateRandomWalk>()
                .map(RateRandomWalk::density)
                .map(|k| (RandomWalk::new(k, dt_s), rng(Effect::RateRandomWalk))),
            ramp: axis.get::<RateRamp>().map_or(0.0, RateRamp::rate),
            gauss_markov: axis
                .get::<GaussMarkov>()
                .map(|g| bank(&[(g.tau_s, g.sigma)], Effect::GaussMarkov)),
            resonance: axis.get::<Resonance>().map(|r| {
                let mut g = rng(Effect::Resonance);
                (Resonator::new(r, dt_s, &mut g), g)
            }),
            sinusoid: sinusoid.filter(|_| output_filter.is_none()),
            sinusoid_out: sinusoid.and_then(|(a, w, p)| {
                let f = output_filter?;
                let (mut re, mut im) = (0.0, 0.0);
                for (j, h) in f.impulse_response(dt_out).iter().enumerate() {
                    let arg = w * j as f64 * dt_s;
                    re += h * arg.cos();
                    im -= h * arg.sin();
                }
                Some((a * re.hypot(im), w, p + im.atan2(re)))
            }),
            temperature: axis
                .get::<TemperatureBias>()
                .map(TemperatureBias::per_degree)
                .map(|c| (c, model.temperature.clone(), model.temperature_reference_c)),
            quantizer: axis
                .get::<Quantization>()
                .map(Quantization::coefficient)
                .map(|q| Quantizer::new(q, &mut rng(Effect::Quantization))),
            scratch: Vec::new(),
            #[cfg(debug_assertions)]
            next_k: 0,
        }
    }

    /// Reference the slowly varying bias processes (flicker bias instability components and the
    /// Gauss-Markov term) to their values at t = 0 (see [`GaussMarkovBank::reference_to_start`]);
    /// random walks already start at 0, white noise and the other terms are unchanged.
    /// Call before the first sample.
    pub fn calibrate_start(&mut self) {
        for (bank, _) in [&mut self.flicker, &mut self.gauss_markov]
            .into_iter()
            .flatten()
        {
            bank.reference_to_start();
        }
    }

    /// Reference the slowly varying bias processes (flicker components and the Gauss-Markov term)
    /// to their means over a calibration window of `window_s` seconds before t = 0
    /// ([`GaussMarkovBank::reference_to_window_mean`]); each process's window draws come from its
    /// own calibration stream (`calibration_rng`), so its own stream is untouched.
    /// Call before the first sample.
    fn calibrate_window(&mut self, window_s: f64, seed: u64, run: u64, channel: usize) {
        for (bank, effect) in [
            (&mut self.flicker, Effect::BiasInstability),
            (&mut self.gauss_markov, Effect::GaussMarkov),
        ] {
            if let Some((bank, _)) = bank {
                let mut r = calibration_rng(seed, run, channel as u64, effect);
                bank.reference_to_window_mean(window_s, &mut r);
            }
        }
    }

    /// The measured value of sample `k` (t = k·dt) given the ideal triad input. Calls must come with
    /// k = 0, 1, 2, ... in order: the stochastic states advance one step per call.
    #[inline]
    pub fn sample(&mut self, k: u64, ideal: &Vector3<f64>) -> f64 {
        let mut v = 0.0;
        self.fill_with(k, std::slice::from_mut(&mut v), |_| ideal);
        v
    }

    /// Samples `k0 .. k0 + out.len()` for a constant ideal input (a static IMU). The same values,
    /// bit for bit, as `sample` called for each k in turn (one implementation serves both); a block
    /// is faster: each term runs over the whole block in one loop.
    pub fn fill_static(&mut self, k0: u64, ideal: &Vector3<f64>, out: &mut [f64]) {
        // Sub-blocks keep the draws of one sub-block (`scratch`) in L1.
        for (c, chunk) in out.chunks_mut(FILL_CHUNK).enumerate() {
            self.fill_with(k0 + (c * FILL_CHUNK) as u64, chunk, |_| ideal);
        }
    }

    /// Samples `k0 .. k0 + out.len()`, sample `k0 + i` with ideal input `ideal(i)`. Each term adds
    /// its values to the whole block in turn, in the order (and with the arithmetic) of one sample,
    /// and every term draws from its own stream in sample order, so the block length does not
    /// change any value.
    #[inline]
    fn fill_with<'a>(
        &mut self,
        k0: u64,
        out: &mut [f64],
        ideal: impl Fn(usize) -> &'a Vector3<f64>,
    ) {
        #[cfg(debug_assertions)]
        {
            assert_eq!(k0, self.next_k, "samples must be drawn in order");
            self.next_k = k0 + out.len() as u64;
        }
        match self.filter.take() {
            None => self.fill_raw(k0, 0, out, ideal),
            Some(mut f) => {
                // Output sub-blocks of about RAW_CHUNK raw samples (the filter's state carries
                // over, so the split changes no value).
                let per = (RAW_CHUNK / f.decimation).max(1);
                for (c, sub) in out.chunks_mut(per).enumerate() {
                    let first = c * per;
                    self.fill_filtered(&mut f, k0 + first as u64, sub, |i| ideal(first + i));
                }
                self.filter = Some(f);
                if let Some((a, omega, phase)) = self.sinusoid_out {
                    let dt = self.dt_s;
                    out.iter_mut().enumerate().for_each(|(i, v)| {
                        *v += a * (omega * (k0 + i as u64) as f64 * dt + phase).sin()
                    });
                }
            }
        }
        if let Some(o) = &mut self.outliers {
            o.add(k0, out);
        }
        if let Some(q) = &mut self.quantizer {
            let dt_s = self.dt_s;
            out.iter_mut().for_each(|v| *v = q.apply(*v, dt_s));
        }
    }

    /// Output samples `k0 .. k0 + out.len()` through the output filter `f`: the raw samples up to
    /// the one output k0 + n - 1 is read at, each with the ideal input of the output sample it
    /// belongs to (zero-order hold; the pre-roll takes output 0's), then filtered and read out.
    fn fill_filtered<'a>(
        &mut self,
        f: &mut FilterState,
        k0: u64,
        out: &mut [f64],
        ideal: impl Fn(usize) -> &'a Vector3<f64>,
    ) {
        let n = out.len() as u64;
        let (d, pre) = (f.decimation as u64, f.preroll as u64);
        let end = pre + (k0 + n - 1) * d + 1;
        let start = f.raw_done;
        let mut raw = std::mem::take(&mut f.raw);
        raw.clear();
        raw.resize((end - start) as usize, 0.0);
        self.fill_raw(start, pre, &mut raw, |j| {
            let r = start + j as u64;
            let o = r.saturating_sub(pre).div_ceil(d);
            ideal((o.max(k0) - k0).min(n - 1) as usize)
        });
        f.filter(start, &raw, k0, out);
        f.raw = raw;
    }

    /// Raw samples `k0 .. k0 + out.len()` at the raw interval (time t = (k - preroll) dt_raw), every
    /// term but the filter, the outliers and the quantiser.
    #[inline]
    fn fill_raw<'a>(
        &mut self,
        k0: u64,
        preroll: u64,
        out: &mut [f64],
        ideal: impl Fn(usize) -> &'a Vector3<f64>,
    ) {
        let offset = preroll as f64 * self.dt_raw;
        // x - 0.0 == x bit for bit: without a filter the times are unchanged.
        let t = |i: usize| (k0 + i as u64) as f64 * self.dt_raw - offset;
        for (i, v) in out.iter_mut().enumerate() {
            let x = ideal(i);
            *v = self.row[0] * x.x + self.row[1] * x.y + self.row[2] * x.z + self.bias;
        }
        let scratch = &mut self.scratch;
        if let Some((w, rng)) = &mut self.white {
            w.add_block(rng, out, scratch);
        }
        if let Some((f, rng)) = &mut self.flicker {
            f.add_block(rng, out, scratch);
        }
        if let Some((w, rng)) = &mut self.bias_random_walk {
            w.add_block(rng, out, scratch);
        }
        if let Some((w, rng)) = &mut self.rate_random_walk {
            w.add_block(rng, out, scratch);
        }
        if self.ramp != 0.0 {
            let ramp = self.ramp;
            out.iter_mut()
                .enumerate()
                .for_each(|(i, v)| *v += ramp * t(i));
        }
        if let Some((g, rng)) = &mut self.gauss_markov {
            g.add_block(rng, out, scratch);
        }
        if let Some((r, rng)) = &mut self.resonance {
            r.add_block(rng, out, scratch);
        }
        if let Some((a, omega, phase)) = self.sinusoid {
            out.iter_mut()
                .enumerate()
                .for_each(|(i, v)| *v += a * (omega * t(i) + phase).sin());
        }
        if let Some((c, profile, reference)) = &self.temperature {
            out.iter_mut()
                .enumerate()
                .for_each(|(i, v)| *v += c * (profile.at(t(i)) - reference));
        }
        if let Some((a, tau)) = self.transient {
            out.iter_mut()
                .enumerate()
                .for_each(|(i, v)| *v += a * (-t(i).max(0.0) / tau).exp());
        }
    }
}

/// An IIR recursion: coefficients (b, a) and the input and output histories (newest first).
#[derive(Clone, Debug)]
struct IirState {
    b: Vec<f64>,
    a: Vec<f64>,
    xs: Vec<f64>,
    ys: Vec<f64>,
}

/// The output filter's running state: the raw history it needs and where the raw stream stands.
#[derive(Clone, Debug)]
struct FilterState {
    /// Impulse response (FIR kinds; for the IIR kinds only its length sets the pre-roll).
    h: Vec<f64>,
    /// The IIR kinds' recursion and histories.
    iir: Option<IirState>,
    decimation: usize,
    /// Raw samples before the one output 0 is read at: the response's length - 1, so the filter's
    /// history is full (FIR) or settled to 1e-17 (IIR) at t = 0.
    preroll: usize,
    /// Raw samples produced so far.
    raw_done: u64,
    /// The last `h.len() - 1` raw samples (FIR), oldest first.
    history: Vec<f64>,
    /// Scratch for one block's raw samples.
    raw: Vec<f64>,
}

impl FilterState {
    fn new(f: &crate::terms::output_filter::OutputFilter, dt_s: f64) -> FilterState {
        let h = f.impulse_response(dt_s);
        let iir = f.recursion(dt_s).map(|(b, a)| {
            let (nb, na) = (b.len(), a.len());
            IirState {
                b,
                a,
                xs: vec![0.0; nb],
                ys: vec![0.0; na],
            }
        });
        FilterState {
            preroll: h.len() - 1,
            h,
            iir,
            decimation: f.decimation as usize,
            raw_done: 0,
            history: Vec::new(),
            raw: Vec::new(),
        }
    }

    /// Filter the raw samples `start ..` in `raw`, writing the output samples k0 .. into `out`.
    fn filter(&mut self, start: u64, raw: &[f64], k0: u64, out: &mut [f64]) {
        let (d, pre) = (self.decimation as u64, self.preroll as u64);
        let is_output = |r: u64| r >= pre && (r - pre).is_multiple_of(d);
        let slot = |r: u64| ((r - pre) / d - k0) as usize;
        if let Some(IirState { b, a, xs, ys }) = &mut self.iir {
            for (j, &x) in raw.iter().enumerate() {
                xs.rotate_right(1);
                xs[0] = x;
                let mut y: f64 = b.iter().zip(xs.iter()).map(|(b, x)| b * x).sum();
                for i in 1..a.len() {
                    y -= a[i] * ys[i - 1];
                }
                ys.rotate_right(1);
                ys[0] = y;
                let r = start + j as u64;
                if is_output(r) {
                    out[slot(r)] = y;
                }
            }
        } else {
            // y_r = sum_i h_i x_{r-i}, only at the raw indices that are read out.
            let l = self.h.len();
            let hist = self.history.len();
            let mut joined = std::mem::take(&mut self.history);
            joined.extend_from_slice(raw);
            let first = start.max(pre);
            let mut r = if is_output(first) {
                first
            } else {
                pre + (first - pre).div_ceil(d) * d
            };
            let end = start + raw.len() as u64;
            while r < end {
                // Position of raw sample r in `joined`.
                let p = (r - start) as usize + hist;
                let mut y = 0.0;
                for (i, hi) in self.h.iter().enumerate() {
                    y += hi * joined[p - i];
                }
                out[slot(r)] = y;
                r += d;
            }
            let keep = (l - 1).min(joined.len());
            self.history = joined[joined.len() - keep..].to_vec();
        }
        self.raw_done = start + raw.len() as u64;
    }
}

/// Outliers: the index of the next one and the draws (geometric gaps, random sign).
#[derive(Clone, Debug)]
struct OutlierState {
    p: f64,
    size: f64,
    next: u64,
    rng: ImuRng,
}

impl OutlierState {
    fn new(p: f64, size: f64, mut rng: ImuRng) -> OutlierState {
        let first = Self::gap(p, &mut rng);
        OutlierState {
            p,
            size,
            next: first.saturating_sub(1),
            rng,
        }
    }

    /// Samples to the next outlier (>= 1): geometric with success probability p (a Bernoulli process).
    fn gap(p: f64, rng: &mut ImuRng) -> u64 {
        if p <= 0.0 {
            return u64::MAX;
        }
        if p >= 1.0 {
            return 1;
        }
        let u: f64 = 1.0 - rng.gen::<f64>(); // (0, 1]
        1 + (u.ln() / (-p).ln_1p()).floor().min(1e18) as u64
    }

    fn add(&mut self, k0: u64, out: &mut [f64]) {
        let end = k0 + out.len() as u64;
        while self.next < end {
            let sign = if self.rng.gen::<bool>() { 1.0 } else { -1.0 };
            out[(self.next - k0) as usize] += sign * self.size;
            self.next = self.next.saturating_add(Self::gap(self.p, &mut self.rng));
        }
    }
}

/// A model that cannot run at a sample rate: an axis whose output filter does not fit the rate
/// ([`crate::OutputFilter::check_rate`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{axis}.output_filter at {rate_hz} Hz output, decimation {decimation} ({internal_hz} Hz internal): {error}")]
pub struct RateError {
    /// The axis, e.g. "gyro.x".
    pub axis: String,
    pub rate_hz: f64,
    pub decimation: u32,
    pub internal_hz: f64,
    pub error: crate::model_error::ModelError,
}

/// Per-run error state of a whole IMU: six channels (gx gy gz ax ay az).
#[derive(Clone, Debug)]
pub struct ImuErrors {
    channels: [ChannelErrors; 6],
    temperature: TemperatureProfile,
    dt_s: f64,
}

impl ImuErrors {
    /// Can `model` run at sample interval `dt_s`? Every output filter's cutoff must lie below its
    /// internal Nyquist frequency and its response fit [`crate::MAX_RESPONSE`] internal
    /// samples. Check before [`ImuErrors::new`]: a filter that fails gives meaningless values.
    pub fn check_rate(model: &SensorModel, dt_s: f64) -> Result<(), RateError> {
        for sensor in Sensor::ALL {
            for (axis, name) in model.triad(sensor).axes.iter().zip(crate::AXIS_NAMES) {
                if let Some(f) = axis.get::<OutputFilter>() {
                    f.check_rate(dt_s).map_err(|error| RateError {
                        axis: format!("{}.{name}", sensor.name()),
                        rate_hz: 1.0 / dt_s,
                        decimation: f.decimation,
                        internal_hz: 1.0 / f.internal_dt(dt_s),
                        error,
                    })?;
                }
            }
        }
        Ok(())
    }

    /// Draw run `run`'s per-run values (turn-on bias, initial states, phases) from `seed`.
    /// `dt_s` must be finite and > 0, and the model must pass [`ImuErrors::check_rate`] at it.
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

    /// The same run with the bias perfectly calibrated at turn-on: every channel's flicker and
    /// Gauss-Markov bias processes are referenced to their value at t = 0, so the error they add is
    /// b(t) - b(0) (`ChannelErrors::calibrate_start`). The draws are those of `new`; only the
    /// offsets differ. Call before the first sample.
    pub fn with_calibrated_start(mut self) -> ImuErrors {
        self.channels
            .iter_mut()
            .for_each(ChannelErrors::calibrate_start);
        self
    }

    /// The same run (`seed`, `run` must be those given to `new`) with the bias calibrated by
    /// averaging the static output over a window of `window_s` seconds (finite, > 0) before t = 0:
    /// every channel's flicker and Gauss-Markov bias processes are referenced to their window
    /// mean m, so the error they add is b(t) - m ([`GaussMarkovBank::reference_to_window_mean`]).
    /// The draws of `new` are unchanged; the window means come from separate calibration streams.
    /// Call before the first sample.
    pub fn with_calibration_window(mut self, window_s: f64, seed: u64, run: u64) -> ImuErrors {
        assert!(
            window_s.is_finite() && window_s > 0.0,
            "calibration window must be > 0 s, got {window_s}"
        );
        for (c, ch) in self.channels.iter_mut().enumerate() {
            ch.calibrate_window(window_s, seed, run, c);
        }
        self
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

    /// Samples `k0 .. k0 + n` of a static IMU (constant ideal inputs), channel by channel into
    /// `out[c][..n]` (gx gy gz ax ay az): the same values, bit for bit, as `corrupt` for each k.
    pub fn fill_static(
        &mut self,
        k0: u64,
        ideal_gyro: &Vector3<f64>,
        ideal_accel: &Vector3<f64>,
        out: [&mut [f64]; 6],
    ) {
        for (c, (channel, o)) in self.channels.iter_mut().zip(out).enumerate() {
            channel.fill_static(k0, if c < 3 { ideal_gyro } else { ideal_accel }, o);
        }
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
