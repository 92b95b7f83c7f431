//! A resonance: a narrow-band random vibration (second-order Gauss-Markov process).

use super::term::{
    note_value_units, ErrorTerm, GenContext, Generate, RawClock, Stage, TermKind, WriteContext,
};
use crate::closed_form as cf;
use crate::config::error::ConfigError;
use crate::config::read::{ReadContext, Text};
use crate::discrete::{draws, normal};
use crate::filter::FilteredAllan;
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check, ModelError};
use crate::units::{Quantity, Signal};
use crate::ImuRng;
use crate::NormalStream;
use rand::Rng;

/// A resonance: a narrow-band random vibration, white noise through a damped oscillator (a
/// second-order Gauss-Markov process). Stationary std `sigma`, natural frequency `frequency_hz`,
/// half-power (-3 dB) bandwidth `bandwidth_hz` = 2 zeta f0 of its spectral peak; underdamped
/// (bandwidth below twice the frequency). Closed forms in [`cf::resonance_exponent`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resonance {
    sigma: f64,
    frequency_hz: f64,
    bandwidth_hz: f64,
}

impl Resonance {
    /// Checks sigma (finite, >= 0), the frequency and bandwidth (finite, > 0) and that the
    /// bandwidth is below twice the frequency (underdamped).
    pub fn new(sigma: f64, frequency_hz: f64, bandwidth_hz: f64) -> Result<Resonance, ModelError> {
        check("resonance sigma", sigma, false)?;
        check("resonance frequency", frequency_hz, true)?;
        check("resonance bandwidth", bandwidth_hz, true)?;
        if bandwidth_hz >= 2.0 * frequency_hz {
            return Err(ModelError {
                what: "resonance bandwidth",
                expected: "a bandwidth below twice the frequency (an underdamped resonance)",
                found: bandwidth_hz,
            });
        }
        Ok(Resonance {
            sigma,
            frequency_hz,
            bandwidth_hz,
        })
    }

    /// Stationary standard deviation (signal units).
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// Natural frequency, Hz.
    pub fn frequency_hz(&self) -> f64 {
        self.frequency_hz
    }

    /// Half-power (-3 dB) bandwidth, Hz.
    pub fn bandwidth_hz(&self) -> f64 {
        self.bandwidth_hz
    }

    /// Damping ratio zeta = bandwidth / (2 frequency).
    pub fn damping(&self) -> f64 {
        self.bandwidth_hz / (2.0 * self.frequency_hz)
    }
}

/// `resonance = { sigma, frequency, bandwidth }` as written.
#[derive(serde::Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawResonance {
    sigma: Text,
    frequency: Text,
    bandwidth: Text,
}

impl ErrorTerm for Resonance {
    fn law_sources(&self, _cx: &LawSourceContext) -> Vec<LawSource> {
        vec![LawSource::Resonance {
            sigma: self.sigma,
            frequency_hz: self.frequency_hz,
            bandwidth_hz: self.bandwidth_hz,
        }]
    }

    /// Sigma, named `sigma` (docs/cli.md).
    fn level(&self) -> Option<(&'static str, f64)> {
        Some(("sigma", self.sigma))
    }

    /// The frequency and bandwidth, named `frequency_hz` and `bandwidth_hz`.
    fn shape(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("frequency_hz", self.frequency_hz),
            ("bandwidth_hz", self.bandwidth_hz),
        ]
    }

    /// [`cf::resonance_avar`].
    fn allan_variance(&self, tau_s: f64) -> Option<f64> {
        let (s, f, b) = (self.sigma, self.frequency_hz, self.bandwidth_hz);
        Some(cf::resonance_avar(s, f, b, tau_s))
    }

    fn allan_variance_sampled(&self, tau_s: f64, dt_s: f64) -> Option<f64> {
        let (s, f, b) = (self.sigma, self.frequency_hz, self.bandwidth_hz);
        Some(cf::resonance_avar_sampled(s, f, b, tau_s, dt_s))
    }

    fn allan_variance_filtered(&self, tau_s: f64, _dt_s: f64, fa: &FilteredAllan) -> Option<f64> {
        Some(fa.resonance(self.sigma, self.frequency_hz, self.bandwidth_hz, tau_s))
    }

    fn config_value(&self, cx: &WriteContext) -> String {
        format!(
            "{{ sigma = {}, frequency = {}, bandwidth = {} }}",
            cx.quoted(self.sigma, Quantity::Signal(cx.sig)),
            cx.quoted(self.frequency_hz, Quantity::Frequency),
            cx.quoted(self.bandwidth_hz, Quantity::Frequency)
        )
    }
}

impl TermKind for Resonance {
    const STOCHASTIC: bool = true;
    const LONG_TERM: bool = false;
    const FREE_PARAMETERS: usize = 3;
    const SHOWS_IN_STATIC_LOG: bool = true;
    type Raw = RawResonance;
    const EXAMPLE: Option<&'static str> =
        Some("resonance = { sigma = \"0.5 mg\", frequency = \"10 Hz\", bandwidth = \"0.7 Hz\" }");

    /// The frequency and bandwidth kept.
    fn with_level(&self, level: f64) -> Result<Resonance, ModelError> {
        Resonance::new(level, self.frequency_hz, self.bandwidth_hz)
    }

    /// Stationary std `sigma`, natural `frequency`, half-power `bandwidth` (below twice the
    /// frequency).
    fn from_raw(raw: &RawResonance, cx: &ReadContext) -> Result<Resonance, ConfigError> {
        let sigma = cx.sub_value("sigma", &raw.sigma, Quantity::Signal(cx.sig), true)?;
        let frequency_hz = cx.sub_positive("frequency", &raw.frequency, Quantity::Frequency)?;
        let bw_key = cx.sub("bandwidth");
        let bandwidth_hz = cx
            .ctx
            .positive(&bw_key, &raw.bandwidth, Quantity::Frequency)?;
        Resonance::new(sigma, frequency_hz, bandwidth_hz).map_err(|e| {
            cx.ctx.invalid_at(
                &bw_key,
                Some(&raw.bandwidth),
                e.expected,
                format!(
                    "\"{}\" with frequency \"{}\"",
                    raw.bandwidth.get_ref(),
                    raw.frequency.get_ref()
                ),
            )
        })
    }

    fn note_units(value: &toml::Value, sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value)) {
        note_value_units(value, Quantity::Signal(sig), sig, note);
    }

    type Generator = ResonanceGenerator;

    fn generator(&self, cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> ResonanceGenerator {
        let mut rng = rng();
        ResonanceGenerator {
            resonator: Resonator::new(self, cx.dt_raw_s, &mut rng),
            rng: NormalStream::new(rng),
        }
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
    pub fn new<R: Rng + ?Sized>(r: &Resonance, dt_s: f64, rng: &mut R) -> Resonator {
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

    /// The recursion as the four-run loop runs it (`crate::discrete::fused4`).
    pub(crate) fn lane(&mut self) -> crate::discrete::ResonatorLane<'_> {
        crate::discrete::ResonatorLane {
            phi: self.phi,
            chol: self.chol,
            state: &mut self.state,
        }
    }

    /// Add the next `out.len()` values (two normals per sample, in sample order).
    #[inline]
    fn add_block(&mut self, rng: &mut NormalStream, out: &mut [f64], scratch: &mut Vec<f64>) {
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

/// A resonator's [`Resonator::add_block`] over a block as a follower of the flicker bank
/// ([`crate::discrete::GaussMarkovBank::add_block_then`]): the same operations on each sample;
/// its state is written back by [`ResonatorFollower::finish`].
pub(crate) struct ResonatorFollower<'a> {
    resonator: &'a mut Resonator,
    x: f64,
    v: f64,
    /// Two normals per sample, in sample order.
    draws: &'a [f64],
}

impl ResonatorFollower<'_> {
    /// Keep the resonator's state at the end of the block.
    pub(crate) fn finish(self) {
        self.resonator.state = [self.x, self.v];
    }
}

impl crate::discrete::Follower for ResonatorFollower<'_> {
    #[inline(always)]
    fn add(&mut self, i: usize, o: &mut f64) {
        let (phi, (l11, l21, l22)) = (&self.resonator.phi, self.resonator.chol);
        let (d0, d1) = (self.draws[2 * i], self.draws[2 * i + 1]);
        let (x, v) = (self.x, self.v);
        *o += x;
        self.x = phi[0][0] * x + phi[0][1] * v + l11 * d0;
        self.v = phi[1][0] * x + phi[1][1] * v + l21 * d0 + l22 * d1;
    }
}

impl ResonanceGenerator {
    /// The resonator and its stream.
    pub(crate) fn parts(&mut self) -> (&mut Resonator, &mut NormalStream) {
        (&mut self.resonator, &mut self.rng)
    }
}

impl ResonanceGenerator {
    /// The resonance over the next `n` samples as a follower of the flicker bank, its draws in
    /// `scratch`.
    pub(crate) fn follower<'a>(
        &'a mut self,
        scratch: &'a mut Vec<f64>,
        n: usize,
    ) -> ResonatorFollower<'a> {
        let draws = draws(&mut self.rng, scratch, 2 * n);
        let [x, v] = self.resonator.state;
        ResonatorFollower {
            resonator: &mut self.resonator,
            x,
            v,
            draws,
        }
    }
}

/// A resonance with its stream.
#[derive(Clone, Debug)]
pub struct ResonanceGenerator {
    resonator: Resonator,
    rng: NormalStream,
}

impl Generate for ResonanceGenerator {
    fn stage(&self) -> Stage {
        Stage::Raw
    }

    #[inline]
    fn add_raw(&mut self, _clock: RawClock, out: &mut [f64], scratch: &mut Vec<f64>) {
        self.resonator.add_block(&mut self.rng, out, scratch);
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> Resonance {
    Resonance::new(7e-4, 20.0, 0.7).unwrap()
}

#[cfg(test)]
mod fused_tests {
    use super::*;
    use crate::discrete::{draws, GaussMarkovBank, RandomWalk, WalkFollower};
    use rand::SeedableRng;

    /// The flicker bank, a random walk and a resonance in one pass give the bits of the three
    /// passes one after the other (bank with 3 and with 6 every-sample components: the one-pass
    /// loop and the stepwise fallback), in blocks of mixed lengths.
    #[test]
    fn bank_walk_and_resonance_in_one_pass_equal_three_passes() {
        let r = Resonance::new(8e-3, 11.36, 0.18).unwrap();
        for every in [3usize, 6] {
            let comps: Vec<(f64, f64)> = (0..every)
                .map(|c| (0.05 * (c + 1) as f64, 1e-3))
                .chain([(10.0, 2e-4), (1000.0, 3e-4)])
                .collect();
            let dt = 0.01;
            let mut seed = crate::ImuRng::seed_from_u64(8);
            let mut bank_a = GaussMarkovBank::multirate(&comps, dt, &mut seed);
            let mut res_a = ResonanceGenerator {
                resonator: Resonator::new(&r, dt, &mut seed),
                rng: NormalStream::new(crate::ImuRng::seed_from_u64(5)),
            };
            let (mut bank_b, mut res_b) = (bank_a.clone(), res_a.clone());
            let (mut walk_a, mut walk_b) = (RandomWalk::new(5e-5, dt), RandomWalk::new(5e-5, dt));
            let mut streams = [1u64, 2].map(|s| NormalStream::new(crate::ImuRng::seed_from_u64(s)));
            let [bank_rng_a, walk_rng_a] = &mut streams;
            let (mut bank_rng_b, mut walk_rng_b) = (bank_rng_a.clone(), walk_rng_a.clone());
            let n = 20_000;
            let (mut a, mut b) = (vec![0.125; n], vec![0.125; n]);
            let mut s = [(); 4].map(|_| Vec::new());
            let mut k = 0;
            for len in [512usize, 1, 2048, 7, 333].iter().cycle() {
                if k >= n {
                    break;
                }
                let end = (k + len).min(n);
                let [s0, s1, s2, s3] = &mut s;
                let walk = WalkFollower::new(&mut walk_a, draws(walk_rng_a, s1, end - k));
                let mut f = (walk, res_a.follower(s2, end - k));
                bank_a.add_block_then(bank_rng_a, &mut a[k..end], s0, &mut f);
                f.0.finish();
                f.1.finish();
                bank_b.add_block(&mut bank_rng_b, &mut b[k..end], s3);
                walk_b.add_block(&mut walk_rng_b, &mut b[k..end], s3);
                res_b.add_raw(
                    RawClock {
                        k0: k as u64,
                        dt_s: dt,
                        offset_s: 0.0,
                    },
                    &mut b[k..end],
                    s3,
                );
                k = end;
            }
            assert!(
                a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
                "{every} every-sample components"
            );
        }
    }
}
